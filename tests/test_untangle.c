/* States that begin tangled (issue 3, item 5): cloths modelled through each other, a cloth
 * through itself, positions set through another cloth. Before mesh_contact_untangle.c such a
 * state stayed tangled for good: two sheets begun through each other kept their 124 crossing
 * triangle pairs in every frame, the failsafe fighting them (56,000 CCD hits a frame). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"

/* A square sheet of n x n quads, `size` metres across, centred at (cx, cy, cz) and tilted about z
 * by a slope (y rises by `slope` per metre of x). */
static test_grid tilted_sheet(int n, float size, float cx, float cy, float cz, float slope)
{
	test_grid grid = test_grid_make(n, n, size, size);
	for (int i = 0; i < grid.vertex_count; ++i) {
		plait_vec3 *x = &grid.positions[i];
		x->y = cy + slope * x->x;
		x->x += cx;
		x->z += cz;
	}
	return grid;
}

static plait_object_id add_cloth(plait_world_id world, const test_grid *grid)
{
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(grid);
	def.surface.thickness = 0.005f;
	def.self_collide = true;
	plait_error error;
	plait_object_id id = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(id), "%s", error.message);
	return id;
}

static plait_world_id world_with_ground(void)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	wdef.substeps = 4;
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	plait_collider_def ground = plait_default_collider_def();
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &ground, NULL)));
	return world;
}

static int crossings_now(plait_world_id world)
{
	plait_intersection_report report;
	cr_assert_eq(plait_world_check_intersections(world, &report, NULL), PLAIT_OK);
	return report.triangle_pairs;
}

/* Steps `frames` frames; from frame `clean_from` on (1-based) every frame must be free of
 * crossings and of tangles found. Returns the tangles found over the frames before it. */
static long untangle(plait_world_id world, int frames, int clean_from)
{
	long tangles = 0;
	for (int frame = 1; frame <= frames; ++frame) {
		cr_assert(test_step_frames(world, 1), "frame %d failed", frame);
		plait_frame_stats stats = plait_world_get_stats(world);
		int crossings = crossings_now(world);
		if (frame < clean_from) {
			tangles += stats.tangles;
			continue;
		}
		cr_assert_eq(crossings, 0, "frame %d: %d crossing triangle pairs", frame, crossings);
		cr_assert_eq(stats.tangles, 0, "frame %d: %d tangles found", frame, stats.tangles);
	}
	/* Undone, not torn apart: at rest on the ground the edges are near their lengths (a sheet
	 * dropped on another without crossings ends at 0.01). */
	plait_frame_stats last = plait_world_get_stats(world);
	cr_expect_lt(last.max_strain, 0.2f, "an edge ends stretched by %g", (double)last.max_strain);
	return tangles;
}

Test(untangle, two_cloths_begun_through_each_other_come_apart_and_stay_apart)
{
	plait_world_id world = world_with_ground();
	test_grid flat = tilted_sheet(20, 1.0f, 0.0f, 0.5f, 0.0f, 0.0f);
	test_grid tilted = tilted_sheet(12, 0.6f, 0.1f, 0.5f, 0.1f, 0.3f);
	plait_object_id lower_id = add_cloth(world, &flat);
	plait_object_id upper_id = add_cloth(world, &tilted);
	cr_assert_eq(flat.vertex_count, 441);
	cr_assert_eq(tilted.vertex_count, 169);
	int begun = crossings_now(world);
	cr_assert_gt(begun, 0, "the sheets should begin through each other");
	long tangles = untangle(world, 48, 4);
	cr_log_info("%d crossing pairs at the start, %ld tangles found in frames 1-3", begun, tangles);
	cr_expect_gt(tangles, 0, "the crossings were never found (stats.tangles)");
	/* Where the small sheet lies on the large one it keeps their thicknesses apart (the large
	 * one on the ground at 0.005 m, the small one a further 0.01 m up, less a sag): the pairs
	 * that began crossing had no separation at the start, and clipped to it (as pairs that begin
	 * closer than their thicknesses are) they let it sink to 0.0099 m. */
	plait_vec3 below[441], above[169];
	cr_assert_eq(plait_object_get_positions(lower_id, 0, 441, below, NULL), PLAIT_OK);
	cr_assert_eq(plait_object_get_positions(upper_id, 0, 169, above, NULL), PLAIT_OK);
	plait_vec3 low = below[0], high = below[0];
	for (int i = 1; i < 441; ++i) {
		low.x = fminf(low.x, below[i].x);
		low.z = fminf(low.z, below[i].z);
		high.x = fmaxf(high.x, below[i].x);
		high.z = fmaxf(high.z, below[i].z);
	}
	int over = 0;
	for (int i = 0; i < 169; ++i) {
		if (above[i].x > low.x + 0.03f && above[i].x < high.x - 0.03f && above[i].z > low.z + 0.03f &&
		    above[i].z < high.z - 0.03f) {
			over += 1;
			cr_expect_geq(above[i].y, 0.0115f, "vertex %d lies %g m over the ground, on the lower sheet", i,
			              (double)above[i].y);
		}
	}
	cr_expect_gt(over, 20, "the small sheet should end on the large one (%d vertices over it)", over);
	plait_destroy_world(world);
	test_grid_free(&flat);
	test_grid_free(&tilted);
}

