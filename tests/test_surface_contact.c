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

/* ---- Bounce and stickiness between objects (mesh contacts) ----------------------------------- */

/* A 1 m sheet lying at y = 0 with every vertex pinned: a surface that does not give way. */
static plait_object_id add_pinned_sheet(plait_world_id world, float bounce, float stickiness)
{
	test_grid grid = test_grid_make(5, 5, 1.0f, 1.0f);
	int *pins = malloc(sizeof(int) * (size_t)grid.vertex_count);
	for (int i = 0; i < grid.vertex_count; ++i) {
		grid.positions[i].y = 0.0f;
		pins[i] = i;
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.pins = pins;
	def.pin_count = grid.vertex_count;
	def.surface.thickness = 0.005f;
	def.surface.bounce = bounce;
	def.surface.stickiness = stickiness;
	plait_error error;
	plait_object_id id = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(id), "%s", error.message);
	free(pins);
	test_grid_free(&grid);
	return id;
}

static plait_world_id bare_world(void)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	return world;
}

/* One particle (radius 1 cm) with the given surface, at `height`, still. */
static plait_object_id add_particle(plait_world_id world, float height, float bounce, float stickiness)
{
	plait_vec3 x = {0.1f, height, 0.15f};
	plait_particles_def def = plait_default_particles_def();
	def.positions = &x;
	def.count = 1;
	def.radius = 0.01f;
	def.surface.bounce = bounce;
	def.surface.stickiness = stickiness;
	plait_object_id id = plait_create_particles(world, &def, NULL);
	cr_assert(!plait_object_id_is_null(id));
	return id;
}

/* The height a particle dropped from 0.5 m climbs back to after its first landing, over the
 * level it landed at (metres), on a pinned cloth or on a ground plane of the same surface. */
static float rebound(bool on_cloth, float bounce)
{
	plait_world_id world = bare_world();
	float level;
	if (on_cloth) {
		add_pinned_sheet(world, bounce, 0.0f);
		level = 0.005f + 0.01f;
	} else {
		plait_collider_def ground = plait_default_collider_def();
		ground.surface.bounce = bounce;
		ground.surface.thickness = 0.005f;
		cr_assert(!plait_object_id_is_null(plait_create_collider(world, &ground, NULL)));
		level = 0.005f + 0.01f;
	}
	plait_object_id dot = add_particle(world, 0.5f + level, bounce, 0.0f);
	float lowest = 1e9f, highest_after = -1e9f;
	bool landed = false;
	for (int frame = 0; frame < 40; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_vec3 x, v;
		plait_object_get_positions(dot, 0, 1, &x, NULL);
		plait_object_get_velocities(dot, 0, 1, &v, NULL);
		cr_assert_geq(x.y, level - 2e-3f, "the particle went into the surface: y = %g", (double)x.y);
		lowest = fminf(lowest, x.y);
		/* Landed: at rest on the surface, or going up again (a frame is longer than a bounce). */
		landed = landed || x.y < level + 1e-3f || v.y > 0.0f;
		if (landed) {
			highest_after = fmaxf(highest_after, x.y);
		}
		/* Stop at the top of the first rebound, before it lands again. */
		if (landed && v.y < 0.0f) {
			break;
		}
	}
	cr_assert(landed, "the particle never reached the surface (lowest y = %g)", (double)lowest);
	plait_destroy_world(world);
	return highest_after - level;
}

Test(surface_contact, a_particle_bounces_off_a_cloth_as_its_bounce_asks_and_as_off_a_collider)
{
	/* From 0.5 m a perfectly elastic landing climbs back 0.5 m and one at restitution e climbs
	 * e^2 of it; the substeps' positions lose some. Before cloth contacts had bounce, every
	 * landing on a cloth was inelastic: 0 for all three. */
	float asked[3] = {0.0f, 0.5f, 1.0f};
	float low[3] = {0.0f, 0.07f, 0.35f}, high[3] = {0.01f, 0.2f, 0.505f};
	for (int k = 0; k < 3; ++k) {
		float cloth = rebound(true, asked[k]), ground = rebound(false, asked[k]);
		cr_log_info("bounce %g: rebound %.4f m off the cloth, %.4f m off the ground", (double)asked[k],
		            (double)cloth, (double)ground);
		cr_expect(cloth >= low[k] && cloth <= high[k], "bounce %g: rebound %g m off the cloth, want %g..%g",
		          (double)asked[k], (double)cloth, (double)low[k], (double)high[k]);
		cr_expect(ground >= low[k] && ground <= high[k],
		          "bounce %g: rebound %g m off the ground, want %g..%g", (double)asked[k], (double)ground,
		          (double)low[k], (double)high[k]);
		cr_expect(fabsf(cloth - ground) <= 0.25f * ground + 0.01f,
		          "bounce %g: %g m off the cloth against %g m off the ground", (double)asked[k],
		          (double)cloth, (double)ground);
	}
}

/* The highest mean height a 0.4 m sheet dropped from 0.3 m onto a pinned one climbs back to
 * after it lands, over the level it lands at (metres). */
