/* Tethers (long-range attachments): no vertex ever gets farther from its anchor than the
 * tether length times scale, and they cut the stretch of a hanging cloth. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "test_support.h"
#include <string.h>

static float v3len(plait_vec3 a, plait_vec3 b)
{
	float dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
	return sqrtf(dx * dx + dy * dy + dz * dz);
}

/* A heavy cloth hanging from its pins (n = 20 quads a side, (n + 1)^2 vertices), solved with
 * few iterations: without tethers it stretches a lot. Returns the largest distance ratio
 * |x_v - x_pin| / rest distance over all frames and every pin certainly among a vertex's four
 * tethered ones (those strictly nearer than its fourth nearest), and the largest stretch of a
 * structural edge at the end. */
/* The distance from vertex v to its fourth nearest pin (infinity with fewer pins). */
static float fourth_nearest(const plait_vec3 *rest, int v, const int *pins, int pin_count)
{
	float nearest[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
	for (int k = 0; k < pin_count; ++k) {
		float d = v3len(rest[v], rest[pins[k]]);
		for (int m = 0; m < 4; ++m) {
			if (d < nearest[m]) {
				float t = nearest[m];
				nearest[m] = d;
				d = t;
			}
		}
	}
	return nearest[3];
}

static void hang_with(const int *pins, int pin_count, plait_tether_mode mode, float scale, float stiffness,
                      double *worst_ratio, double *max_stretch)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	int n = 20;
	test_grid grid = test_grid_make(n, n, 1.0f, 1.0f);
	plait_vec3 *rest = malloc(sizeof *rest * (size_t)grid.vertex_count);
	for (int i = 0; i < grid.vertex_count; ++i) {
		rest[i] = grid.positions[i];
	}
	float *masses = malloc(sizeof(float) * (size_t)grid.vertex_count);
	for (int i = 0; i < grid.vertex_count; ++i) {
		masses[i] = 1.0f;
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.vertex_masses = masses;
	def.stretch_resistance = 10000.0f;
	def.compression_resistance = 10000.0f;
	def.iterations = 5;
	def.pins = pins;
	def.pin_count = pin_count;
	def.tethers = mode;
	def.tether_scale = scale;
	def.tether_stiffness = stiffness;
	plait_error error;
	plait_object_id cloth = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(cloth), "%s", error.message);
	plait_vec3 *x = malloc(sizeof *x * (size_t)grid.vertex_count);
	*worst_ratio = 0.0;
	for (int frame = 0; frame < 72; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_object_get_positions(cloth, 0, grid.vertex_count, x, NULL);
		for (int v = 0; v < grid.vertex_count; ++v) {
			/* The rest distance in a straight line (the Euclidean tether's). */
			float fourth = fourth_nearest(rest, v, pins, pin_count);
			for (int k = 0; k < pin_count; ++k) {
				float d = v3len(rest[v], rest[pins[k]]);
				if (d > 0.0f && d < fourth) {
					*worst_ratio = fmax(*worst_ratio, v3len(x[v], x[pins[k]]) / d);
				}
			}
		}
	}
	/* Stretch of the structural edges (compression, where the cloth folds, left out). */
	double worst = 0.0;
	for (int j = 0; j <= n; ++j) {
		for (int i = 0; i <= n; ++i) {
			int a = j * (n + 1) + i;
			if (i < n) {
				worst = fmax(worst, v3len(x[a], x[a + 1]) * n - 1.0);
			}
			if (j < n) {
				worst = fmax(worst, v3len(x[a], x[a + n + 1]) * n - 1.0);
			}
		}
	}
	*max_stretch = worst;
	free(x);
	free(rest);
	free(masses);
	test_grid_free(&grid);
	plait_destroy_world(world);
}

static void hang_from(const int *pins, int pin_count, plait_tether_mode mode, float scale,
                      double *worst_ratio, double *max_stretch)
{
	hang_with(pins, pin_count, mode, scale, 1.0f, worst_ratio, max_stretch);
}

