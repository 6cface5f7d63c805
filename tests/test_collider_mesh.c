/* Collider geometry for writing and checking: world-space shapes where the collider is now,
 * surface meshes that are closed, outward, on the true surface and inside it, and that follow
 * the collider's transform once a step has reached it. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <plait/plait.h>

typedef struct surface {
	int vertex_count, triangle_count;
	plait_vec3 *positions;
	int *triangles;
} surface;

static surface surface_of(plait_object_id collider)
{
	surface s = {0};
	s.vertex_count = plait_collider_get_surface_vertex_count(collider);
	s.triangle_count = plait_collider_get_surface_triangles(collider, NULL, 0);
	cr_assert_gt(s.vertex_count, 0);
	cr_assert_gt(s.triangle_count, 0);
	s.positions = malloc(sizeof *s.positions * (size_t)s.vertex_count);
	s.triangles = malloc(sizeof(int) * 3 * (size_t)s.triangle_count);
	cr_assert_eq(plait_collider_get_surface_triangles(collider, s.triangles, s.triangle_count),
	             s.triangle_count);
	plait_error error;
	cr_assert_eq(plait_collider_get_surface_positions(collider, 0, s.vertex_count, s.positions, &error),
	             PLAIT_OK, "%s", error.message);
	for (int k = 0; k < 3 * s.triangle_count; ++k) {
		cr_assert(s.triangles[k] >= 0 && s.triangles[k] < s.vertex_count);
	}
	return s;
}

static void surface_free(surface *s)
{
	free(s->positions);
	free(s->triangles);
}

static plait_vec3 sub(plait_vec3 a, plait_vec3 b)
{
	return (plait_vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}

static plait_vec3 cross(plait_vec3 a, plait_vec3 b)
{
	return (plait_vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

static float dot(plait_vec3 a, plait_vec3 b)
{
	return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* Every edge joins exactly two triangles, in opposite directions (consistent winding). */
static bool closed_and_consistent(const surface *s)
{
	int edges = 3 * s->triangle_count;
	for (int e = 0; e < edges; ++e) {
		int t = e / 3, k = e % 3;
		int i = s->triangles[3 * t + k], j = s->triangles[3 * t + (k + 1) % 3];
		int opposite = 0, same = 0;
		for (int f = 0; f < edges; ++f) {
			int u = f / 3, m = f % 3;
			int a = s->triangles[3 * u + m], b = s->triangles[3 * u + (m + 1) % 3];
			opposite += a == j && b == i;
			same += a == i && b == j;
		}
		if (opposite != 1 || same != 1) {
			return false;
		}
	}
	return true;
}

/* Vertices on the true surface, triangle centres inside it, and triangles facing away from
 * the inside point `center`. */
