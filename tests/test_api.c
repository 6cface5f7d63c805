/* The public API: defaults, ids, and every failure returning a readable message. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"

#define ASSERT_MESSAGE(error, text)                                                                          \
	cr_assert(strstr((error).message, (text)) != NULL, "message \"%s\" lacks \"%s\"", (error).message, (text))

Test(api, world_def_is_validated)
{
	plait_error error;
	plait_world_def def = plait_default_world_def();
	def.substeps = 0;
	cr_assert(plait_world_id_is_null(plait_create_world(&def, &error)));
	cr_assert_eq(error.code, PLAIT_ERROR_INVALID_ARGUMENT);
	ASSERT_MESSAGE(error, "substeps must be in 1..1000, got 0");
	def = plait_default_world_def();
	def.fps = -24.0f;
	cr_assert(plait_world_id_is_null(plait_create_world(&def, &error)));
	ASSERT_MESSAGE(error, "fps must be > 0");
	def = plait_default_world_def();
	def.contact_pass_interval = -1;
	cr_assert(plait_world_id_is_null(plait_create_world(&def, &error)));
	ASSERT_MESSAGE(error, "contact_pass_interval must be in 0..1000, got -1");
	def = plait_default_world_def();
	def.space_scale = 0.0f;
	cr_assert(plait_world_id_is_null(plait_create_world(&def, &error)));
	ASSERT_MESSAGE(error, "space_scale");
	plait_world_def uninitialised;
	memset(&uninitialised, 0, sizeof uninitialised);
	cr_assert(plait_world_id_is_null(plait_create_world(&uninitialised, &error)));
	ASSERT_MESSAGE(error, "plait_default_world_def");
}

Test(api, defaults_are_the_documented_ones)
{
	plait_world_def w = plait_default_world_def();
	cr_assert_eq(w.fps, 24.0f);
	cr_assert_eq(w.substeps, 3);
	cr_assert_eq(w.max_collision_iterations, 4);
	cr_assert_eq(w.contact_pass_interval, 1);
	cr_assert_eq(w.gravity.y, -9.81f);
	cr_assert_eq(w.space_scale, 1.0f);
	plait_cloth_def c = plait_default_cloth_def();
	cr_assert_eq(c.stretch_resistance, 20.0f);
	cr_assert_eq(c.rest_length_scale, 1.0f);
	cr_assert(c.surface.collide);
}

Test(api, object_errors_name_the_object_and_field)
{
	plait_world_id world = plait_create_world(&(plait_world_def){0}, NULL);
	cr_assert(plait_world_id_is_null(world));
	plait_world_def wdef = plait_default_world_def();
	world = plait_create_world(&wdef, NULL);
	test_grid grid = test_grid_make(2, 2, 1.0f, 1.0f);
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.name = "shirt";
	cloth.mesh = test_grid_mesh(&grid);
	cloth.stretch_resistance = -1.0f;
	plait_error error;
	cr_assert(plait_object_id_is_null(plait_create_cloth(world, &cloth, &error)));
	ASSERT_MESSAGE(error, "cloth 'shirt': stretch_resistance must be in 0..10000, got -1");
	cloth.stretch_resistance = 20.0f;
	int bad_pin = 99;
	cloth.pins = &bad_pin;
	cloth.pin_count = 1;
	cr_assert(plait_object_id_is_null(plait_create_cloth(world, &cloth, &error)));
	ASSERT_MESSAGE(error, "pin 0 is vertex 99");
	cloth.pin_count = 0;
	grid.positions[3].x = NAN;
	cr_assert(plait_object_id_is_null(plait_create_cloth(world, &cloth, &error)));
	cr_assert_eq(error.code, PLAIT_ERROR_INVALID_MESH);
	ASSERT_MESSAGE(error, "positions[3] is not finite");
	grid.positions[3].x = 0.0f;
	grid.face_indices[2] = 42;
	cr_assert(plait_object_id_is_null(plait_create_cloth(world, &cloth, &error)));
	ASSERT_MESSAGE(error, "vertex index 42");
	/* Nothing half-made: the failed creations left no object behind. */
	cr_assert_eq(plait_world_get_object_count(world), 0);

	plait_collider_def sphere = plait_default_collider_def();
	sphere.name = "ball";
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.radius = -2.0f;
	cr_assert(plait_object_id_is_null(plait_create_collider(world, &sphere, &error)));
	ASSERT_MESSAGE(error, "collider 'ball': a sphere needs");
	sphere.shape = PLAIT_SHAPE_MESH;
	cr_assert(plait_object_id_is_null(plait_create_collider(world, &sphere, &error)));
	ASSERT_MESSAGE(error, "a mesh collider needs vertices and faces");

	plait_curve_def curve = plait_default_curve_def();
	plait_vec3 one = {0, 0, 0};
	curve.positions = &one;
	curve.vertex_count = 1;
	cr_assert(plait_object_id_is_null(plait_create_curve(world, &curve, &error)));
	ASSERT_MESSAGE(error, "at least 2 vertices");

	plait_particles_def particles = plait_default_particles_def();
	particles.positions = &one;
	particles.count = 1;
	particles.radius = 0.0f;
	cr_assert(plait_object_id_is_null(plait_create_particles(world, &particles, &error)));
	ASSERT_MESSAGE(error, "radius");
	test_grid_free(&grid);
	plait_destroy_world(world);
}