/* Hung from its two top corners. */
static void hang(plait_tether_mode mode, float scale, double *worst_ratio, double *max_stretch)
{
	int pins[2] = {0, 20};
	hang_from(pins, 2, mode, scale, worst_ratio, max_stretch);
}

Test(tethers, no_vertex_exceeds_its_tether_length_times_scale)
{
	double ratio, strain;
	hang(PLAIT_TETHER_EUCLIDEAN, 1.0f, &ratio, &strain);
	cr_assert_leq(ratio, 1.0 + 1e-4, "a vertex reached %g times its tether length", ratio);
	hang(PLAIT_TETHER_EUCLIDEAN, 1.1f, &ratio, &strain);
	cr_assert_leq(ratio, 1.1 + 1e-4, "a vertex reached %g times its rest distance (scale 1.1)", ratio);
	/* Geodesic tethers follow the mesh: on this flat grid at most the octile distance, 8.3%
	 * above the straight one. */
	hang(PLAIT_TETHER_GEODESIC, 1.0f, &ratio, &strain);
	cr_assert_leq(ratio, 1.083 + 1e-4, "geodesic: %g", ratio);
}

Test(tethers, hold_a_heavy_hanging_cloth_to_its_rest_reach)
{
	double ratio_none, stretch_none, ratio_tethered, stretch_tethered;
	hang(PLAIT_TETHER_NONE, 1.0f, &ratio_none, &stretch_none);
	hang(PLAIT_TETHER_EUCLIDEAN, 1.0f, &ratio_tethered, &stretch_tethered);
	cr_log_info("largest edge stretch without tethers %.4f, with %.4f; worst pin distance ratio %.3f vs %.3f",
	            stretch_none, stretch_tethered, ratio_none, ratio_tethered);
	cr_assert_gt(ratio_none, 1.5, "without tethers the cloth should overstretch (%g)", ratio_none);
	cr_assert_leq(ratio_tethered, 1.0001);
	/* Tied to one pin each, vertices either side of the middle were pulled towards opposite
	 * corners and the edges between them torn to 1.79 times their length. */
	cr_assert_lt(stretch_tethered, 0.25);
}

/* A stiffness under 1 removes only that share of a tether's excess a pass: the cloth then hangs
 * past its tethers, farther the softer they are (the rows of two are solved in vector lanes
 * with one stiffness per run: a kernel that lost it would hold every cloth alike). */
Test(tethers, softer_tethers_let_the_cloth_hang_farther)
{
	int pins[2] = {0, 20};
	double ratio[3], stretch;
	const float stiffness[3] = {1.0f, 0.5f, 0.1f};
	for (int k = 0; k < 3; ++k) {
		hang_with(pins, 2, PLAIT_TETHER_EUCLIDEAN, 1.0f, stiffness[k], &ratio[k], &stretch);
	}
	cr_log_info("worst pin distance ratio at stiffness 1, 0.5, 0.1: %.5f %.5f %.5f", ratio[0], ratio[1],
	            ratio[2]);
	cr_assert_leq(ratio[0], 1.0001);
	cr_assert_gt(ratio[1], ratio[0] + 1e-4, "stiffness 0.5 held as tightly as 1 (%g, %g)", ratio[1],
	             ratio[0]);
	cr_assert_gt(ratio[2], ratio[1] + 1e-4, "stiffness 0.1 held as tightly as 0.5 (%g, %g)", ratio[2],
	             ratio[1]);
}

Test(tethers, three_pins_hold_every_tether)
{
	/* Two top corners and the middle of a side: balls that meet in circles and points. */
	int pins[3] = {0, 20, 10 * 21};
	double ratio, stretch;
	hang_from(pins, 3, PLAIT_TETHER_EUCLIDEAN, 1.0f, &ratio, &stretch);
	cr_assert_leq(ratio, 1.0 + 1e-4, "a vertex reached %g times a tether's length", ratio);
	cr_assert_lt(stretch, 0.25, "stretch %g", stretch);
}

