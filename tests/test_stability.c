/* Stability: example scenes run 10 s of simulated time without non-finite values and with
 * bounded energy; short runs with random parameters inside the documented ranges never
 * produce a non-finite value. */
#include <criterion/criterion.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"
#include "test_support.h"

Test(stability, random_parameters_never_go_non_finite, .timeout = 600)
{
	uint32_t state = 12345u;
	int runs = getenv("PLAIT_STABILITY_RUNS") ? atoi(getenv("PLAIT_STABILITY_RUNS")) : 300;
	for (int run = 0; run < runs; ++run) {
		plait_world_def wdef = plait_default_world_def();
		wdef.fps = test_uniform(&state, 12.0f, 120.0f);
		wdef.substeps = 1 + (int)(test_random(&state) % 8);
		wdef.max_collision_iterations = (int)(test_random(&state) % 10);
		wdef.gravity = (plait_vec3){test_uniform(&state, -5, 5), test_uniform(&state, -30, 0),
		                            test_uniform(&state, -5, 5)};
		wdef.air_density = test_uniform(&state, 0.0f, 5.0f);
		wdef.wind.speed = test_uniform(&state, 0.0f, 30.0f);
		wdef.wind.direction = (plait_vec3){test_uniform(&state, -1, 1), test_uniform(&state, -1, 1),
		                                   test_uniform(&state, -1, 1)};
		wdef.wind.noise = test_uniform(&state, 0.0f, 2.0f);
		wdef.space_scale = test_random(&state) % 4 == 0 ? 0.01f : 1.0f;
		wdef.time_scale = test_uniform(&state, 0.25f, 2.0f);
		plait_error error;
		plait_world_id world = plait_create_world(&wdef, &error);
		cr_assert(!plait_world_id_is_null(world), "run %d: %s", run, error.message);
		float unit = 1.0f / wdef.space_scale;

		int n = 4 + (int)(test_random(&state) % 12);
		test_grid grid = test_grid_make(n, n, unit * test_uniform(&state, 0.2f, 2.0f),
		                                unit * test_uniform(&state, 0.2f, 2.0f));
		for (int i = 0; i < grid.vertex_count; ++i) {
			grid.positions[i].y = unit * 1.0f;
		}
		plait_cloth_def cloth = plait_default_cloth_def();
		cloth.mesh = test_grid_mesh(&grid);
		cloth.density = test_uniform(&state, 0.01f, 5.0f);
		cloth.stretch_resistance = powf(10.0f, test_uniform(&state, -1.0f, 4.0f));
		cloth.compression_resistance = powf(10.0f, test_uniform(&state, -1.0f, 4.0f));
		cloth.shear_resistance = powf(10.0f, test_uniform(&state, -1.0f, 4.0f));
		cloth.bend_resistance = powf(10.0f, test_uniform(&state, -2.0f, 3.0f));
		cloth.iterations = test_random(&state) % 2 ? 0 : 1 + (int)(test_random(&state) % 40);
		cloth.rest_length_scale = test_uniform(&state, 0.5f, 1.5f);
		cloth.drag = test_uniform(&state, 0.0f, 2.0f);
		cloth.tangential_drag = test_uniform(&state, 0.0f, 1.0f);
		cloth.lift = test_uniform(&state, 0.0f, 1.0f);
		cloth.damp = test_uniform(&state, 0.0f, 5.0f);
		cloth.surface.thickness = unit * test_uniform(&state, 0.0f, 0.05f);
		cloth.surface.friction = test_uniform(&state, 0.0f, 2.0f);
		cloth.surface.bounce = test_uniform(&state, 0.0f, 1.0f);
		cloth.surface.stickiness = test_uniform(&state, 0.0f, 1.0f);
		int pins[2] = {0, n};
		cloth.pins = pins;
		cloth.pin_count = (int)(test_random(&state) % 3);
		plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
		cr_assert(!plait_object_id_is_null(cloth_id), "run %d: %s", run, error.message);

		plait_vec3 rope_x[12];
		for (int i = 0; i < 12; ++i) {
			rope_x[i] = (plait_vec3){unit * 0.05f * (float)i, unit * 1.5f, 0.0f};
		}
		plait_curve_def rope = plait_default_curve_def();
		rope.positions = rope_x;
		rope.vertex_count = 12;
		rope.mass = test_uniform(&state, 0.001f, 1.0f);
		rope.stretch_resistance = powf(10.0f, test_uniform(&state, -1.0f, 4.0f));
		rope.bend_resistance = powf(10.0f, test_uniform(&state, -2.0f, 3.0f));
		rope.drag = test_uniform(&state, 0.0f, 2.0f);
		plait_create_curve(world, &rope, NULL);

		plait_vec3 dots[30];
		for (int i = 0; i < 30; ++i) {
			dots[i] = (plait_vec3){unit * test_uniform(&state, -0.5f, 0.5f),
			                       unit * test_uniform(&state, 0.5f, 2.0f),
			                       unit * test_uniform(&state, -0.5f, 0.5f)};
		}
		plait_particles_def particles = plait_default_particles_def();
		particles.positions = dots;
		particles.count = 30;
		particles.radius = unit * test_uniform(&state, 0.005f, 0.1f);
		particles.mass = test_uniform(&state, 0.001f, 10.0f);
		particles.surface.bounce = test_uniform(&state, 0.0f, 1.0f);
		plait_create_particles(world, &particles, NULL);

		plait_collider_def collider = plait_default_collider_def();
		collider.shape = (plait_shape_type)(test_random(&state) % 4);
		collider.center = (plait_vec3){0.0f, unit * 0.4f, 0.0f};
		collider.radius = unit * test_uniform(&state, 0.1f, 0.5f);
		collider.a = (plait_vec3){-unit * 0.5f, unit * 0.4f, 0.0f};
		collider.b = (plait_vec3){unit * 0.5f, unit * 0.4f, 0.0f};
		collider.size = (plait_vec3){unit * 0.6f, unit * 0.3f, unit * 0.6f};
		collider.rotation_deg = (plait_vec3){test_uniform(&state, 0, 90), test_uniform(&state, 0, 90), 0.0f};
		collider.surface.friction = test_uniform(&state, 0.0f, 2.0f);
		collider.surface.thickness = unit * test_uniform(&state, 0.0f, 0.05f);
		plait_object_id collider_id = plait_create_collider(world, &collider, &error);
		cr_assert(!plait_object_id_is_null(collider_id), "run %d: %s", run, error.message);

		char description[512];
		snprintf(
		    description, sizeof description,
		    "fps %g substeps %d collisions %d air %g wind %g noise %g scale %g time %g; cloth n %d density "
		    "%g "
		    "stretch %g compression %g shear %g bend %g iterations %d rest %g drag %g/%g lift %g damp %g "
		    "thickness %g; rope mass %g stretch %g bend %g; particles r %g m %g; collider %d r %g",
		    (double)wdef.fps, wdef.substeps, wdef.max_collision_iterations, (double)wdef.air_density,
		    (double)wdef.wind.speed, (double)wdef.wind.noise, (double)wdef.space_scale,
		    (double)wdef.time_scale, n, (double)cloth.density, (double)cloth.stretch_resistance,
		    (double)cloth.compression_resistance, (double)cloth.shear_resistance,
		    (double)cloth.bend_resistance, cloth.iterations, (double)cloth.rest_length_scale,
		    (double)cloth.drag, (double)cloth.tangential_drag, (double)cloth.lift, (double)cloth.damp,
		    (double)cloth.surface.thickness, (double)rope.mass, (double)rope.stretch_resistance,
		    (double)rope.bend_resistance, (double)particles.radius, (double)particles.mass,
		    (int)collider.shape, (double)collider.radius);
		for (int frame = 0; frame < 24; ++frame) {
			plait_transform t = plait_identity_transform();
			t.translate.y = unit * 0.3f * sinf(0.3f * (float)frame);
			t.rotate_deg.y = 20.0f * (float)frame;
			plait_collider_set_transform(collider_id, t, NULL);
			plait_result result = plait_world_step(world, &error);
			cr_assert_eq(result, PLAIT_OK, "run %d frame %d: %s\n%s", run, frame, error.message, description);
			cr_assert_eq(plait_world_get_stats(world).nonfinite, 0, "run %d frame %d", run, frame);
		}
		test_grid_free(&grid);
		plait_destroy_world(world);
	}
}

