/* States that begin tangled (issue 3, item 5): cloths modelled through each other, a cloth
 * through itself, positions set through another cloth. Before mesh_contact_untangle.c such a
 * state stayed tangled for good: two sheets begun through each other kept their 124 crossing
 * triangle pairs in every frame, the failsafe fighting them (56,000 CCD hits a frame). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "collision/intersect.h"
#include "dynamics/mesh_contact_internal.h"
#include "world/world.h"
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

static plait_world_id world_with_ground_and_passes(int contact_pass_interval)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	wdef.substeps = 4;
	wdef.contact_pass_interval = contact_pass_interval;
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	plait_collider_def ground = plait_default_collider_def();
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &ground, NULL)));
	return world;
}

static plait_world_id world_with_ground(void)
{
	return world_with_ground_and_passes(0);
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
		cr_assert(test_step_frames(world, 1), "frame %d failed", plait_world_get_frame(world) + 1);
		plait_frame_stats stats = plait_world_get_stats(world);
		int crossings = crossings_now(world), at = plait_world_get_frame(world);
		if (frame < clean_from) {
			tangles += stats.tangles;
			continue;
		}
		cr_assert_eq(crossings, 0, "frame %d: %d crossing triangle pairs", at, crossings);
		cr_assert_eq(stats.tangles, 0, "frame %d: %d tangles found", at, stats.tangles);
	}
	return tangles;
}

/* Undone, not torn apart: at rest on the ground the edges are near their lengths (a sheet
 * dropped on another without crossings ends at 0.01). */
static void expect_rested(plait_world_id world)
{
	plait_frame_stats last = plait_world_get_stats(world);
	cr_expect_lt(last.max_strain, 0.2f, "an edge ends stretched by %g", (double)last.max_strain);
}

/* Vertex-face pairs between two objects in the list, and of those, the ones that push at less
 * than `distance` (their contact distance clipped to their start separation). */
static void pairs_between(plait_world_id world, float distance, int *between, int *clipped)
{
	const plait_mesh_contacts *mc = world.world->sim.mesh_contacts;
	for (int k = 0; k < mc->pair_count; ++k) {
		const contact_pair *pair = &mc->pairs[k];
		if (pair->type == PAIR_VERTEX_FACE && mc->object_of[pair->v[0]] != mc->object_of[pair->v[3]]) {
			*between += 1;
			*clipped += pair->distance < distance - 1e-5f;
		}
	}
}

Test(untangle, two_cloths_begun_through_each_other_come_apart_and_stay_apart)
{
	plait_world_id world = world_with_ground();
	test_grid flat = tilted_sheet(20, 1.0f, 0.0f, 0.5f, 0.0f, 0.0f);
	test_grid tilted = tilted_sheet(12, 0.6f, 0.1f, 0.5f, 0.1f, 0.3f);
	add_cloth(world, &flat);
	add_cloth(world, &tilted);
	int begun = crossings_now(world);
	cr_assert_gt(begun, 0, "the sheets should begin through each other");
	long tangles = untangle(world, 4, 5);
	cr_log_info("%d crossing pairs at the start, %ld tangles found in frames 1-4", begun, tangles);
	cr_expect_gt(tangles, 0, "the crossings were never found (stats.tangles)");
	/* Every pair of the two sheets listed from then on pushes at their whole contact distance
	 * (0.01 m): pairs that begin closer than that are clipped to their start separation, but
	 * the pairs that began crossing had none to speak of, and clipped to it they would lie on
	 * each other without thickness, held apart by the failsafe alone. */
	int between = 0, clipped = 0;
	for (int frame = 5; frame <= 48; ++frame) {
		cr_assert_eq(untangle(world, 1, 1), 0);
		pairs_between(world, 0.01f, &between, &clipped);
	}
	cr_log_info("%d vertex-face pairs of the two sheets listed over frames 5-48, %d clipped", between,
	            clipped);
	cr_expect_gt(between, 0, "the sheets should meet");
	cr_expect_eq(clipped, 0,
	             "%d of %d vertex-face pairs of the two sheets pushed at less than their thicknesses",
	             clipped, between);
	expect_rested(world);
	plait_destroy_world(world);
	test_grid_free(&flat);
	test_grid_free(&tilted);
}