Test(untangle, a_cloth_begun_through_itself_comes_apart_and_stays_apart)
{
	/* The same two sheets as one self-colliding cloth. */
	plait_world_id world = world_with_ground();
	test_grid flat = tilted_sheet(20, 1.0f, 0.0f, 0.5f, 0.0f, 0.0f);
	test_grid tilted = tilted_sheet(12, 0.6f, 0.1f, 0.5f, 0.1f, 0.3f);
	test_grid both = {0};
	both.vertex_count = flat.vertex_count + tilted.vertex_count;
	both.face_count = flat.face_count + tilted.face_count;
	both.positions = malloc(sizeof(plait_vec3) * (size_t)both.vertex_count);
	both.face_sizes = malloc(sizeof(int) * (size_t)both.face_count);
	both.face_indices = malloc(sizeof(int) * 4 * (size_t)both.face_count);
	memcpy(both.positions, flat.positions, sizeof(plait_vec3) * (size_t)flat.vertex_count);
	memcpy(both.positions + flat.vertex_count, tilted.positions,
	       sizeof(plait_vec3) * (size_t)tilted.vertex_count);
	for (int f = 0; f < both.face_count; ++f) {
		both.face_sizes[f] = 4;
	}
	memcpy(both.face_indices, flat.face_indices, sizeof(int) * 4 * (size_t)flat.face_count);
	for (int k = 0; k < 4 * tilted.face_count; ++k) {
		both.face_indices[4 * flat.face_count + k] = flat.vertex_count + tilted.face_indices[k];
	}
	add_cloth(world, &both);
	int begun = crossings_now(world);
	cr_assert_gt(begun, 0, "the cloth should begin through itself");
	long tangles = untangle(world, 48, 4);
	cr_log_info("%d crossing pairs at the start, %ld tangles found in frames 1-3", begun, tangles);
	cr_expect_gt(tangles, 0);
	plait_destroy_world(world);
	test_grid_free(&flat);
	test_grid_free(&tilted);
	test_grid_free(&both);
}

Test(untangle, a_cloth_set_through_another_comes_apart)
{
	/* Two sheets at rest on each other; then the upper is set through the lower, tilted: the
	 * next frames find the crossings (positions set from outside may cross anything) and undo
	 * them. */
	plait_world_id world = world_with_ground();
	test_grid lower = tilted_sheet(20, 1.0f, 0.0f, 0.02f, 0.0f, 0.0f);
	test_grid upper = tilted_sheet(12, 0.6f, 0.1f, 0.1f, 0.1f, 0.0f);
	add_cloth(world, &lower);
	plait_object_id moved = add_cloth(world, &upper);
	cr_assert_eq(untangle(world, 24, 1), 0);
	test_grid through = tilted_sheet(12, 0.6f, 0.1f, 0.05f, 0.1f, 0.3f);
	cr_assert_eq(plait_object_set_positions(moved, 0, through.vertex_count, through.positions, NULL),
	             PLAIT_OK);
	plait_vec3 *still = calloc((size_t)through.vertex_count, sizeof *still);
	cr_assert_eq(plait_object_set_velocities(moved, 0, through.vertex_count, still, NULL), PLAIT_OK);
	int begun = crossings_now(world);
	cr_assert_gt(begun, 0, "the upper sheet should now be through the lower one");
	long tangles = untangle(world, 48, 4);
	cr_log_info("%d crossing pairs after the set, %ld tangles found in frames 1-3", begun, tangles);
	cr_expect_gt(tangles, 0);
	free(still);
	plait_destroy_world(world);
	test_grid_free(&lower);
	test_grid_free(&upper);
	test_grid_free(&through);
}