Test(api, ids_go_stale_when_destroyed_and_others_keep_working)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_vec3 a[3] = {{0, 1, 0}, {1, 1, 0}, {2, 1, 0}};
	plait_vec3 b[2] = {{0, 5, 0}, {1, 5, 0}};
	plait_particles_def def = plait_default_particles_def();
	def.positions = a;
	def.count = 3;
	def.name = "first";
	plait_object_id first = plait_create_particles(world, &def, NULL);
	def.positions = b;
	def.count = 2;
	def.name = "second";
	plait_object_id second = plait_create_particles(world, &def, NULL);
	cr_assert_str_eq(plait_object_get_name(second), "second");
	cr_assert_eq(plait_world_get_object_count(world), 2);
	plait_destroy_object(first);
	cr_assert_not(plait_object_is_valid(first));
	plait_error error;
	plait_vec3 out[3];
	cr_assert_eq(plait_object_get_positions(first, 0, 1, out, &error), PLAIT_ERROR_INVALID_ID);
	ASSERT_MESSAGE(error, "stale");
	/* The survivor still reads its own particles. */
	cr_assert_eq(plait_object_get_positions(second, 0, 2, out, &error), PLAIT_OK);
	cr_assert_eq(out[1].x, 1.0f);
	cr_assert_eq(out[1].y, 5.0f);
	cr_assert_eq(plait_world_get_object_count(world), 1);
	cr_assert_eq(plait_world_get_object(world, 0).index1, second.index1);
	cr_assert(test_step_frames(world, 2));
	/* Range errors say what was wrong. */
	cr_assert_eq(plait_object_get_positions(second, 1, 5, out, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	ASSERT_MESSAGE(error, "outside its 2 vertices");
	plait_destroy_world(world);
}

Test(api, positions_velocities_and_pins_round_trip)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.gravity = (plait_vec3){0, 0, 0};
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_vec3 x[2] = {{0, 0, 0}, {1, 0, 0}};
	plait_particles_def def = plait_default_particles_def();
	def.positions = x;
	def.count = 2;
	def.surface.collide = false;
	plait_object_id id = plait_create_particles(world, &def, NULL);
	plait_vec3 v[2] = {{1, 0, 0}, {0, 2, 0}};
	cr_assert_eq(plait_object_set_velocities(id, 0, 2, v, NULL), PLAIT_OK);
	cr_assert(test_step_frames(world, 24));
	plait_vec3 out[2];
	plait_object_get_positions(id, 0, 2, out, NULL);
	cr_assert_float_eq(out[0].x, 1.0f, 1e-4f);
	cr_assert_float_eq(out[1].y, 2.0f, 1e-4f);
	/* A pinned vertex follows its target, interpolated over the frame. */
	cr_assert_eq(plait_object_pin_vertex(id, 0, (plait_vec3){5, 0, 0}, NULL), PLAIT_OK);
	cr_assert(test_step_frames(world, 1));
	plait_object_get_positions(id, 0, 1, out, NULL);
	cr_assert_float_eq(out[0].x, 5.0f, 1e-5f);
	plait_error error;
	cr_assert_eq(plait_object_set_pin_target(id, 1, (plait_vec3){0, 0, 0}, &error),
	             PLAIT_ERROR_INVALID_ARGUMENT);
	ASSERT_MESSAGE(error, "not pinned");
	plait_destroy_world(world);
}