Test(untangle, a_cloth_that_lands_while_it_comes_apart_ends_on_the_other_at_its_thickness)
{
	/* Begun 10 cm over the ground, the sheets land before they are apart: the small one's
	 * vertices under the large one are squeezed between it and the ground, into its plane,
	 * where no edge crosses it. Found as vertices in it, they are pushed up through it; missed,
	 * they lay in it for good, the failsafe stepping in 96 times a frame. */
	plait_world_id world = world_with_ground();
	test_grid flat = tilted_sheet(20, 1.0f, 0.0f, 0.1f, 0.0f, 0.0f);
	test_grid tilted = tilted_sheet(12, 0.6f, 0.1f, 0.1f, 0.1f, 0.15f);
	add_cloth(world, &flat);
	plait_object_id upper = add_cloth(world, &tilted);
	cr_assert_gt(crossings_now(world), 0);
	cr_expect_gt(untangle(world, 4, 5), 0);
	cr_assert_eq(untangle(world, 40, 1), 0);
	plait_frame_stats last = plait_world_get_stats(world);
	cr_expect_eq(last.failsafe, 0, "the failsafe still steps in %d times a frame at rest", last.failsafe);
	expect_rested(world);
	/* All of it on the large sheet: over the ground by the large sheet's thickness and their
	 * contact distance (0.015 m), less a sag. */
	plait_vec3 x[169];
	cr_assert_eq(plait_object_get_positions(upper, 0, 169, x, NULL), PLAIT_OK);
	for (int i = 0; i < 169; ++i) {
		cr_expect_geq(x[i].y, 0.012f, "vertex %d of the small sheet lies %g m over the ground", i,
		              (double)x[i].y);
	}
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
	long tangles = untangle(world, 48, 5);
	cr_log_info("%d crossing pairs at the start, %ld tangles found in frames 1-4", begun, tangles);
	cr_expect_gt(tangles, 0);
	expect_rested(world);
	/* The pairs of its two parts that began crossing were rest pairs (closer than their
	 * contact distance in the start shape: never pushed, only swept). Undone, they no longer
	 * are: the parts push each other at the thickness as any two layers of a cloth do. */
	const plait_mesh_contacts *mc = world.world->sim.mesh_contacts;
	int across = 0;
	for (int r = 0; r < mc->rest_count; ++r) {
		const rest_pair *pair = &mc->rest_pairs[r];
		bool first_flat = pair->v[0] < flat.vertex_count,
		     last_flat = pair->v[pair_size[pair->type] - 1] < flat.vertex_count;
		across += first_flat != last_flat;
	}
	cr_log_info("%d rest pairs of %d between the cloth's two parts", across, mc->rest_count);
	cr_expect_eq(across, 0, "%d rest pairs between the cloth's two parts", across);
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
	long tangles = untangle(world, 48, 5);
	cr_log_info("%d crossing pairs after the set, %ld tangles found in frames 1-4", begun, tangles);
	cr_expect_gt(tangles, 0);
	expect_rested(world);
	free(still);
	plait_destroy_world(world);
	test_grid_free(&lower);
	test_grid_free(&upper);
	test_grid_free(&through);
}

/* A pseudo-random number in [low, high) (a linear congruential step). */
static float uniform(unsigned *state, float low, float high)
{
	*state = *state * 1664525u + 1013904223u;
	return low + (high - low) * (float)(*state >> 8) / 16777216.0f;
}

/* Start `start` of bench_untangle: two sheets (even starts) or three (odd) of random sizes,
 * resolutions, tilts and thicknesses, through one another about 0.3 m over the ground. */
