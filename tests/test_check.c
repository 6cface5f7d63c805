/* The intersection checker: crossing cloths are counted, separate ones are not, and vertices
 * inside colliders are reported. */
#include <criterion/criterion.h>
#include <stdbool.h>

#include "collision/intersect.h"
#include "test_support.h"

Test(check, triangle_pairs)
{
	plait_vec3 t[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
	plait_vec3 through[3] = {{0.2f, 0.2f, -1}, {0.2f, 0.2f, 1}, {0.3f, 0.3f, 1}};
	plait_vec3 above[3] = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
	plait_vec3 beside[3] = {{2, 0, -1}, {2, 0, 1}, {3, 0, 1}};
	cr_assert(plait_triangles_intersect(t, through));
	cr_assert_not(plait_triangles_intersect(t, above));
	cr_assert_not(plait_triangles_intersect(t, beside));
}

static plait_object_id sheet(plait_world_id world, float y, bool vertical)
{
	test_grid grid = test_grid_make(6, 6, 1.0f, 1.0f);
	for (int i = 0; i < grid.vertex_count; ++i) {
		if (vertical) {
			plait_vec3 p = grid.positions[i];
			grid.positions[i] = (plait_vec3){p.x, y + p.z, 0.013f};
		} else {
			grid.positions[i].y = y;
		}
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	plait_object_id id = plait_create_cloth(world, &def, NULL);
	test_grid_free(&grid);
	return id;
}

Test(check, crossing_cloths_are_counted_and_separate_ones_are_not)
{
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	sheet(world, 0.0f, false);
	sheet(world, 0.5f, false);
	plait_intersection_report report;
	cr_assert_eq(plait_world_check_intersections(world, &report, NULL), PLAIT_OK);
	cr_assert_eq(report.triangle_pairs, 0);
	/* A vertical sheet through the horizontal one at y = 0 crosses it along a line. */
	sheet(world, 0.0f, true);
	cr_assert_eq(plait_world_check_intersections(world, &report, NULL), PLAIT_OK);
	cr_assert_gt(report.triangle_pairs, 0);
	plait_destroy_world(world);
}

Test(check, vertices_inside_colliders_are_reported)
{
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def ball = plait_default_collider_def();
	ball.shape = PLAIT_SHAPE_SPHERE;
	ball.radius = 0.3f;
	plait_create_collider(world, &ball, NULL);
	plait_vec3 x[3] = {{0, 0, 0}, {0.1f, 0, 0}, {1, 1, 1}};
	plait_particles_def def = plait_default_particles_def();
	def.positions = x;
	def.count = 3;
	plait_create_particles(world, &def, NULL);
	plait_intersection_report report;
	cr_assert_eq(plait_world_check_intersections(world, &report, NULL), PLAIT_OK);
	cr_assert_eq(report.inside_colliders, 2);
	plait_destroy_world(world);
}