Test(api, keyframed_collider_sweeps_particles_along)
{
	/* A box moving sideways pushes a resting particle (space-time: it is hit inside the frame). */
	plait_world_def wdef = plait_default_world_def();
	wdef.gravity = (plait_vec3){0, 0, 0};
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def box = plait_default_collider_def();
	box.shape = PLAIT_SHAPE_BOX;
	box.center = (plait_vec3){-1.0f, 0, 0};
	box.size = (plait_vec3){0.2f, 1.0f, 1.0f};
	plait_object_id box_id = plait_create_collider(world, &box, NULL);
	plait_vec3 x = {0, 0, 0};
	plait_particles_def def = plait_default_particles_def();
	def.positions = &x;
	def.count = 1;
	def.radius = 0.05f;
	plait_object_id p = plait_create_particles(world, &def, NULL);
	for (int frame = 1; frame <= 10; ++frame) {
		plait_transform t = plait_identity_transform();
		t.translate.x = 0.2f * (float)frame;
		cr_assert_eq(plait_collider_set_transform(box_id, t, NULL), PLAIT_OK);
		cr_assert(test_step_frames(world, 1));
	}
	plait_vec3 out;
	plait_object_get_positions(p, 0, 1, &out, NULL);
	/* The box's right face ends at -1 + 0.1 + 2 = 1.1; the particle is in front of it. */
	cr_assert_geq(out.x, 1.1f + 0.05f - 1e-3f, "particle at x = %g", (double)out.x);
	cr_assert_eq(plait_world_get_stats(world).penetrations, 0);
	plait_destroy_world(world);
}

/* A world of wdef with a 2 x 2 cloth of stretch only (resistance `stretch`) over the ground. */
static plait_world_id schedule_world(const plait_world_def *wdef, float stretch, test_grid *grid,
                                     plait_object_id *cloth_id)
{
	plait_world_id world = plait_create_world(wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	*grid = test_grid_make(2, 2, 1.0f, 1.0f);
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(grid);
	cloth.stretch_resistance = stretch;
	cloth.shear_resistance = 0.0f;
	cloth.bend_resistance = 0.0f;
	*cloth_id = plait_create_cloth(world, &cloth, NULL);
	plait_collider_def ground = plait_default_collider_def();
	ground.point.y = -1.0f;
	plait_create_collider(world, &ground, NULL);
	return world;
}

/* Names of substep s's passes, joined by spaces. */
static void schedule_text(plait_world_id world, int s, char *text, size_t size)
{
	const char *names[64];
	int count = plait_world_get_schedule(world, s, names, 64);
	cr_assert(count > 0 && count <= 64);
	text[0] = '\0';
	for (int e = 0; e < count; ++e) {
		strncat(text, names[e], size - strlen(text) - 2);
		strncat(text, e + 1 < count ? " " : "", size - strlen(text) - 1);
	}
}

Test(api, schedule_is_readable_through_the_api)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.substeps = 10;
	test_grid grid;
	plait_object_id cloth;
	plait_world_id world = schedule_world(&wdef, plait_default_cloth_def().stretch_resistance, &grid, &cloth);
	cr_assert_eq(plait_world_get_substep_count(world), 10);
	char text[256];
	schedule_text(world, 0, text, sizeof text);
	cr_assert_str_eq(text, "stretch contact stretch collision");
	test_grid_free(&grid);
	plait_destroy_world(world);
}

/* Contact passes take collision slots among the stretch iterations: with the interval 1 and the
 * default 20 stretch iterations a frame over 3 substeps (6, 7, 7), each substep has as many
 * collision slots as stretch iterations, of which max_collision_iterations' share (1, 1, 2; the
 * last always among them) stay collision iterations; at most 8 slots a substep. */