static void random_sheets(plait_world_id world, int start)
{
	unsigned state = 1234u + 7919u * (unsigned)start;
	for (int k = 0; k < 2 + start % 2; ++k) {
		int n = 8 + (int)uniform(&state, 0.0f, 14.0f);
		float size = uniform(&state, 0.4f, 1.0f);
		(void)uniform(&state, 0.05f, 0.6f);
		float slope_x = uniform(&state, -0.4f, 0.4f), slope_z = uniform(&state, -0.4f, 0.4f);
		float cx = uniform(&state, -0.15f, 0.15f), cz = uniform(&state, -0.15f, 0.15f);
		float base = k == 0 ? 0.3f : 0.3f + uniform(&state, -0.05f, 0.05f);
		test_grid grid = test_grid_make(n, n, size, size);
		for (int i = 0; i < grid.vertex_count; ++i) {
			plait_vec3 *x = &grid.positions[i];
			x->y = base + slope_x * x->x + slope_z * x->z;
			x->x += cx;
			x->z += cz;
		}
		plait_cloth_def def = plait_default_cloth_def();
		def.mesh = test_grid_mesh(&grid);
		def.surface.thickness = uniform(&state, 0.002f, 0.01f);
		def.self_collide = true;
		plait_error error;
		cr_assert(!plait_object_id_is_null(plait_create_cloth(world, &def, &error)), "%s", error.message);
		test_grid_free(&grid);
	}
}

static void three_cloths_come_apart(int contact_pass_interval)
{
	plait_world_id world = world_with_ground_and_passes(contact_pass_interval);
	random_sheets(world, 17);
	int begun = crossings_now(world);
	cr_assert_gt(begun, 0);
	long tangles = untangle(world, 14, 15);
	cr_log_info("%d crossing pairs at the start, %ld tangles found in frames 1-14", begun, tangles);
	cr_expect_lt(tangles, 20000, "%ld tangles found: the crossings multiplied", tangles);
	cr_assert_eq(untangle(world, 46, 1), 0);
	plait_frame_stats last = plait_world_get_stats(world);
	cr_expect_lt(last.max_strain, 0.5f, "an edge ends stretched by %g", (double)last.max_strain);
	plait_destroy_world(world);
}

Test(untangle, three_cloths_begun_through_one_another_come_apart_without_tearing)
{
	/* Start 17 of bench_untangle. Exempt from contacts and the failsafe wherever both
	 * primitives had some tangled vertex (not only a crossing edge's with its triangle's), its
	 * sheets crumpled as they landed, passed through each other further from every crossing,
	 * and each new crossing freed more: 440,000 crossings found by frame 24, edges stretched to
	 * 4.5 times their length. */
	three_cloths_come_apart(0);
}

/* The same with contact passes (contact.h), which leave pairs alone while tangles are being
 * undone: projecting again the pairs that pushed held the sheets against the untangling, 150 to
 * 230 crossing pairs from frame 1 to frame 15. */
Test(untangle, three_cloths_come_apart_with_contact_passes)
{
	three_cloths_come_apart(1);
}

Test(untangle, two_cloths_crossed_so_that_neither_is_cut_in_two_come_apart)
{
	/* Start 4 of bench_untangle: the crossing runs from one sheet's border to the other's and
	 * cuts neither in two, so no piece is the smaller. Its ends are weighed by which side of
	 * the crossed triangle more of the cloth around them is on; without that they stayed
	 * crossed for good. */
	plait_world_id world = world_with_ground();
	random_sheets(world, 4);
	int begun = crossings_now(world);
	cr_assert_gt(begun, 0);
	long tangles = untangle(world, 5, 6);
	cr_log_info("%d crossing pairs at the start, %ld tangles found in frames 1-5", begun, tangles);
	cr_assert_eq(untangle(world, 55, 1), 0);
	expect_rested(world);
	plait_destroy_world(world);
}

/* Curve segments that cross the sheet's triangles (the checker counts cloth triangles only). */
static int rope_crossings(const plait_vec3 *rope, int rope_count, const plait_vec3 *sheet,
                          const test_grid *grid)
{
	int hits = 0;
	for (int i = 0; i + 1 < rope_count; ++i) {
		for (int f = 0; f < grid->face_count; ++f) {
			const int *q = &grid->face_indices[4 * f];
			for (int half = 0; half < 2; ++half) {
				hits += plait_segment_crosses_triangle(rope[i], rope[i + 1], sheet[q[0]], sheet[q[1 + half]],
				                                       sheet[q[2 + half]]);
			}
		}
	}
	return hits;
}