static void expect_inscribed(plait_object_id collider, const surface *s, plait_vec3 center, float tolerance)
{
	for (int i = 0; i < s->vertex_count; ++i) {
		float d = plait_collider_signed_distance(collider, s->positions[i]);
		cr_assert(fabsf(d) < tolerance, "vertex %d is %g from the surface", i, (double)d);
	}
	for (int t = 0; t < s->triangle_count; ++t) {
		plait_vec3 a = s->positions[s->triangles[3 * t]], b = s->positions[s->triangles[3 * t + 1]],
		           c = s->positions[s->triangles[3 * t + 2]];
		plait_vec3 centroid = {(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, (a.z + b.z + c.z) / 3};
		cr_assert_leq(plait_collider_signed_distance(collider, centroid), tolerance, "triangle %d sticks out",
		              t);
		plait_vec3 normal = cross(sub(b, a), sub(c, a));
		if (dot(normal, normal) > 0.0f) {
			cr_assert_gt(dot(normal, sub(centroid, center)), 0.0f, "triangle %d faces inward", t);
		}
	}
}

static plait_world_id new_world(void)
{
	plait_world_def def = plait_default_world_def();
	plait_world_id world = plait_create_world(&def, NULL);
	cr_assert(!plait_world_id_is_null(world));
	return world;
}

Test(collider_mesh, sphere_surface_is_closed_outward_and_inscribed)
{
	plait_world_id world = new_world();
	plait_collider_def def = plait_default_collider_def();
	def.shape = PLAIT_SHAPE_SPHERE;
	def.center = (plait_vec3){0.5f, 1.0f, -0.25f};
	def.radius = 0.4f;
	plait_object_id ball = plait_create_collider(world, &def, NULL);
	surface s = surface_of(ball);
	cr_expect_eq(s.vertex_count, 2 + 31 * 64);
	cr_expect_eq(s.triangle_count, 2 * 64 * 31);
	cr_expect(closed_and_consistent(&s));
	expect_inscribed(ball, &s, def.center, 1e-5f);
	cr_expect(plait_collider_is_closed(ball));
	plait_collider_shape shape;
	cr_assert_eq(plait_collider_get_shape(ball, &shape, NULL), PLAIT_OK);
	cr_expect_eq(shape.type, PLAIT_SHAPE_SPHERE);
	cr_expect_float_eq(shape.center.x, 0.5f, 1e-6f);
	cr_expect_float_eq(shape.radius, 0.4f, 1e-6f);
	surface_free(&s);
	plait_destroy_world(world);
}

Test(collider_mesh, capsule_and_box_surfaces_are_closed_outward_and_inscribed)
{
	plait_world_id world = new_world();
	plait_collider_def capsule = plait_default_collider_def();
	capsule.shape = PLAIT_SHAPE_CAPSULE;
	capsule.a = (plait_vec3){0.0f, 0.0f, 0.0f};
	capsule.b = (plait_vec3){1.0f, 1.0f, 0.5f};
	capsule.radius = 0.2f;
	plait_object_id rod = plait_create_collider(world, &capsule, NULL);
	surface s = surface_of(rod);
	cr_expect(closed_and_consistent(&s));
	expect_inscribed(rod, &s, (plait_vec3){0.5f, 0.5f, 0.25f}, 1e-5f);
	surface_free(&s);

	plait_collider_def box = plait_default_collider_def();
	box.shape = PLAIT_SHAPE_BOX;
	box.center = (plait_vec3){0.0f, 2.0f, 0.0f};
	box.size = (plait_vec3){1.0f, 0.5f, 2.0f};
	box.rotation_deg = (plait_vec3){10.0f, 20.0f, 30.0f};
	plait_object_id crate = plait_create_collider(world, &box, NULL);
	s = surface_of(crate);
	cr_expect_eq(s.vertex_count, 8);
	cr_expect_eq(s.triangle_count, 12);
	cr_expect(closed_and_consistent(&s));
	expect_inscribed(crate, &s, box.center, 1e-5f);
	plait_collider_shape shape;
	cr_assert_eq(plait_collider_get_shape(crate, &shape, NULL), PLAIT_OK);
	cr_expect_float_eq(shape.half_extents.z, 1.0f, 1e-6f);
	for (int k = 0; k < 3; ++k) {
		cr_expect_float_eq(dot(shape.axes[k], shape.axes[k]), 1.0f, 1e-5f);
	}
	cr_expect(plait_collider_is_closed(rod) && plait_collider_is_closed(crate));
	surface_free(&s);
	plait_destroy_world(world);
}

Test(collider_mesh, plane_is_an_open_square_on_the_plane)
{
	plait_world_id world = new_world();
	plait_collider_def def = plait_default_collider_def();
	def.point = (plait_vec3){0.0f, -1.0f, 0.0f};
	def.normal = (plait_vec3){0.0f, 2.0f, 0.0f};
	plait_object_id ground = plait_create_collider(world, &def, NULL);
	surface s = surface_of(ground);
	cr_expect_eq(s.vertex_count, 4);
	cr_expect_eq(s.triangle_count, 2);
	for (int i = 0; i < 4; ++i) {
		cr_expect_float_eq(s.positions[i].y, -1.0f, 1e-6f);
		cr_expect_float_eq(fabsf(s.positions[i].x), 0.5f * PLAIT_COLLIDER_PLANE_SIZE, 1e-4f);
	}
	for (int t = 0; t < 2; ++t) {
		plait_vec3 a = s.positions[s.triangles[3 * t]], b = s.positions[s.triangles[3 * t + 1]],
		           c = s.positions[s.triangles[3 * t + 2]];
		cr_expect_gt(cross(sub(b, a), sub(c, a)).y, 0.0f, "the square faces up");
	}
	cr_expect_not(plait_collider_is_closed(ground));
	plait_collider_shape shape;
	cr_assert_eq(plait_collider_get_shape(ground, &shape, NULL), PLAIT_OK);
	cr_expect_float_eq(shape.normal.y, 1.0f, 1e-6f);
	cr_expect_float_eq(shape.point.y, -1.0f, 1e-6f);
	surface_free(&s);
	plait_destroy_world(world);
}

Test(collider_mesh, mesh_collider_keeps_its_triangles_and_knows_if_it_is_closed)
{
	plait_world_id world = new_world();
	/* A unit cube as 6 quads, and the same without its top. */
	plait_vec3 corners[8];
	for (int i = 0; i < 8; ++i) {
		corners[i] = (plait_vec3){(float)(i & 1), (float)((i >> 1) & 1), (float)((i >> 2) & 1)};
	}
	int indices[24] = {0, 4, 6, 2, 1, 3, 7, 5, 0, 1, 5, 4, 2, 6, 7, 3, 0, 2, 3, 1, 4, 5, 7, 6};
	int sizes[6] = {4, 4, 4, 4, 4, 4};
	plait_collider_def def = plait_default_collider_def();
	def.shape = PLAIT_SHAPE_MESH;
	def.mesh = (plait_mesh_def){corners, 8, sizes, 6, indices};
	plait_object_id cube = plait_create_collider(world, &def, NULL);
	def.mesh.face_count = 5;
	plait_object_id open_box = plait_create_collider(world, &def, NULL);
	cr_assert(!plait_object_id_is_null(cube) && !plait_object_id_is_null(open_box));
	surface s = surface_of(cube);
	cr_expect_eq(s.vertex_count, 8);
	cr_expect_eq(s.triangle_count, 12);
	cr_expect(closed_and_consistent(&s));
	/* Quads fanned from their first vertex: (a, b, c), (a, c, d). */
	cr_expect_eq(s.triangles[3], 0);
	cr_expect_eq(s.triangles[4], 6);
	cr_expect_eq(s.triangles[5], 2);
	cr_expect(plait_collider_is_closed(cube));
	cr_expect_not(plait_collider_is_closed(open_box));
	surface_free(&s);
	plait_destroy_world(world);
}

Test(collider_mesh, surface_follows_the_transform_once_a_step_reaches_it)
{
	plait_world_id world = new_world();
	plait_collider_def def = plait_default_collider_def();
	def.shape = PLAIT_SHAPE_SPHERE;
	def.radius = 0.5f;
	def.transform.translate = (plait_vec3){1.0f, 0.0f, 0.0f};
	plait_object_id ball = plait_create_collider(world, &def, NULL);
	plait_collider_shape shape;
	cr_assert_eq(plait_collider_get_shape(ball, &shape, NULL), PLAIT_OK);
	cr_expect_float_eq(shape.center.x, 1.0f, 1e-6f);
	plait_vec3 top;
	cr_assert_eq(plait_collider_get_surface_positions(ball, 0, 1, &top, NULL), PLAIT_OK);
	cr_expect_float_eq(top.x, 1.0f, 1e-6f);
	cr_expect_float_eq(top.y, 0.5f, 1e-6f);

	plait_transform moved = {{0.0f, 2.0f, 0.0f}, {0.0f, 0.0f, 90.0f}, 2.0f};
	cr_assert_eq(plait_collider_set_transform(ball, moved, NULL), PLAIT_OK);
	/* Not there yet: the step has not run. */
	cr_assert_eq(plait_collider_get_shape(ball, &shape, NULL), PLAIT_OK);
	cr_expect_float_eq(shape.center.x, 1.0f, 1e-6f);
	cr_assert_eq(plait_world_step(world, NULL), PLAIT_OK);
	cr_assert_eq(plait_collider_get_shape(ball, &shape, NULL), PLAIT_OK);
	cr_expect_float_eq(shape.center.y, 2.0f, 1e-6f);
	cr_expect_float_eq(shape.radius, 1.0f, 1e-6f);
	/* The top pole, rotated a quarter turn about z and scaled: (-1, 2, 0). */
	cr_assert_eq(plait_collider_get_surface_positions(ball, 0, 1, &top, NULL), PLAIT_OK);
	cr_expect_float_eq(top.x, -1.0f, 1e-5f);
	cr_expect_float_eq(top.y, 2.0f, 1e-5f);
	plait_destroy_world(world);
}

Test(collider_mesh, bad_ids_and_ranges_are_errors)
{
	plait_world_id world = new_world();
	plait_vec3 x[1] = {{0, 0, 0}};
	plait_particles_def dots = plait_default_particles_def();
	dots.positions = x;
	dots.count = 1;
	plait_object_id particles = plait_create_particles(world, &dots, NULL);
	plait_collider_def def = plait_default_collider_def();
	plait_object_id ground = plait_create_collider(world, &def, NULL);
	plait_error error;
	plait_collider_shape shape;
	cr_expect_eq(plait_collider_get_shape(particles, &shape, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect(strstr(error.message, "not a collider") != NULL, "%s", error.message);
	cr_expect_eq(plait_collider_get_shape((plait_object_id){0}, &shape, NULL), PLAIT_ERROR_INVALID_ID);
	cr_expect_eq(plait_collider_get_surface_vertex_count(particles), 0);
	cr_expect_eq(plait_collider_get_surface_triangles(particles, NULL, 0), 0);
	plait_vec3 out[5];
	cr_expect_eq(plait_collider_get_surface_positions(ground, 2, 3, out, &error),
	             PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect_eq(plait_collider_get_surface_positions(ground, 1, 3, out, NULL), PLAIT_OK);
	plait_destroy_world(world);
}

Test(collider_mesh, triangles_intersect_is_public)
{
	plait_vec3 t[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
	plait_vec3 through[3] = {{0.2f, 0.2f, -1}, {0.2f, 0.2f, 1}, {0.3f, 0.3f, 1}};
	plait_vec3 touching[3] = {{0.2f, 0.2f, 0}, {0.2f, 0.2f, 1}, {0.3f, 0.3f, 1}};
	plait_vec3 above[3] = {{0.2f, 0.2f, 0.001f}, {0.2f, 0.2f, 1}, {0.3f, 0.3f, 1}};
	cr_expect(plait_triangles_intersect(t, through));
	cr_expect(plait_triangles_intersect(t, touching));
	cr_expect_not(plait_triangles_intersect(t, above));
}