Test(api, contact_passes_fill_collision_slots_between_stretch_iterations)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.contact_pass_interval = 1;
	test_grid grid;
	plait_object_id id;
	plait_world_id world = schedule_world(&wdef, plait_default_cloth_def().stretch_resistance, &grid, &id);
	char text[1024];
	schedule_text(world, 0, text, sizeof text);
	cr_expect_str_eq(
	    text, "stretch contact stretch contact stretch contact stretch contact stretch contact stretch "
	          "collision");
	schedule_text(world, 2, text, sizeof text);
	cr_expect_str_eq(
	    text, "stretch contact stretch contact stretch contact stretch collision stretch contact stretch "
	          "contact stretch collision");
	/* A rigid cloth's 1,000 stretch iterations: 8 slots a substep, not 333. */
	test_grid_free(&grid);
	plait_destroy_world(world);
	world = schedule_world(&wdef, 10000.0f, &grid, &id);
	const char *names[512];
	int count = plait_world_get_schedule(world, 0, names, 512), slots = 0, collisions = 0;
	for (int e = 0; e < count; ++e) {
		slots += strcmp(names[e], "contact") == 0 || strcmp(names[e], "collision") == 0;
		collisions += strcmp(names[e], "collision") == 0;
	}
	cr_expect_eq(slots, 8);
	cr_expect_eq(collisions, 1);
	cr_expect_str_eq(names[count - 1], "collision");
	/* 0: the collision iterations alone. */
	wdef = plait_world_get_def(world);
	wdef.contact_pass_interval = 0;
	cr_assert_eq(plait_world_set_def(world, &wdef, NULL), PLAIT_OK);
	count = plait_world_get_schedule(world, 0, names, 512);
	for (int e = 0; e < count; ++e) {
		cr_expect_str_neq(names[e], "contact");
	}
	test_grid_free(&grid);
	plait_destroy_world(world);
}

static size_t live_bytes;
static void *counting_alloc(size_t size, size_t alignment, void *context)
{
	(void)context;
	size_t *block = aligned_alloc(alignment, (size + 64 + alignment - 1) / alignment * alignment);
	block[0] = size;
	live_bytes += size;
	return (char *)block + 64;
}
static void counting_free(void *memory, void *context)
{
	(void)context;
	size_t *block = (size_t *)((char *)memory - 64);
	live_bytes -= block[0];
	free(block);
}

Test(api, allocator_hooks_see_every_byte_and_get_them_back)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.alloc = counting_alloc;
	wdef.free = counting_free;
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert_gt(live_bytes, 0);
	test_grid grid = test_grid_make(8, 8, 1.0f, 1.0f);
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(&grid);
	plait_object_id id = plait_create_cloth(world, &cloth, NULL);
	plait_collider_def ground = plait_default_collider_def();
	ground.point.y = -1.0f;
	plait_create_collider(world, &ground, NULL);
	cr_assert(test_step_frames(world, 5));
	plait_destroy_object(id);
	cr_assert(test_step_frames(world, 1));
	plait_destroy_world(world);
	cr_assert_eq(live_bytes, 0, "%zu bytes not returned", live_bytes);
	test_grid_free(&grid);
}