Test(tethers, a_pinned_edge_holds_each_vertex_to_its_nearest_pins)
{
	int pins[21];
	for (int k = 0; k < 21; ++k) {
		pins[k] = k;
	}
	double ratio, stretch;
	hang_from(pins, 21, PLAIT_TETHER_EUCLIDEAN, 1.0f, &ratio, &stretch);
	cr_assert_leq(ratio, 1.0 + 1e-4, "a vertex reached %g times a tether's length", ratio);
}

/* The solver regroups tethers by their pins (dynamics/tether.c); destroying an object renumbers
 * the particles after it, and the regrouping must follow, or the second cloth's vertices would
 * be held to stale numbers. */
Test(tethers, hold_after_another_cloth_is_destroyed)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	/* A smaller cloth first, so that stale numbers would name other vertices and pins. */
	int sizes[2] = {7, 12};
	test_grid grids[2];
	plait_object_id cloths[2];
	for (int k = 0; k < 2; ++k) {
		int n = sizes[k];
		grids[k] = test_grid_make(n, n, 1.0f, 1.0f);
		for (int i = 0; i < grids[k].vertex_count; ++i) {
			grids[k].positions[i].x += 2.0f * (float)k;
		}
		int pins[2] = {0, n};
		plait_cloth_def def = plait_default_cloth_def();
		def.mesh = test_grid_mesh(&grids[k]);
		def.iterations = 3;
		def.pins = pins;
		def.pin_count = 2;
		def.tethers = PLAIT_TETHER_EUCLIDEAN;
		plait_error error;
		cloths[k] = plait_create_cloth(world, &def, &error);
		cr_assert(!plait_object_id_is_null(cloths[k]), "%s", error.message);
	}
	const test_grid *grid = &grids[1];
	int pins[2] = {0, sizes[1]};
	plait_vec3 *x = malloc(sizeof *x * (size_t)grid->vertex_count);
	cr_assert(test_step_frames(world, 10));
	plait_destroy_object(cloths[0]);
	double worst = 0.0;
	for (int frame = 0; frame < 40; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_object_get_positions(cloths[1], 0, grid->vertex_count, x, NULL);
		for (int v = 0; v < grid->vertex_count; ++v) {
			for (int k = 0; k < 2; ++k) {
				float d = v3len(grid->positions[v], grid->positions[pins[k]]);
				if (d > 0.0f) {
					worst = fmax(worst, v3len(x[v], x[pins[k]]) / d);
				}
			}
		}
	}
	cr_assert_leq(worst, 1.0 + 1e-4, "a vertex reached %g times its tether length", worst);
	/* It hangs: its free corners fell well below the pins. */
	cr_assert_lt(x[grid->vertex_count - 1].y, -0.5f);
	free(x);
	test_grid_free(&grids[0]);
	test_grid_free(&grids[1]);
	plait_destroy_world(world);
}

/* A cloth of the grid held at two pins by Euclidean tethers. */
static plait_object_id two_pin_cloth(plait_world_id world, test_grid *grid, const int pins[2])
{
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(grid);
	def.pins = pins;
	def.pin_count = 2;
	def.tethers = PLAIT_TETHER_EUCLIDEAN;
	plait_error error;
	plait_object_id cloth = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(cloth), "%s", error.message);
	return cloth;
}

/* Pins pulled apart past the cloth's reach leave the tethers without a common point: the
 * solver must stay finite and keep each vertex within reach of its nearest pin. */