static float cloth_rebound(float bounce)
{
	plait_world_id world = bare_world();
	add_pinned_sheet(world, bounce, 0.0f);
	test_grid grid = test_grid_make(5, 5, 0.4f, 0.4f);
	for (int i = 0; i < grid.vertex_count; ++i) {
		grid.positions[i].y = 0.3f;
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.surface.thickness = 0.005f;
	def.surface.bounce = bounce;
	plait_object_id upper = plait_create_cloth(world, &def, NULL);
	cr_assert(!plait_object_id_is_null(upper));
	int n = grid.vertex_count;
	test_grid_free(&grid);
	plait_vec3 *x = malloc(sizeof *x * (size_t)n);
	float level = 0.01f, highest_after = -1e9f;
	bool landed = false;
	for (int frame = 0; frame < 36; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_object_get_positions(upper, 0, n, x, NULL);
		float mean = 0.0f;
		for (int i = 0; i < n; ++i) {
			cr_assert_geq(x[i].y, level - 2e-3f, "frame %d: vertex %d went through the pinned cloth", frame,
			              i);
			mean += x[i].y / (float)n;
		}
		landed = landed || mean < level + 0.01f;
		if (landed) {
			highest_after = fmaxf(highest_after, mean);
		}
	}
	cr_assert(landed, "the sheet never landed");
	free(x);
	plait_destroy_world(world);
	return highest_after - level;
}

Test(surface_contact, a_cloth_dropped_on_a_cloth_bounces_back_as_its_bounce_asks)
{
	/* Its vertices land together, so it leaves nearly whole: a perfectly elastic landing
	 * climbs most of the way back, an inelastic one stays down. */
	float elastic = cloth_rebound(1.0f), inelastic = cloth_rebound(0.0f);
	cr_log_info("the sheet climbed back %.4f m at bounce 1, %.4f m at 0", (double)elastic, (double)inelastic);
	cr_expect_geq(elastic, 0.15f, "bounce 1: the sheet climbed back %g m of 0.29 m", (double)elastic);
	cr_expect_leq(elastic, 0.29f, "bounce 1: the sheet climbed back %g m of 0.29 m (energy made)",
	              (double)elastic);
	cr_expect_leq(inelastic, 0.01f, "bounce 0: the sheet climbed back %g m", (double)inelastic);
}

/* How far a particle resting on a surface (a pinned cloth or the ground) rises after a kick of
 * 1 m/s straight up, both surfaces with the given stickiness (metres). */
static float rise_after_kick(bool on_cloth, float stickiness)
{
	plait_world_id world = bare_world();
	float level = 0.005f + 0.01f;
	if (on_cloth) {
		add_pinned_sheet(world, 0.0f, stickiness);
	} else {
		plait_collider_def ground = plait_default_collider_def();
		ground.surface.stickiness = stickiness;
		ground.surface.thickness = 0.005f;
		cr_assert(!plait_object_id_is_null(plait_create_collider(world, &ground, NULL)));
	}
	plait_object_id dot = add_particle(world, level + 0.002f, 0.0f, stickiness);
	cr_assert(test_step_frames(world, 12));
	plait_vec3 x, kick = {0.0f, 1.0f, 0.0f};
	plait_object_get_positions(dot, 0, 1, &x, NULL);
	cr_assert(fabsf(x.y - level) < 1e-3f, "the particle rests at y = %g, not on the surface at %g",
	          (double)x.y, (double)level);
	cr_assert_eq(plait_object_set_velocities(dot, 0, 1, &kick, NULL), PLAIT_OK);
	float highest = x.y;
	for (int frame = 0; frame < 12; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_object_get_positions(dot, 0, 1, &x, NULL);
		highest = fmaxf(highest, x.y);
	}
	plait_destroy_world(world);
	return highest - level;
}

Test(surface_contact, stickiness_keeps_a_kicked_particle_on_a_cloth_as_on_a_collider)
{
	/* Unstuck, 1 m/s climbs 5.1 cm. Fully sticky, the first substep's rise (1 m/s over a
	 * substep of 1/72 s: 1.4 cm) is about all it gets: its separating speed is taken away while
	 * it still touches. Before cloth contacts had stickiness: 4.9 cm off the cloth. */
	float free_rise = rise_after_kick(true, 0.0f), stuck_rise = rise_after_kick(true, 1.0f);
	float ground_free = rise_after_kick(false, 0.0f), ground_stuck = rise_after_kick(false, 1.0f);
	cr_log_info("kicked: rose %.4f m unstuck and %.4f m at stickiness 1 off a cloth, %.4f and %.4f off the "
	            "ground",
	            (double)free_rise, (double)stuck_rise, (double)ground_free, (double)ground_stuck);
	cr_expect_geq(free_rise, 0.04f, "stickiness 0: rose %g m off the cloth", (double)free_rise);
	cr_expect_leq(stuck_rise, 0.015f, "stickiness 1: rose %g m off the cloth", (double)stuck_rise);
	cr_expect_leq(ground_stuck, 0.015f, "stickiness 1: rose %g m off the ground", (double)ground_stuck);
	cr_expect(fabsf(stuck_rise - ground_stuck) <= 2e-3f,
	          "stickiness 1: rose %g m off the cloth, %g m off the ground", (double)stuck_rise,
	          (double)ground_stuck);
}
