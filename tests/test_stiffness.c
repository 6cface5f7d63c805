/* The material does not change with the solver settings (XPBD compliance, seed 000 §2.4):
 * a hanging sheet's steady-state strain is the same, within 20%, at 3 and 12 substeps and at
 * 32x32 and 64x64 quads, once the solve has converged. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "test_support.h"

/* A 1 m x 1 m sheet hanging in the XY plane from its whole top row; returns the mean strain of
 * its vertical edges after 3 s. Stretch and compression resistance 0.2 give a soft membrane
 * (k = 20 N/m) that stretches about 5% under its own weight; 600 stretch iterations per frame
 * converge it. Shear is off: its iterations follow its own resistance, and this test is about
 * the stretch material. */
static double hanging_strain(int n, int substeps)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.substeps = substeps;
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	int vertex_count = (n + 1) * (n + 1);
	plait_vec3 *x = malloc(sizeof *x * (size_t)vertex_count);
	int *sizes = malloc(sizeof(int) * (size_t)(n * n)), *indices = malloc(sizeof(int) * 4 * (size_t)(n * n));
	int *pins = malloc(sizeof(int) * (size_t)(n + 1));
	for (int j = 0; j <= n; ++j) {
		for (int i = 0; i <= n; ++i) {
			x[j * (n + 1) + i] = (plait_vec3){-0.5f + (float)i / (float)n, -(float)j / (float)n, 0.0f};
		}
	}
	for (int f = 0, j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i, ++f) {
			int a = j * (n + 1) + i;
			sizes[f] = 4;
			int *q = indices + 4 * f;
			q[0] = a;
			q[1] = a + 1;
			q[2] = a + n + 2;
			q[3] = a + n + 1;
		}
	}
	for (int i = 0; i <= n; ++i) {
		pins[i] = i;
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = (plait_mesh_def){x, vertex_count, sizes, n * n, indices};
	def.density = 0.2f;
	def.stretch_resistance = 0.2f;
	def.compression_resistance = 0.2f;
	def.shear_resistance = 0.0f;
	def.iterations = 600;
	def.damp = 1.0f;
	def.pins = pins;
	def.pin_count = n + 1;
	plait_error error;
	plait_object_id cloth = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(cloth), "%s", error.message);
	cr_assert(test_step_frames(world, 72));
	plait_object_get_positions(cloth, 0, vertex_count, x, NULL);
	double sum = 0.0;
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i <= n; ++i) {
			int a = j * (n + 1) + i, b = a + n + 1;
			double dx = x[b].x - x[a].x, dy = x[b].y - x[a].y, dz = x[b].z - x[a].z;
			sum += sqrt(dx * dx + dy * dy + dz * dz) * n - 1.0;
		}
	}
	plait_destroy_world(world);
	free(x);
	free(sizes);
	free(indices);
	free(pins);
	return sum / (n * (n + 1));
}

static void assert_close(double a, double b, const char *what)
{
	double relative = fabs(a - b) / fmax(fabs(a), fabs(b));
	cr_assert_lt(relative, 0.20, "%s: strain %g vs %g (%.1f%% apart)", what, a, b, 100.0 * relative);
}

Test(stiffness, strain_does_not_depend_on_substeps_or_resolution, .timeout = 600)
{
	double coarse3 = hanging_strain(32, 3), coarse12 = hanging_strain(32, 12);
	double fine3 = hanging_strain(64, 3), fine12 = hanging_strain(64, 12);
	cr_log_info("mean strain: 32x32 %.4f (3 substeps) %.4f (12); 64x64 %.4f (3) %.4f (12)", coarse3, coarse12,
	            fine3, fine12);
	/* The converged material stretches as the membrane model says: tension at height y is
	 * rho g y, so the mean strain of a sheet of height L is rho g L / (2 k). */
	double analytic = 0.2 * 9.81 * 1.0 / (2.0 * 20.0);
	cr_assert_lt(fabs(coarse12 - analytic) / analytic, 0.20, "strain %g, membrane model %g", coarse12,
	             analytic);
	cr_assert_lt(fabs(fine12 - analytic) / analytic, 0.20, "strain %g, membrane model %g", fine12, analytic);
	assert_close(coarse3, coarse12, "32x32, substeps 3 vs 12");
	assert_close(fine3, fine12, "64x64, substeps 3 vs 12");
	assert_close(coarse3, fine3, "3 substeps, 32x32 vs 64x64");
	assert_close(coarse12, fine12, "12 substeps, 32x32 vs 64x64");
}