Test(untangle, a_cord_begun_through_a_sheet_comes_out_of_it)
{
	/* A cord lying over a sheet that dips through it and back (a drawstring threaded wrong): its
	 * dip, the smaller piece between the two crossings, goes back up through the sheet. Before
	 * curves were searched, it stayed through the sheet for good. */
	plait_world_id world = world_with_ground();
	test_grid grid = tilted_sheet(16, 0.8f, 0.0f, 0.4f, 0.0f, 0.0f);
	plait_object_id sheet = add_cloth(world, &grid);
	plait_vec3 cord[21];
	for (int i = 0; i < 21; ++i) {
		float s = (float)i / 20.0f;
		cord[i] = (plait_vec3){-0.3f + 0.5f * s, s > 0.6f && s < 0.85f ? 0.37f : 0.43f, 0.03f};
	}
	plait_curve_def def = plait_default_curve_def();
	def.positions = cord;
	def.vertex_count = 21;
	def.surface.thickness = 0.004f;
	plait_error error;
	plait_object_id curve = plait_create_curve(world, &def, &error);
	cr_assert(!plait_object_id_is_null(curve), "%s", error.message);
	plait_vec3 *x = malloc(sizeof *x * (size_t)grid.vertex_count);
	long tangles = 0;
	for (int frame = 0; frame <= 48; ++frame) {
		if (frame > 0) {
			cr_assert(test_step_frames(world, 1));
			tangles += plait_world_get_stats(world).tangles;
		}
		cr_assert_eq(plait_object_get_positions(sheet, 0, grid.vertex_count, x, NULL), PLAIT_OK);
		cr_assert_eq(plait_object_get_positions(curve, 0, 21, cord, NULL), PLAIT_OK);
		int crossings = rope_crossings(cord, 21, x, &grid);
		if (frame == 0) {
			cr_assert_gt(crossings, 0, "the cord should begin through the sheet");
		} else if (frame >= 4) {
			cr_assert_eq(crossings, 0, "frame %d: the cord crosses the sheet %d times", frame, crossings);
		}
	}
	cr_expect_gt(tangles, 0);
	free(x);
	plait_destroy_world(world);
	test_grid_free(&grid);
}

Test(untangle, turned_off_it_leaves_a_tangled_scene_as_it_was)
{
	/* plait_world_def.untangle false: no search, nothing counted, the crossings held. */
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	wdef.substeps = 4;
	wdef.untangle = false;
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	plait_collider_def ground = plait_default_collider_def();
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &ground, NULL)));
	test_grid flat = tilted_sheet(20, 1.0f, 0.0f, 0.5f, 0.0f, 0.0f);
	test_grid tilted = tilted_sheet(12, 0.6f, 0.1f, 0.5f, 0.1f, 0.3f);
	add_cloth(world, &flat);
	add_cloth(world, &tilted);
	int begun = crossings_now(world);
	for (int frame = 1; frame <= 8; ++frame) {
		cr_assert(test_step_frames(world, 1));
		cr_assert_eq(plait_world_get_stats(world).tangles, 0, "frame %d: tangles counted", frame);
	}
	cr_expect_geq(crossings_now(world), begun, "the crossings should be held as they were");
	/* Turned back on, it finds them and undoes them. */
	plait_world_def on = plait_world_get_def(world);
	on.untangle = true;
	plait_error error;
	cr_assert_eq(plait_world_set_def(world, &on, &error), PLAIT_OK, "%s", error.message);
	cr_expect_gt(untangle(world, 6, 7), 0);
	cr_assert_eq(untangle(world, 20, 1), 0);
	plait_destroy_world(world);
	test_grid_free(&flat);
	test_grid_free(&tilted);
}
