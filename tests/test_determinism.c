/* Determinism: the same scene gives byte-identical results. */
#include <criterion/criterion.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "test_support.h"

static uint64_t fnv1a(uint64_t hash, const void *data, size_t size)
{
	const unsigned char *bytes = data;
	for (size_t k = 0; k < size; ++k) {
		hash ^= bytes[k];
		hash *= 1099511628211ull;
	}
	return hash;
}

/* A scene with everything at once: cloth in wind with noise on a sphere and plane, a rope,
 * and a pile of particles. Returns a hash of all positions and velocities at every frame. */
static uint64_t run_scene(void)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.wind.speed = 3.0f;
	wdef.wind.noise = 0.5f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	test_grid grid = test_grid_make(24, 24, 1.5f, 1.5f);
	for (int i = 0; i < grid.vertex_count; ++i) {
		grid.positions[i].y = 1.5f;
	}
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(&grid);
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, NULL);
	plait_vec3 rope_x[20];
	for (int i = 0; i < 20; ++i) {
		rope_x[i] = (plait_vec3){1.0f + 0.05f * (float)i, 2.0f, 0.0f};
	}
	plait_curve_def rope = plait_default_curve_def();
	rope.positions = rope_x;
	rope.vertex_count = 20;
	int pin = 0;
	rope.pins = &pin;
	rope.pin_count = 1;
	plait_object_id rope_id = plait_create_curve(world, &rope, NULL);
	plait_vec3 pile[200];
	for (int i = 0; i < 200; ++i) {
		pile[i] = (plait_vec3){-0.3f + 0.06f * (float)(i % 10), 2.5f + 0.06f * (float)(i / 100),
		                       -0.3f + 0.06f * (float)((i / 10) % 10)};
	}
	plait_particles_def particles = plait_default_particles_def();
	particles.positions = pile;
	particles.count = 200;
	particles.radius = 0.025f;
	plait_object_id pile_id = plait_create_particles(world, &particles, NULL);
	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.0f, 0.6f, 0.0f};
	sphere.radius = 0.5f;
	plait_create_collider(world, &sphere, NULL);
	plait_collider_def ground = plait_default_collider_def();
	plait_create_collider(world, &ground, NULL);

	plait_object_id objects[3] = {cloth_id, rope_id, pile_id};
	uint64_t hash = 1469598103934665603ull;
	plait_vec3 *buffer = malloc(sizeof *buffer * 1024);
	for (int frame = 0; frame < 48; ++frame) {
		cr_assert(test_step_frames(world, 1));
		for (int o = 0; o < 3; ++o) {
			int n = plait_object_get_vertex_count(objects[o]);
			plait_object_get_positions(objects[o], 0, n, buffer, NULL);
			hash = fnv1a(hash, buffer, sizeof *buffer * (size_t)n);
			plait_object_get_velocities(objects[o], 0, n, buffer, NULL);
			hash = fnv1a(hash, buffer, sizeof *buffer * (size_t)n);
		}
	}
	free(buffer);
	test_grid_free(&grid);
	plait_destroy_world(world);
	return hash;
}

Test(determinism, same_scene_twice_gives_identical_bytes)
{
	uint64_t first = run_scene(), second = run_scene();
	cr_assert_eq(first, second, "hashes differ: %llx vs %llx", (unsigned long long)first,
	             (unsigned long long)second);
}