Test(tethers, pins_pulled_apart_stay_finite)
{
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	test_grid grid = test_grid_make(10, 10, 1.0f, 1.0f);
	int pins[2] = {0, 10};
	plait_object_id cloth = two_pin_cloth(world, &grid, pins);
	plait_error error;
	for (int frame = 0; frame < 30; ++frame) {
		float spread = 0.5f + 0.05f * (float)frame;
		cr_assert_eq(plait_object_set_pin_target(cloth, 0, (plait_vec3){-spread, 0.0f, -0.5f}, &error),
		             PLAIT_OK);
		cr_assert_eq(plait_object_set_pin_target(cloth, 10, (plait_vec3){spread, 0.0f, -0.5f}, &error),
		             PLAIT_OK);
		cr_assert(test_step_frames(world, 1));
	}
	plait_vec3 x[121];
	plait_object_get_positions(cloth, 0, 121, x, NULL);
	for (int v = 0; v < 121; ++v) {
		cr_assert(isfinite(x[v].x) && isfinite(x[v].y) && isfinite(x[v].z), "vertex %d", v);
	}
	test_grid_free(&grid);
	plait_destroy_world(world);
}

/* Pins pulled apart past the cloth's width: a vertex of the pinned edge cannot be within reach of
 * both, and every vertex on that edge goes through the solver's exact fallback. Each must
 * still end within its nearest pin's tether (the nearest is projected last), on every
 * instruction set: a fallback that mixed up a row's two tethers would leave it short of one
 * and far past the other. */
Test(tethers, pins_pulled_apart_keep_each_vertex_within_its_nearest_tether)
{
	const plait_simd levels[] = {PLAIT_SIMD_SCALAR, PLAIT_SIMD_AVX2, PLAIT_SIMD_AVX512};
	for (int l = 0; l < 3; ++l) {
		if (!plait_simd_is_supported(levels[l])) {
			continue;
		}
		plait_world_def wdef = plait_default_world_def();
		wdef.simd = levels[l];
		plait_world_id world = plait_create_world(&wdef, NULL);
		int n = 20;
		test_grid grid = test_grid_make(n, n, 1.0f, 1.0f);
		int pins[2] = {0, n};
		plait_object_id cloth = two_pin_cloth(world, &grid, pins);
		plait_error error;
		plait_vec3 left = grid.positions[pins[0]], right = grid.positions[pins[1]];
		for (int frame = 0; frame < 12; ++frame) {
			float spread = 0.01f * (float)(frame < 6 ? frame + 1 : 6); /* then held 6 cm apart */
			cr_assert_eq(plait_object_set_pin_target(cloth, pins[0],
			                                         (plait_vec3){left.x - spread, left.y, left.z}, &error),
			             PLAIT_OK);
			cr_assert_eq(plait_object_set_pin_target(
			                 cloth, pins[1], (plait_vec3){right.x + spread, right.y, right.z}, &error),
			             PLAIT_OK);
			cr_assert(test_step_frames(world, 1));
		}
		int count = grid.vertex_count;
		plait_vec3 *x = malloc(sizeof *x * (size_t)count);
		plait_object_get_positions(cloth, 0, count, x, NULL);
		for (int v = 0; v < count; ++v) {
			if (v == pins[0] || v == pins[1]) {
				continue;
			}
			float rest0 = v3len(grid.positions[v], left), rest1 = v3len(grid.positions[v], right);
			/* Equally near both (the middle column): either may be the one projected last. */
			double ratio0 = v3len(x[v], x[pins[0]]) / rest0, ratio1 = v3len(x[v], x[pins[1]]) / rest1;
			double nearest = rest0 < rest1 ? ratio0 : rest1 < rest0 ? ratio1 : fmin(ratio0, ratio1);
			cr_assert_leq(nearest, 1.0 + 1e-4, "simd %d: vertex %d at %g times its nearest tether",
			              (int)levels[l], v, nearest);
		}
		free(x);
		test_grid_free(&grid);
		plait_destroy_world(world);
	}
}

Test(tethers, bad_parameters_are_rejected)
{
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	test_grid grid = test_grid_make(2, 2, 1.0f, 1.0f);
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.tethers = PLAIT_TETHER_GEODESIC;
	def.tether_scale = 0.5f;
	plait_error error;
	cr_assert(plait_object_id_is_null(plait_create_cloth(world, &def, &error)));
	cr_assert(strstr(error.message, "tether_scale must be in 1..10") != NULL, "%s", error.message);
	test_grid_free(&grid);
	plait_destroy_world(world);
}