Test(api, ranges_that_overflow_an_int_are_rejected)
{
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_vec3 x[3] = {{0, 2, 0}, {1, 2, 0}, {2, 2, 0}};
	plait_particles_def def = plait_default_particles_def();
	def.positions = x;
	def.count = 3;
	plait_object_id id = plait_create_particles(world, &def, NULL);
	plait_vec3 out[3];
	plait_error error;
	cr_assert_eq(plait_object_get_positions(id, 2, 2147483647, out, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	ASSERT_MESSAGE(error, "outside its 3 vertices");
	cr_assert_eq(plait_object_set_velocities(id, 4, 0, out, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	plait_destroy_world(world);
}

Test(api, a_frame_going_non_finite_is_rolled_back)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.time_scale = 100.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_vec3 x[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}};
	plait_vec3 v[4] = {{3e38f, 0, 0}, {-3e38f, 0, 0}, {0, 0, 0}, {0, 0, 0}};
	plait_particles_def def = plait_default_particles_def();
	def.positions = x;
	def.velocities = v;
	def.count = 4;
	plait_object_id id = plait_create_particles(world, &def, NULL);
	plait_error error;
	cr_assert_eq(plait_world_step(world, &error), PLAIT_ERROR_NONFINITE);
	ASSERT_MESSAGE(error, "non-finite");
	plait_vec3 out[4];
	plait_object_get_positions(id, 0, 4, out, NULL);
	for (int k = 0; k < 4; ++k) {
		cr_assert(out[k].x == x[k].x && out[k].y == x[k].y && out[k].z == x[k].z,
		          "particle %d was not restored", k);
	}
	cr_assert_eq(plait_world_get_frame(world), 0);
	plait_destroy_world(world);
}

/* The same with enough particles that the frame's start is kept by the streaming copy
 * (core/stream_copy.c: 4 KB and up), with their ends unaligned: positions and velocities come
 * back to the bit. */
Test(api, a_large_frame_going_non_finite_is_rolled_back_to_the_bit)
{
	enum { COUNT = 1001 };
	plait_world_def wdef = plait_default_world_def();
	wdef.time_scale = 100.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_vec3 *x = malloc(sizeof *x * COUNT), *v = malloc(sizeof *v * COUNT);
	plait_vec3 *out = malloc(sizeof *out * COUNT);
	for (int k = 0; k < COUNT; ++k) {
		x[k] = (plait_vec3){0.37f * (float)(k % 31), 0.11f * (float)(k / 31), 0.013f * (float)k};
		v[k] = (plait_vec3){0.5f * (float)(k % 7) - 1.5f, 0.25f * (float)(k % 5), -0.1f * (float)(k % 3)};
	}
	v[500] = (plait_vec3){3e38f, 0, 0};
	v[501] = (plait_vec3){-3e38f, 0, 0};
	plait_particles_def def = plait_default_particles_def();
	def.positions = x;
	def.velocities = v;
	def.count = COUNT;
	plait_object_id id = plait_create_particles(world, &def, NULL);
	cr_assert(!plait_object_id_is_null(id));
	plait_error error;
	cr_assert_eq(plait_world_step(world, &error), PLAIT_ERROR_NONFINITE);
	plait_object_get_positions(id, 0, COUNT, out, NULL);
	cr_assert(memcmp(out, x, sizeof *x * COUNT) == 0, "positions were not restored");
	plait_object_get_velocities(id, 0, COUNT, out, NULL);
	cr_assert(memcmp(out, v, sizeof *v * COUNT) == 0, "velocities were not restored");
	free(x);
	free(v);
	free(out);
	plait_destroy_world(world);
}

/* Every allocation failing in turn, while creating and destroying objects: each call either
 * works or says "out of memory", and what it leaves behind is consistent. */
static int fail_after;
static void *failing_alloc(size_t size, size_t alignment, void *context)
{
	(void)context;
	if (fail_after-- == 0) {
		return NULL;
	}
	return aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
}
static void plain_free(void *memory, void *context)
{
	(void)context;
	free(memory);
}

Test(api, out_of_memory_anywhere_leaves_a_consistent_world)
{
	for (int failure = 0; failure < 200; ++failure) {
		plait_world_def wdef = plait_default_world_def();
		wdef.alloc = failing_alloc;
		wdef.free = plain_free;
		fail_after = failure;
		plait_error error;
		plait_world_id world = plait_create_world(&wdef, &error);
		if (plait_world_id_is_null(world)) {
			cr_assert_eq(error.code, PLAIT_ERROR_OUT_OF_MEMORY);
			continue;
		}
		test_grid grid = test_grid_make(4, 4, 1.0f, 1.0f);
		/* Uneven spacing: a constraint given another's rest length would show. */
		for (int i = 0; i < grid.vertex_count; ++i) {
			grid.positions[i].x *= 1.0f + 0.1f * (float)(i % 3);
		}
		plait_cloth_def cloth = plait_default_cloth_def();
		cloth.mesh = test_grid_mesh(&grid);
		cloth.tethers = PLAIT_TETHER_GEODESIC;
		int pins[1] = {0};
		cloth.pins = pins;
		cloth.pin_count = 1;
		plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
		if (plait_object_id_is_null(cloth_id)) {
			cr_assert_eq(error.code, PLAIT_ERROR_OUT_OF_MEMORY, "%s", error.message);
		} else {
			/* Freshly made, the cloth is at rest: no stretch edge is strained. */
			cr_assert_lt(plait_world_get_stats(world).max_strain, 1e-5f, "failure %d scrambled constraints",
			             failure);
		}
		plait_vec3 x[2] = {{0, 2, 0}, {1, 2, 0}};
		plait_particles_def particles = plait_default_particles_def();
		particles.positions = x;
		particles.count = 2;
		plait_object_id dots = plait_create_particles(world, &particles, NULL);
		plait_destroy_object(cloth_id);
		if (!plait_object_id_is_null(dots)) {
			plait_vec3 out[2];
			cr_assert_eq(plait_object_get_positions(dots, 0, 2, out, NULL), PLAIT_OK);
			cr_assert(out[0].y == 2.0f && out[1].x == 1.0f, "failure %d: the particles lost track of theirs",
			          failure);
		}
		plait_world_step(world, NULL);
		plait_destroy_world(world);
		test_grid_free(&grid);
	}
}
