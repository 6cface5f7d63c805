/* Vertices of one object against the triangles of another cloth: a cloth falling on another
 * stays on top even when their vertices do not line up, and particles rest on a cloth. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"

static plait_object_id add_sheet(plait_world_id world, int n, float size, float height, float shift)
{
	test_grid grid = test_grid_make(n, n, size, size);
	for (int i = 0; i < grid.vertex_count; ++i) {
		grid.positions[i].x += shift;
		grid.positions[i].z += shift;
		grid.positions[i].y = height;
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.surface.thickness = 0.005f;
	def.surface.friction = 0.3f;
	plait_error error;
	plait_object_id id = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(id), "%s", error.message);
	test_grid_free(&grid);
	return id;
}

Test(surface_contact, a_cloth_falling_on_another_stays_on_top)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	wdef.cloth_contacts = true;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def ground = plait_default_collider_def();
	plait_create_collider(world, &ground, NULL);
	/* Coarse sheets whose vertices fall between each other's: vertex-vertex contact alone
	 * would let them pass through. */
	plait_object_id lower = add_sheet(world, 8, 1.0f, 0.02f, 0.0f);
	plait_object_id upper = add_sheet(world, 8, 0.8f, 0.6f, 0.05f);
	int n_upper = plait_object_get_vertex_count(upper);
	plait_vec3 *x = malloc(sizeof *x * (size_t)n_upper);
	for (int frame = 0; frame < 48; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_intersection_report report;
		cr_assert_eq(plait_world_check_intersections(world, &report, NULL), PLAIT_OK);
		cr_assert_eq(report.triangle_pairs, 0, "frame %d: %d crossing triangle pairs", frame,
		             report.triangle_pairs);
	}
	plait_object_get_positions(upper, 0, n_upper, x, NULL);
	/* The lower sheet lies on the ground at its thickness (0.005 m); the upper one on it, a
	 * further two thicknesses up. */
	for (int v = 0; v < n_upper; ++v) {
		cr_assert_geq(x[v].y, 0.005f + 0.01f - 2e-3f,
		              "upper vertex %d at y = %g went through the lower sheet", v, (double)x[v].y);
	}
	free(x);
	(void)lower;
	plait_destroy_world(world);
}

Test(surface_contact, particles_rest_on_a_cloth_lying_on_the_ground)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	wdef.cloth_contacts = true;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def ground = plait_default_collider_def();
	plait_create_collider(world, &ground, NULL);
	add_sheet(world, 4, 1.0f, 0.005f, 0.0f);
	plait_vec3 x[3] = {{0.1f, 0.5f, 0.1f}, {-0.15f, 0.8f, 0.05f}, {0.0f, 1.2f, -0.2f}};
	plait_particles_def def = plait_default_particles_def();
	def.positions = x;
	def.count = 3;
	def.radius = 0.01f;
	def.mass = 0.05f;
	plait_object_id dots = plait_create_particles(world, &def, NULL);
	cr_assert(test_step_frames(world, 48));
	plait_object_get_positions(dots, 0, 3, x, NULL);
	for (int k = 0; k < 3; ++k) {
		/* On the cloth: its thickness plus the particle's radius above the sheet at 0.005 m. */
		cr_assert_geq(x[k].y, 0.005f + 0.005f + 0.01f - 2e-3f, "particle %d at y = %g is below the cloth", k,
		              (double)x[k].y);
	}
	plait_destroy_world(world);
}

Test(surface_contact, destroying_a_cloth_keeps_the_other_surfaces_working)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	wdef.cloth_contacts = true;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def ground = plait_default_collider_def();
	plait_create_collider(world, &ground, NULL);
	plait_object_id first = add_sheet(world, 4, 1.0f, 0.3f, 0.0f);
	add_sheet(world, 8, 1.0f, 0.005f, 0.0f);
	plait_vec3 x = {0.05f, 0.6f, 0.05f};
	plait_particles_def def = plait_default_particles_def();
	def.positions = &x;
	def.count = 1;
	def.radius = 0.01f;
	plait_object_id dot = plait_create_particles(world, &def, NULL);
	cr_assert(test_step_frames(world, 2));
	plait_destroy_object(first);
	cr_assert(test_step_frames(world, 46));
	plait_object_get_positions(dot, 0, 1, &x, NULL);
	cr_assert_geq(x.y, 0.005f + 0.005f + 0.01f - 2e-3f, "particle at y = %g fell through the remaining cloth",
	              (double)x.y);
	plait_destroy_world(world);
}

/* A sheet folded over itself: a lower layer at 2 cm, a crease, and an upper layer at 8 cm
 * going back over it. Falling onto the ground, the upper layer must stay above the lower one:
 * that is the cloth colliding with itself. */
static double folded_sheet_gap(bool self_collide)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def ground = plait_default_collider_def();
	plait_create_collider(world, &ground, NULL);
	int nx = 6, rows = 6; /* quads per row; rows per layer */
	int columns = nx + 1, row_count = 2 * rows + 2;
	plait_vec3 *x = malloc(sizeof *x * (size_t)(columns * row_count));
	for (int r = 0; r < row_count; ++r) {
		bool upper = r > rows;
		int k = upper ? row_count - 1 - r : r; /* the upper layer runs back over the lower */
		float z = 0.5f * (float)k / (float)rows;
		for (int c = 0; c < columns; ++c) {
			x[r * columns + c] =
			    (plait_vec3){0.5f * (float)c / (float)nx, upper ? 0.08f : 0.02f, upper ? z - 0.04f : z};
		}
	}
	int face_count = nx * (row_count - 1);
	int *sizes = malloc(sizeof(int) * (size_t)face_count),
	    *indices = malloc(sizeof(int) * 4 * (size_t)face_count);
	for (int f = 0, r = 0; r + 1 < row_count; ++r) {
		for (int c = 0; c < nx; ++c, ++f) {
			int a = r * columns + c;
			sizes[f] = 4;
			int quad[4] = {a, a + columns, a + columns + 1, a + 1};
			memcpy(indices + 4 * f, quad, sizeof quad);
		}
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = (plait_mesh_def){x, columns * row_count, sizes, face_count, indices};
	def.surface.thickness = 0.004f;
	def.self_collide = self_collide;
	plait_error error;
	plait_object_id cloth = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(cloth), "%s", error.message);
	/* Vertex-face contacts only: where the crease folds, edges can still cross edges (edge-edge
	 * contacts are the next step), so crossings are not asserted here, only the layers. */
	cr_assert(test_step_frames(world, 36));
	plait_object_get_positions(cloth, 0, columns * row_count, x, NULL);
	/* The smallest height of an upper-layer vertex above the lower layer's middle vertices. */
	double gap = INFINITY;
	for (int r = rows + 3; r < row_count - 1; ++r) {
		for (int c = 1; c < nx; ++c) {
			gap = fmin(gap, (double)x[r * columns + c].y - (double)x[2 * columns + c].y);
		}
	}
	plait_destroy_world(world);
	free(x);
	free(sizes);
	free(indices);
	return gap;
}

Test(surface_contact, a_cloth_folded_over_itself_keeps_its_layers_apart)
{
	double without = folded_sheet_gap(false), with = folded_sheet_gap(true);
	cr_log_info("upper layer above the lower one: %.4f m without self-collision, %.4f m with", without, with);
	cr_assert_lt(without, 0.004, "without self-collision the layers should meet or pass (%g)", without);
	cr_assert_geq(with, 0.008 - 0.002, "with self-collision the layers sit two thicknesses apart (%g)", with);
}