/* Every scene in scenes/ runs 10 s of simulated time with no non-finite value and kinetic
 * energy bounded by what falling from the scene could release. */
Test(stability, example_scenes_run_ten_seconds, .timeout = 900)
{
	DIR *folder = opendir(PLAIT_SOURCE_DIR "/scenes");
	cr_assert_not_null(folder);
	struct dirent *entry;
	int scenes = 0;
	while ((entry = readdir(folder)) != NULL) {
		size_t length = strlen(entry->d_name);
		if (length < 6 || strcmp(entry->d_name + length - 5, ".json") != 0) {
			continue;
		}
		char path[1024];
		snprintf(path, sizeof path, "%s/scenes/%s", PLAIT_SOURCE_DIR, entry->d_name);
		plait_scene scene;
		plait_tool_error error;
		cr_assert(plait_scene_load(path, &scene, &error), "%s: %s", path, error.message);
		plait_world_id world;
		cr_assert(plait_scene_create_world(&scene, &world, &error), "%s: %s", path, error.message);
		int frames = (int)ceilf(10.0f * scene.world.fps);
		double worst_energy = 0.0;
		for (int frame = 1; frame <= frames; ++frame) {
			cr_assert(plait_scene_apply_frame(&scene, world, frame, &error), "%s: %s", path, error.message);
			plait_error step_error;
			cr_assert_eq(plait_world_step(world, &step_error), PLAIT_OK, "%s frame %d: %s", path, frame,
			             step_error.message);
			plait_frame_stats stats = plait_world_get_stats(world);
			cr_assert_eq(stats.nonfinite, 0, "%s frame %d", path, frame);
			worst_energy = fmax(worst_energy, stats.kinetic_energy);
		}
		/* Bounded: no scene here holds more than a few kg falling a few metres, or wind of
		 * 20 m/s; 1 kJ is far above anything physical and far below any blow-up. */
		cr_assert_lt(worst_energy, 1000.0, "%s: kinetic energy reached %g J", path, worst_energy);
		cr_log_info("%s: 10 s, max kinetic energy %.3g J", entry->d_name, worst_energy);
		plait_destroy_world(world);
		plait_scene_free(&scene);
		++scenes;
	}
	closedir(folder);
	cr_assert_geq(scenes, 3);
}

