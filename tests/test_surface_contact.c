/* Vertices of one object against the triangles of another cloth: a cloth falling on another
 * stays on top even when their vertices do not line up, and particles rest on a cloth. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

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