/* A heavy rigid cloth (127 x 127 quads, 1 kg per vertex, stretch and compression rigid) hung
 * from two corners over a sphere, without tethers, with one pass per substep. With the stretch
 * sweep alternating direction from substep to substep it blew up within 15 frames at 16
 * substeps and at 32 (the edges next to a pin were left stretched every other substep, and the
 * velocity update fed the oscillation); every substep now ends its stretch sweep the same way. */
static void hang_heavy_rigid_cloth(int substeps)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	wdef.substeps = substeps;
	plait_world_id world = plait_create_world(&wdef, NULL);
	int n = 127;
	test_grid grid = test_grid_make(n, n, 2.0f, 2.0f);
	float *masses = malloc(sizeof(float) * (size_t)grid.vertex_count);
	for (int i = 0; i < grid.vertex_count; ++i) {
		masses[i] = 1.0f;
	}
	int pins[2] = {0, n};
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.vertex_masses = masses;
	def.stretch_resistance = def.compression_resistance = 10000.0f;
	def.iterations = substeps;
	def.surface.thickness = 0.0f;
	def.pins = pins;
	def.pin_count = 2;
	plait_error error;
	plait_object_id cloth = plait_create_cloth(world, &def, &error);
	cr_assert(!plait_object_id_is_null(cloth), "%s", error.message);
	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.0f, -0.75f, 0.0f};
	sphere.radius = 0.5f;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &sphere, &error)), "%s", error.message);
	/* Falling 3 m at most, 16,384 kg can gain at most about 0.5 MJ. */
	for (int frame = 0; frame < 40; ++frame) {
		cr_assert(test_step_frames(world, 1), "%d substeps: frame %d failed", substeps, frame);
		plait_frame_stats stats = plait_world_get_stats(world);
		cr_assert_lt(stats.kinetic_energy, 1e6, "%d substeps, frame %d: kinetic energy %g J", substeps, frame,
		             stats.kinetic_energy);
		/* Strain: the blow-up reached 45 by frame 9. Later, overloaded as it is (16 t on rigid
		 * edges without tethers), the sheet slides off the ball and its edges near the pins
		 * stretch towards 20 whatever the sweep, so the bound holds for the first half. */
		if (frame < 20) {
			cr_assert_lt(stats.max_strain, 20.0f, "%d substeps, frame %d: strain %g", substeps, frame,
			             (double)stats.max_strain);
		}
	}
	free(masses);
	test_grid_free(&grid);
	plait_destroy_world(world);
}

Test(stability, heavy_rigid_cloth_hangs_with_one_pass, .timeout = 300)
{
	hang_heavy_rigid_cloth(16);
	hang_heavy_rigid_cloth(32);
}
