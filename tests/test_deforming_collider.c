/* Deforming mesh colliders: a rising floor carries what rests on it and nothing ends below it, a
 * sliding floor carries by friction, an inflating sphere and a box sweeping at 60 m/s leave no
 * particle inside, the same positions come out with any thread count, the API refuses bad
 * positions, and a scene's `sequence` of OBJ files drives the collider, every file checked
 * before the run. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "collision/mesh_shape.h"
#include "collision/moving_triangle.h"
#include "scene.h"
#include "test_cli.h"
#include "test_support.h"
#include "thread_pool.h"

/* ---- Meshes ---------------------------------------------------------------------------------- */

typedef struct test_mesh {
	plait_vec3 *positions;
	int vertex_count;
	int *sizes, *indices;
	int face_count, index_count;
} test_mesh;

static void test_mesh_free(test_mesh *mesh)
{
	free(mesh->positions);
	free(mesh->sizes);
	free(mesh->indices);
	*mesh = (test_mesh){0};
}

static plait_mesh_def test_mesh_def(const test_mesh *mesh)
{
	return (plait_mesh_def){mesh->positions, mesh->vertex_count, mesh->sizes, mesh->face_count,
	                        mesh->indices};
}

/* Turns every face to face away from the origin (the mesh is star-shaped around it). */
static void orient_outward(test_mesh *mesh)
{
	for (int f = 0, start = 0; f < mesh->face_count; start += mesh->sizes[f++]) {
		int *face = mesh->indices + start;
		plait_vec3 a = mesh->positions[face[0]], b = mesh->positions[face[1]], c = mesh->positions[face[2]];
		plait_vec3 u = {b.x - a.x, b.y - a.y, b.z - a.z}, v = {c.x - a.x, c.y - a.y, c.z - a.z};
		plait_vec3 n = {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
		if (n.x * a.x + n.y * a.y + n.z * a.z < 0.0f) {
			for (int i = 0, j = mesh->sizes[f] - 1; i < j; ++i, --j) {
				int swap = face[i];
				face[i] = face[j];
				face[j] = swap;
			}
		}
	}
}

static void add_face(test_mesh *mesh, int size, const int *corners)
{
	mesh->sizes[mesh->face_count++] = size;
	memcpy(mesh->indices + mesh->index_count, corners, sizeof(int) * (size_t)size);
	mesh->index_count += size;
}

/* A closed unit sphere of latitude rings and longitude segments (triangles at the poles). */
static test_mesh make_sphere(int rings, int segments)
{
	test_mesh mesh = {0};
	mesh.vertex_count = 2 + (rings - 1) * segments;
	mesh.positions = malloc(sizeof *mesh.positions * (size_t)mesh.vertex_count);
	mesh.sizes = malloc(sizeof(int) * (size_t)(rings * segments));
	mesh.indices = malloc(sizeof(int) * 4 * (size_t)(rings * segments));
	mesh.positions[0] = (plait_vec3){0.0f, 1.0f, 0.0f};
	mesh.positions[mesh.vertex_count - 1] = (plait_vec3){0.0f, -1.0f, 0.0f};
	for (int r = 1; r < rings; ++r) {
		float polar = 3.14159265f * (float)r / (float)rings;
		for (int s = 0; s < segments; ++s) {
			float azimuth = 2.0f * 3.14159265f * (float)s / (float)segments;
			mesh.positions[1 + (r - 1) * segments + s] =
			    (plait_vec3){sinf(polar) * cosf(azimuth), cosf(polar), sinf(polar) * sinf(azimuth)};
		}
	}
	for (int s = 0; s < segments; ++s) {
		int next = (s + 1) % segments;
		int top[3] = {0, 1 + s, 1 + next};
		add_face(&mesh, 3, top);
		int base = 1 + (rings - 2) * segments;
		int bottom[3] = {mesh.vertex_count - 1, base + next, base + s};
		add_face(&mesh, 3, bottom);
		for (int r = 1; r + 1 < rings; ++r) {
			int a = 1 + (r - 1) * segments;
			int quad[4] = {a + s, a + segments + s, a + segments + next, a + next};
			add_face(&mesh, 4, quad);
		}
	}
	orient_outward(&mesh);
	return mesh;
}

/* A closed cube of half size h centred at the origin. */
static test_mesh make_cube(float h)
{
	test_mesh mesh = {0};
	mesh.vertex_count = 8;
	mesh.positions = malloc(sizeof *mesh.positions * 8);
	mesh.sizes = malloc(sizeof(int) * 6);
	mesh.indices = malloc(sizeof(int) * 24);
	for (int v = 0; v < 8; ++v)
		mesh.positions[v] = (plait_vec3){v & 1 ? h : -h, v & 2 ? h : -h, v & 4 ? h : -h};
	static const int faces[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4},
	                                {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
	for (int f = 0; f < 6; ++f)
		add_face(&mesh, 4, faces[f]);
	orient_outward(&mesh);
	return mesh;
}

/* ---- Worlds ---------------------------------------------------------------------------------- */

static plait_world_id make_world(float gravity_y, plait_thread_pool *pool)
{
	plait_world_def def = plait_default_world_def();
	def.fps = 60.0f;
	def.gravity = (plait_vec3){0.0f, gravity_y, 0.0f};
	def.air_density = 0.0f;
	plait_thread_pool_attach(pool, &def);
	plait_error error;
	plait_world_id world = plait_create_world(&def, &error);
	cr_assert(!plait_world_id_is_null(world), "%s", error.message);
	return world;
}

static plait_object_id add_deforming(plait_world_id world, const char *name, plait_mesh_def mesh,
                                     float friction)
{
	plait_collider_def def = plait_default_collider_def();
	def.name = name;
	def.shape = PLAIT_SHAPE_MESH;
	def.mesh = mesh;
	def.deforming = true;
	def.surface.friction = friction;
	plait_error error;
	plait_object_id id = plait_create_collider(world, &def, &error);
	cr_assert(!plait_object_id_is_null(id), "%s", error.message);
	return id;
}

/* nx * nz particles of radius r in a square of side `side` at height y. */
static plait_object_id add_layer(plait_world_id world, int nx, int nz, float side, float y, float r,
                                 float friction)
{
	int count = nx * nz;
	plait_vec3 *x = malloc(sizeof *x * (size_t)count);
	for (int k = 0; k < count; ++k) {
		float u = nx > 1 ? (float)(k % nx) / (float)(nx - 1) - 0.5f : 0.0f;
		float w = nz > 1 ? (float)(k / nx) / (float)(nz - 1) - 0.5f : 0.0f;
		x[k] = (plait_vec3){side * u, y, side * w};
	}
	plait_particles_def def = plait_default_particles_def();
	def.name = "dots";
	def.positions = x;
	def.count = count;
	def.radius = r;
	def.self_collide = false;
	def.surface.friction = friction;
	plait_error error;
	plait_object_id id = plait_create_particles(world, &def, &error);
	cr_assert(!plait_object_id_is_null(id), "%s", error.message);
	free(x);
	return id;
}

/* A cubic cloud of n^3 particles spaced `spacing` apart around the origin, at rest. */
static plait_object_id add_cloud(plait_world_id world, int n, float spacing, float r)
{
	int count = n * n * n;
	plait_vec3 *x = malloc(sizeof *x * (size_t)count);
	float offset = 0.5f * spacing * (float)(n - 1);
	for (int k = 0; k < count; ++k)
		x[k] = (plait_vec3){spacing * (float)(k % n) - offset, spacing * (float)(k / n % n) - offset,
		                    spacing * (float)(k / (n * n)) - offset};
	plait_particles_def def = plait_default_particles_def();
	def.name = "cloud";
	def.positions = x;
	def.count = count;
	def.radius = r;
	def.self_collide = false;
	plait_object_id id = plait_create_particles(world, &def, NULL);
	cr_assert(!plait_object_id_is_null(id));
	free(x);
	return id;
}

static void set_shape(plait_object_id collider, const test_mesh *rest, plait_vec3 scale, plait_vec3 shift)
{
	plait_vec3 *x = malloc(sizeof *x * (size_t)rest->vertex_count);
	for (int v = 0; v < rest->vertex_count; ++v)
		x[v] =
		    (plait_vec3){scale.x * rest->positions[v].x + shift.x, scale.y * rest->positions[v].y + shift.y,
		                 scale.z * rest->positions[v].z + shift.z};
	plait_error error;
	cr_assert_eq(plait_collider_set_mesh_positions(collider, x, rest->vertex_count, &error), PLAIT_OK, "%s",
	             error.message);
	free(x);
}

static test_mesh floor_mesh(int n, float side)
{
	test_grid grid = test_grid_make(n, n, side, side);
	test_mesh mesh = {grid.positions,    grid.vertex_count, grid.face_sizes,
	                  grid.face_indices, grid.face_count,   4 * grid.face_count};
	return mesh;
}

/* ---- Motion ---------------------------------------------------------------------------------- */

/* 0.5 m per frame at 60 fps: 30 m/s, 0.17 m per substep against particles of radius 0.02. Were
 * the vertices' motion ignored, the floor would jump past the particles and leave them below. */
Test(deforming_collider, rising_floor_carries_resting_particles)
{
	plait_world_id world = make_world(-9.81f, NULL);
	test_mesh floor = floor_mesh(8, 2.0f);
	plait_object_id collider = add_deforming(world, "floor", test_mesh_def(&floor), 0.1f);
	float r = 0.02f;
	plait_object_id dots = add_layer(world, 6, 6, 1.4f, r, r, 0.1f);
	plait_vec3 x[36];
	for (int frame = 1; frame <= 12; ++frame) {
		float height = 0.5f * (float)frame;
		set_shape(collider, &floor, (plait_vec3){1, 1, 1}, (plait_vec3){0, height, 0});
		cr_assert(test_step_frames(world, 1));
		cr_assert_eq(plait_world_get_stats(world).penetrations, 0, "frame %d", frame);
		plait_object_get_positions(dots, 0, 36, x, NULL);
		for (int k = 0; k < 36; ++k) {
			cr_assert_geq(x[k].y, height + r - 1e-3f, "frame %d: particle %d at y = %g, the floor at %g",
			              frame, k, (double)x[k].y, (double)height);
			cr_assert_leq(x[k].y, height + r + 0.05f, "frame %d: particle %d thrown to y = %g", frame, k,
			              (double)x[k].y);
		}
		/* The collider's distance queries see the deformed floor. */
		cr_assert_float_eq(plait_collider_signed_distance(collider, (plait_vec3){0.1f, height + 0.3f, 0.2f}),
		                   0.3f, 1e-4f);
	}
	test_mesh_free(&floor);
	plait_destroy_world(world);
}

Test(deforming_collider, rising_floor_carries_a_cloth)
{
	plait_world_id world = make_world(-9.81f, NULL);
	test_mesh floor = floor_mesh(6, 3.0f);
	plait_object_id collider = add_deforming(world, "floor", test_mesh_def(&floor), 0.1f);
	test_grid grid = test_grid_make(12, 12, 1.0f, 1.0f);
	float thickness = 0.01f;
	for (int v = 0; v < grid.vertex_count; ++v)
		grid.positions[v].y = thickness;
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(&grid);
	cloth.surface.thickness = thickness;
	plait_error error;
	plait_object_id sheet = plait_create_cloth(world, &cloth, &error);
	cr_assert(!plait_object_id_is_null(sheet), "%s", error.message);
	plait_vec3 *x = malloc(sizeof *x * (size_t)grid.vertex_count);
	for (int frame = 1; frame <= 10; ++frame) {
		float height = 0.5f * (float)frame;
		set_shape(collider, &floor, (plait_vec3){1, 1, 1}, (plait_vec3){0, height, 0});
		cr_assert(test_step_frames(world, 1));
		cr_assert_eq(plait_world_get_stats(world).penetrations, 0, "frame %d", frame);
		plait_object_get_positions(sheet, 0, grid.vertex_count, x, NULL);
		for (int v = 0; v < grid.vertex_count; ++v)
			cr_assert_geq(x[v].y, height + thickness - 1e-3f,
			              "frame %d: vertex %d at y = %g, the floor at %g", frame, v, (double)x[v].y,
			              (double)height);
	}
	free(x);
	test_grid_free(&grid);
	test_mesh_free(&floor);
	plait_destroy_world(world);
}

/* A floor sliding sideways at 1.2 m/s takes what rests on it along by friction, as a conveyor
 * belt does: friction acts on the motion relative to the moving surface. */
Test(deforming_collider, sliding_floor_carries_by_friction)
{
	plait_world_id world = make_world(-9.81f, NULL);
	test_mesh floor = floor_mesh(4, 4.0f);
	plait_object_id collider = add_deforming(world, "belt", test_mesh_def(&floor), 1.0f);
	float r = 0.02f;
	plait_object_id dots = add_layer(world, 3, 3, 0.6f, r, r, 1.0f);
	plait_vec3 start[9], x[9];
	plait_object_get_positions(dots, 0, 9, start, NULL);
	int frames = 60;
	for (int frame = 1; frame <= frames; ++frame) {
		set_shape(collider, &floor, (plait_vec3){1, 1, 1}, (plait_vec3){0.02f * (float)frame, 0, 0});
		cr_assert(test_step_frames(world, 1));
	}
	plait_object_get_positions(dots, 0, 9, x, NULL);
	plait_vec3 v[9];
	plait_object_get_velocities(dots, 0, 9, v, NULL);
	for (int k = 0; k < 9; ++k) {
		/* Friction 1 takes 0.12 s to bring it to the belt's speed: it lags by about 7 cm. */
		float moved = x[k].x - start[k].x;
		cr_assert_gt(moved, 1.2f - 0.15f, "particle %d moved %g m with a belt that moved 1.2 m", k,
		             (double)moved);
		cr_assert_lt(moved, 1.2f + 1e-3f, "particle %d moved %g m", k, (double)moved);
		cr_assert_float_eq(v[k].x, 1.2f, 0.05f, "particle %d moves at %g m/s", k, (double)v[k].x);
		cr_assert_float_eq(x[k].y, r, 2e-3f, "particle %d at y = %g", k, (double)x[k].y);
	}
	test_mesh_free(&floor);
	plait_destroy_world(world);
}

static void expect_nothing_inside(plait_world_id world, plait_object_id collider, plait_object_id cloud,
                                  int count, int frame)
{
	cr_assert_eq(plait_world_get_stats(world).penetrations, 0, "frame %d", frame);
	plait_vec3 *x = malloc(sizeof *x * (size_t)count);
	plait_object_get_positions(cloud, 0, count, x, NULL);
	for (int k = 0; k < count; ++k) {
		float d = plait_collider_signed_distance(collider, x[k]);
		cr_assert_geq(d, -1e-3f, "frame %d: particle %d is %g m inside", frame, k, (double)d);
	}
	free(x);
}

/* A sphere growing from 0.1 m to 1 m in 6 frames (9 m/s) through a cloud at rest: every particle
 * it overtakes is pushed out ahead of its surface. */
Test(deforming_collider, inflating_sphere_leaves_no_particle_inside)
{
	plait_world_id world = make_world(0.0f, NULL);
	test_mesh sphere = make_sphere(12, 24);
	plait_object_id ball = add_deforming(world, "ball", test_mesh_def(&sphere), 0.1f);
	set_shape(ball, &sphere, (plait_vec3){0.1f, 0.1f, 0.1f}, (plait_vec3){0, 0, 0});
	cr_assert(test_step_frames(world, 1));
	int n = 8, count = n * n * n;
	plait_object_id cloud = add_cloud(world, n, 0.2f, 0.02f);
	expect_nothing_inside(world, ball, cloud, count, 0);
	for (int frame = 1; frame <= 10; ++frame) {
		float radius = frame < 6 ? 0.1f + 0.15f * (float)frame : 1.0f;
		set_shape(ball, &sphere, (plait_vec3){radius, radius, radius}, (plait_vec3){0, 0, 0});
		cr_assert(test_step_frames(world, 1));
		expect_nothing_inside(world, ball, cloud, count, frame);
	}
	/* Most of the cloud started within 1 m of the centre: it was all pushed out to the surface. */
	plait_vec3 *x = malloc(sizeof *x * (size_t)count);
	plait_object_get_positions(cloud, 0, count, x, NULL);
	for (int k = 0; k < count; ++k)
		cr_assert_geq(sqrtf(x[k].x * x[k].x + x[k].y * x[k].y + x[k].z * x[k].z), 0.97f);
	free(x);
	test_mesh_free(&sphere);
	plait_destroy_world(world);
}

/* A 0.5 m box whose vertices move 1 m a frame (60 m/s, 0.33 m a substep) through a cloud at rest
 * sweeps it along without leaving any particle inside. */
Test(deforming_collider, box_sweeping_fast_through_a_cloud_leaves_no_particle_inside)
{
	plait_world_id world = make_world(0.0f, NULL);
	test_mesh cube = make_cube(0.25f);
	plait_object_id box = add_deforming(world, "box", test_mesh_def(&cube), 0.1f);
	set_shape(box, &cube, (plait_vec3){1, 1, 1}, (plait_vec3){-2.0f, 0, 0});
	cr_assert(test_step_frames(world, 1));
	int n = 5, count = n * n * n;
	plait_object_id cloud = add_cloud(world, n, 0.1f, 0.02f);
	for (int frame = 1; frame <= 6; ++frame) {
		float x = frame < 4 ? -2.0f + (float)frame : 2.0f;
		set_shape(box, &cube, (plait_vec3){1, 1, 1}, (plait_vec3){x, 0, 0});
		cr_assert(test_step_frames(world, 1));
		expect_nothing_inside(world, box, cloud, count, frame);
	}
	/* Everything was swept ahead of the box, which stopped at x = 2 (front face at 2.25). */
	plait_vec3 *p = malloc(sizeof *p * (size_t)count);
	plait_object_get_positions(cloud, 0, count, p, NULL);
	for (int k = 0; k < count; ++k)
		cr_assert_gt(p[k].x, 2.25f, "particle %d left behind at x = %g", k, (double)p[k].x);
	free(p);
	test_mesh_free(&cube);
	plait_destroy_world(world);
}

/* A deforming collider with a keyframed transform on top: the floor rises by its vertices and is
 * carried sideways by its transform. */
Test(deforming_collider, keyframed_transform_applies_on_top)
{
	plait_world_id world = make_world(-9.81f, NULL);
	test_mesh floor = floor_mesh(4, 2.0f);
	plait_object_id collider = add_deforming(world, "floor", test_mesh_def(&floor), 0.1f);
	float r = 0.02f;
	plait_object_id dots = add_layer(world, 1, 1, 0.0f, r, r, 0.1f);
	for (int frame = 1; frame <= 6; ++frame) {
		set_shape(collider, &floor, (plait_vec3){1, 1, 1}, (plait_vec3){0, 0.25f * (float)frame, 0});
		plait_transform t = plait_identity_transform();
		t.translate.y = 0.25f * (float)frame;
		plait_collider_set_transform(collider, t, NULL);
		cr_assert(test_step_frames(world, 1));
	}
	plait_vec3 x;
	plait_object_get_positions(dots, 0, 1, &x, NULL);
	cr_assert_float_eq(x.y, 3.0f + r, 2e-3f, "the particle is at y = %g, the floor at 3", (double)x.y);
	cr_assert_float_eq(plait_collider_signed_distance(collider, (plait_vec3){0, 3.5f, 0}), 0.5f, 1e-4f);
	test_mesh_free(&floor);
	plait_destroy_world(world);
}

/* Results do not depend on the thread count: particles are collided one by one, each on its own. */
static void rising_floor_positions(int threads, plait_vec3 *out, int count)
{
	plait_thread_pool *pool = threads > 1 ? plait_thread_pool_create(threads) : NULL;
	plait_world_id world = make_world(-9.81f, pool);
	test_mesh floor = floor_mesh(16, 3.0f);
	/* A dome rather than a plane: particles see triangles that tilt as they rise. */
	for (int v = 0; v < floor.vertex_count; ++v) {
		plait_vec3 *p = &floor.positions[v];
		p->y = 0.2f * (p->x * p->x + p->z * p->z);
	}
	plait_object_id collider = add_deforming(world, "dome", test_mesh_def(&floor), 0.3f);
	plait_object_id dots = add_layer(world, 50, 50, 2.0f, 1.0f, 0.01f, 0.3f);
	for (int frame = 1; frame <= 8; ++frame) {
		float bulge = 1.0f + 0.3f * (float)frame;
		set_shape(collider, &floor, (plait_vec3){1, bulge, 1}, (plait_vec3){0, 0.2f * (float)frame, 0});
		cr_assert(test_step_frames(world, 1));
	}
	plait_object_get_positions(dots, 0, count, out, NULL);
	test_mesh_free(&floor);
	plait_destroy_world(world);
	plait_thread_pool_destroy(pool);
}

Test(deforming_collider, same_positions_with_1_and_3_threads, .timeout = 300)
{
	int count = 2500;
	plait_vec3 *one = malloc(sizeof *one * (size_t)count), *three = malloc(sizeof *three * (size_t)count);
	rising_floor_positions(1, one, count);
	rising_floor_positions(3, three, count);
	cr_assert(memcmp(one, three, sizeof *one * (size_t)count) == 0, "positions differ with 3 threads");
	free(one);
	free(three);
}

/* ---- The cheap tests before the continuous one ---------------------------------------------- */

static float random_unit(uint32_t *state)
{
	*state = *state * 1664525u + 1013904223u;
	return (float)(*state >> 8) / (float)(1u << 24);
}

static plait_vec3 random_vec(uint32_t *state, float size)
{
	return (plait_vec3){size * (2.0f * random_unit(state) - 1.0f), size * (2.0f * random_unit(state) - 1.0f),
	                    size * (2.0f * random_unit(state) - 1.0f)};
}

static plait_vec3 lerp3(plait_vec3 a, plait_vec3 b, float t)
{
	return (plait_vec3){a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t};
}

static float distance_at(plait_vec3 p0, plait_vec3 p1, const plait_vec3 start[3], const plait_vec3 end[3],
                         float t)
{
	plait_vec3 p = lerp3(p0, p1, t);
	int region;
	plait_vec3 q = plait_closest_point_on_triangle(p, lerp3(start[0], end[0], t), lerp3(start[1], end[1], t),
	                                               lerp3(start[2], end[2], t), &region, NULL);
	return sqrtf((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z));
}

/* When the cheap tests spare the continuous test, nothing is missed: every time the point comes
 * within the radius, it is either carried along (then it ends within the radius plus that
 * distance, where the proximity test at the end finds a crossing) or never that close at all.
 * Checked against 257 samples in time on random motions, half of them carried by the triangle. */
Test(deforming_collider, cheap_tests_before_the_continuous_one_miss_nothing)
{
	uint32_t state = 11u;
	int spared = 0, spared_close = 0;
	for (int query = 0; query < 20000; ++query) {
		float radius = query % 3 == 0 ? 0.01f : query % 3 == 1 ? 0.05f : 0.2f;
		plait_vec3 start[3], end[3], shift = random_vec(&state, 0.5f);
		for (int k = 0; k < 3; ++k) {
			start[k] = random_vec(&state, 1.0f);
			plait_vec3 wobble = random_vec(&state, query % 2 == 0 ? 0.3f * radius : 0.5f);
			end[k] = (plait_vec3){start[k].x + shift.x + wobble.x, start[k].y + shift.y + wobble.y,
			                      start[k].z + shift.z + wobble.z};
		}
		/* Carried queries start near the triangle, the others anywhere around it. */
		plait_vec3 p0 = random_vec(&state, 1.2f);
		if (query % 2 == 0) {
			float u = random_unit(&state), v = random_unit(&state) * (1.0f - u);
			plait_vec3 on = {start[0].x + u * (start[1].x - start[0].x) + v * (start[2].x - start[0].x),
			                 start[0].y + u * (start[1].y - start[0].y) + v * (start[2].y - start[0].y),
			                 start[0].z + u * (start[1].z - start[0].z) + v * (start[2].z - start[0].z)};
			plait_vec3 off = random_vec(&state, 1.5f * radius);
			p0 = (plait_vec3){on.x + off.x, on.y + off.y, on.z + off.z};
		}
		plait_vec3 noise = random_vec(&state, query % 2 == 0 ? 0.3f * radius : 1.0f);
		plait_vec3 p1 = {p0.x + shift.x + noise.x, p0.y + shift.y + noise.y, p0.z + shift.z + noise.z};
		if (plait_moving_triangle_may_touch(p0, p1, start, end, radius))
			continue;
		++spared;
		float end_distance = distance_at(p0, p1, start, end, 1.0f);
		bool close = false;
		for (int k = 0; k <= 256; ++k) {
			float d = distance_at(p0, p1, start, end, (float)k / 256.0f);
			if (d <= radius) {
				close = true;
				cr_assert_lt(end_distance, d + radius * 1.001f,
				             "query %d: within %g at t = %g, ends %g away (radius %g) with no sweep", query,
				             (double)d, k / 256.0, (double)end_distance, (double)radius);
			}
		}
		spared_close += close;
	}
	/* Both kinds of spared queries occur: far apart, and carried along while close. */
	cr_assert_gt(spared, 5000, "only %d of 20000 queries spared", spared);
	cr_assert_gt(spared_close, 500, "only %d spared queries came close", spared_close);
}

/* ---- API errors ------------------------------------------------------------------------------ */

Test(deforming_collider, set_mesh_positions_refuses_bad_input)
{
	plait_world_id world = make_world(0.0f, NULL);
	test_mesh floor = floor_mesh(2, 2.0f); /* 9 vertices */
	plait_object_id collider = add_deforming(world, "floor", test_mesh_def(&floor), 0.1f);
	plait_error error;

	plait_vec3 raised[9];
	for (int v = 0; v < 9; ++v)
		raised[v] = (plait_vec3){floor.positions[v].x, 1.0f, floor.positions[v].z};
	cr_assert_eq(plait_collider_set_mesh_positions(collider, raised, 8, &error),
	             PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect_str_eq(error.message, "'floor': expected 9 mesh positions (one per vertex), got 8");
	cr_assert_eq(plait_collider_set_mesh_positions(collider, NULL, 9, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect_str_eq(error.message,
	                 "'floor': expected 9 mesh positions (one per vertex), got 9 and no array");
	raised[3].y = INFINITY;
	cr_assert_eq(plait_collider_set_mesh_positions(collider, raised, 9, &error),
	             PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect_str_eq(error.message, "'floor': mesh position 3 is not finite (-1, inf, 0)");
	raised[3].y = NAN;
	cr_assert_eq(plait_collider_set_mesh_positions(collider, raised, 9, &error),
	             PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect(strstr(error.message, "'floor': mesh position 3 is not finite") == error.message, "%s",
	          error.message);
	/* A refused call changes nothing: the floor stays at y = 0. */
	cr_assert(test_step_frames(world, 1));
	cr_expect_float_eq(plait_collider_signed_distance(collider, (plait_vec3){0, 0.5f, 0}), 0.5f, 1e-5f);

	/* Rigid colliders, mesh or not, take no positions. */
	plait_collider_def rigid = plait_default_collider_def();
	rigid.name = "stone";
	rigid.shape = PLAIT_SHAPE_MESH;
	rigid.mesh = test_mesh_def(&floor);
	plait_object_id stone = plait_create_collider(world, &rigid, &error);
	cr_assert(!plait_object_id_is_null(stone), "%s", error.message);
	raised[3].y = 1.0f;
	cr_assert_eq(plait_collider_set_mesh_positions(stone, raised, 9, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect_str_eq(error.message,
	                 "'stone' is a rigid collider; only a mesh collider created with deforming "
	                 "= true takes mesh positions");
	plait_collider_def ball = plait_default_collider_def();
	ball.name = "ball";
	ball.shape = PLAIT_SHAPE_SPHERE;
	plait_object_id ball_id = plait_create_collider(world, &ball, NULL);
	cr_assert_eq(plait_collider_set_mesh_positions(ball_id, raised, 9, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect_str_eq(error.message,
	                 "'ball' is a rigid collider; only a mesh collider created with deforming = "
	                 "true takes mesh positions");
	ball.deforming = true;
	cr_assert(plait_object_id_is_null(plait_create_collider(world, &ball, &error)));
	cr_expect_str_eq(error.message, "collider 'ball': only a mesh collider can be deforming");

	/* Not a collider, or no object at all. */
	plait_object_id dots = add_layer(world, 1, 1, 0.0f, 2.0f, 0.02f, 0.1f);
	cr_assert_eq(plait_collider_set_mesh_positions(dots, raised, 9, &error), PLAIT_ERROR_INVALID_ARGUMENT);
	cr_expect_str_eq(error.message, "'dots' is not a collider");
	plait_destroy_object(stone);
	cr_assert_eq(plait_collider_set_mesh_positions(stone, raised, 9, &error), PLAIT_ERROR_INVALID_ID);

	/* A good call moves the floor over the next frame, and it stays where it got to. */
	cr_assert_eq(plait_collider_set_mesh_positions(collider, raised, 9, &error), PLAIT_OK, "%s",
	             error.message);
	cr_expect_float_eq(plait_collider_signed_distance(collider, (plait_vec3){0, 0.5f, 0}), 0.5f, 1e-5f);
	cr_assert(test_step_frames(world, 1));
	cr_expect_float_eq(plait_collider_signed_distance(collider, (plait_vec3){0, 1.5f, 0}), 0.5f, 1e-5f);
	cr_assert(test_step_frames(world, 2));
	cr_expect_float_eq(plait_collider_signed_distance(collider, (plait_vec3){0, 1.5f, 0}), 0.5f, 1e-5f);
	test_mesh_free(&floor);
	plait_destroy_world(world);
}

/* A frame that fails leaves everything where it began, the mesh included. */
Test(deforming_collider, failed_frame_puts_the_mesh_back)
{
	plait_world_id world = make_world(-9.81f, NULL);
	test_mesh floor = floor_mesh(1, 2.0f);
	plait_object_id collider = add_deforming(world, "floor", test_mesh_def(&floor), 0.1f);
	plait_object_id dots = add_layer(world, 1, 1, 0.0f, 0.05f, 0.05f, 0.1f);
	/* Finite, but far beyond what the solver's arithmetic survives: the frame goes non-finite. */
	set_shape(collider, &floor, (plait_vec3){1, 1, 1}, (plait_vec3){0, 3e38f, 0});
	plait_error error;
	cr_assert_eq(plait_world_step(world, &error), PLAIT_ERROR_NONFINITE);
	cr_expect_float_eq(plait_collider_signed_distance(collider, (plait_vec3){0, 0.5f, 0}), 0.5f, 1e-5f);
	plait_vec3 x;
	plait_object_get_positions(dots, 0, 1, &x, NULL);
	cr_expect_float_eq(x.y, 0.05f, 1e-6f);
	cr_assert_eq(plait_world_get_frame(world), 0);
	/* With a sane target the frame goes through, from where the mesh was. */
	set_shape(collider, &floor, (plait_vec3){1, 1, 1}, (plait_vec3){0, 0.5f, 0});
	cr_assert(test_step_frames(world, 1));
	plait_object_get_positions(dots, 0, 1, &x, NULL);
	cr_expect_float_eq(x.y, 0.55f, 2e-3f, "the particle is at y = %g", (double)x.y);
	test_mesh_free(&floor);
	plait_destroy_world(world);
}

/* ---- Scenes ---------------------------------------------------------------------------------- */

static char *make_temp_dir(void)
{
	char *dir = strdup("/tmp/plait_sequence_test_XXXXXX");
	cr_assert_not_null(mkdtemp(dir));
	return dir;
}

static void write_text(const char *dir, const char *name, const char *text)
{
	char path[1024];
	snprintf(path, sizeof path, "%s/%s", dir, name);
	FILE *f = fopen(path, "wb");
	cr_assert_not_null(f, "%s", path);
	fputs(text, f);
	fclose(f);
}

/* A 2 x 2 quad floor (9 vertices, 4 faces) at height y, written as an OBJ file. */
static void write_floor(const char *dir, const char *name, float y)
{
	char text[1024];
	int length = 0;
	for (int j = 0; j <= 2; ++j)
		for (int i = 0; i <= 2; ++i)
			length += snprintf(text + length, sizeof text - (size_t)length, "v %g %g %g\n", (double)(i - 1),
			                   (double)y, (double)(j - 1));
	length +=
	    snprintf(text + length, sizeof text - (size_t)length, "f 1 4 5 2\nf 2 5 6 3\nf 4 7 8 5\nf 5 8 9 6\n");
	write_text(dir, name, text);
}

static void write_floor_frames(const char *dir, int first, int last)
{
	for (int frame = first; frame <= last; ++frame) {
		char name[64];
		snprintf(name, sizeof name, "floor.%04d.obj", frame);
		write_floor(dir, name, 0.5f * (float)frame);
	}
}

static const char *floor_scene =
    "{\"world\": {\"fps\": 60, \"air_density\": 0}, \"frames\": 8, \"objects\": ["
    "{\"name\": \"floor\", \"type\": \"collider\", \"shape\": \"mesh\", "
    "\"mesh\": \"floor.obj\", \"sequence\": \"floor.%04d.obj\"},"
    "{\"name\": \"dots\", \"type\": \"particles\", \"radius\": 0.02,"
    " \"positions\": [[0, 0.02, 0], [0.4, 0.02, -0.3]]}]}";

/* Frames 1 to 5 rise 0.5 m each; from frame 6 the last file's shape holds. A file for frame 0
 * is not read: `mesh` is the shape at frame 0 (here it is not even a mesh). */
Test(deforming_collider, scene_sequence_drives_the_collider)
{
	char *dir = make_temp_dir();
	write_floor(dir, "floor.obj", 0.0f);
	write_floor_frames(dir, 1, 5);
	write_text(dir, "floor.0000.obj", "not a mesh\n");
	plait_scene scene;
	plait_tool_error error;
	cr_assert(plait_scene_load_string(floor_scene, "scene.json", dir, &scene, &error), "%s", error.message);
	cr_assert_eq(scene.objects[0].sequence.frame_count, 5);
	plait_world_id world;
	cr_assert(plait_scene_create_world(&scene, &world, &error), "%s", error.message);
	plait_object_id floor = plait_world_get_object(world, 0), dots = plait_world_get_object(world, 1);
	for (int frame = 1; frame <= 8; ++frame) {
		cr_assert(plait_scene_apply_frame(&scene, world, frame, &error), "%s", error.message);
		cr_assert(test_step_frames(world, 1));
		float height = 0.5f * (float)(frame < 5 ? frame : 5);
		cr_assert_float_eq(plait_collider_signed_distance(floor, (plait_vec3){0, height + 1.0f, 0}), 1.0f,
		                   1e-4f, "frame %d", frame);
		plait_vec3 x[2];
		plait_object_get_positions(dots, 0, 2, x, NULL);
		if (frame <= 5) {
			for (int k = 0; k < 2; ++k)
				cr_assert_float_eq(x[k].y, height + 0.02f, 2e-3f, "frame %d: particle %d at y = %g", frame, k,
				                   (double)x[k].y);
		}
	}
	plait_destroy_world(world);
	plait_scene_free(&scene);
	remove_tree(dir);
	free(dir);
}

/* A sequence is read by vertex order, not by position: a frame may bring vertices together or
 * fold faces flat, which merging or dropping by position would get wrong. */
Test(deforming_collider, scene_sequence_keeps_vertices_that_meet)
{
	char *dir = make_temp_dir();
	write_floor(dir, "floor.obj", 0.0f);
	/* Frame 1: the middle column of vertices moves onto the left one, folding two faces flat. */
	write_text(dir, "floor.0001.obj",
	           "v -1 0 -1\nv -1 0 -1\nv 1 0 -1\nv -1 0 0\nv -1 0 0\nv 1 0 0\nv -1 0 1\nv -1 0 1\nv 1 0 1\n"
	           "f 1 4 5 2\nf 2 5 6 3\nf 4 7 8 5\nf 5 8 9 6\n");
	plait_scene scene;
	plait_tool_error error;
	cr_assert(plait_scene_load_string(floor_scene, "scene.json", dir, &scene, &error), "%s", error.message);
	const plait_vec3 *shape = plait_mesh_sequence_frame(&scene.objects[0].sequence, 1);
	cr_assert_eq(scene.objects[0].vertex_count, 9);
	/* The mesh's vertex v is the same vertex in the frame, wherever it went. */
	for (int v = 0; v < 9; ++v) {
		plait_vec3 rest = scene.objects[0].positions[v];
		float expected_x = rest.x > 0.5f ? 1.0f : -1.0f;
		cr_expect_float_eq(shape[v].x, expected_x, 1e-6f, "vertex %d", v);
		cr_expect_float_eq(shape[v].z, rest.z, 1e-6f, "vertex %d", v);
	}
	plait_scene_free(&scene);
	remove_tree(dir);
	free(dir);
}

static void expect_scene_error(const char *dir, const char *json, const char *expected)
{
	plait_scene scene;
	plait_tool_error error = {{0}};
	bool ok = plait_scene_load_string(json, "scene.json", dir, &scene, &error);
	if (ok)
		plait_scene_free(&scene);
	cr_assert(!ok, "loaded: %s", json);
	cr_expect_str_eq(error.message, expected);
}

static char *scene_with_sequence(const char *shape_keys)
{
	char *json = malloc(1024);
	snprintf(json, 1024,
	         "{\"objects\": [{\"name\": \"floor\", \"type\": \"collider\", %s},"
	         "{\"type\": \"particles\", \"positions\": [[0, 1, 0]]}]}",
	         shape_keys);
	return json;
}

Test(deforming_collider, scene_sequence_errors)
{
	char *dir = make_temp_dir();
	write_floor(dir, "floor.obj", 0.0f);
	write_floor_frames(dir, 1, 2);
	write_floor_frames(dir, 4, 5);
	char expected[1024];

	/* A gap, and no file at all. */
	char *json =
	    scene_with_sequence("\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"floor.%04d.obj\"");
	snprintf(
	    expected, sizeof expected,
	    "scene.json: objects[0].sequence: %s/floor.0003.obj: missing: expected a file for every frame from 1 "
	    "to the sequence's last (5)",
	    dir);
	expect_scene_error(dir, json, expected);
	free(json);
	json = scene_with_sequence("\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"none_%d.obj\"");
	snprintf(
	    expected, sizeof expected,
	    "scene.json: objects[0].sequence: %s/none_1.obj: missing: expected a file for every frame from 1 to "
	    "the sequence's last, found none",
	    dir);
	expect_scene_error(dir, json, expected);
	free(json);
	json = scene_with_sequence(
	    "\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"no_such_folder/floor.%04d.obj\"");
	snprintf(
	    expected, sizeof expected,
	    "scene.json: objects[0].sequence: %s/no_such_folder/floor.0001.obj: cannot open its folder: No such "
	    "file or directory",
	    dir);
	expect_scene_error(dir, json, expected);
	free(json);

	/* Other topology: more vertices and faces, or the same counts joined otherwise. */
	write_floor(dir, "floor.0003.obj", 1.5f);
	write_text(
	    dir, "floor.0004.obj",
	    "v -1 0 -1\nv 0 0 -1\nv 1 0 -1\nv -1 0 0\nv 0 0 0\nv 1 0 0\nv -1 0 1\nv 0 0 1\nv 1 0 1\nv 2 0 1\n"
	    "f 1 4 5 2\nf 2 5 6 3\nf 4 7 8 5\nf 5 8 9 6\nf 6 9 10\n");
	json =
	    scene_with_sequence("\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"floor.%04d.obj\"");
	snprintf(expected, sizeof expected,
	         "scene.json: objects[0].sequence: %s/floor.0004.obj: expected the 9 vertices and 4 faces of "
	         "%s/floor.obj, got 10 vertices and 5 faces",
	         dir, dir);
	expect_scene_error(dir, json, expected);
	write_text(dir, "floor.0004.obj",
	           "v -1 0 -1\nv 0 0 -1\nv 1 0 -1\nv -1 0 0\nv 0 0 0\nv 1 0 0\nv -1 0 1\nv 0 0 1\nv 1 0 1\n"
	           "f 1 4 5 2\nf 2 5 6 3\nf 4 7 8 5\nf 5 6 9 8\n");
	snprintf(
	    expected, sizeof expected,
	    "scene.json: objects[0].sequence: %s/floor.0004.obj: expected the faces of %s/floor.obj over the "
	    "same vertices, got 9 vertices and 4 faces joined differently",
	    dir, dir);
	expect_scene_error(dir, json, expected);

	/* An unreadable file, and a non-finite coordinate: the mesh reader's own messages. */
	write_text(dir, "floor.0004.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 99\n");
	plait_tool_error error = {{0}};
	plait_scene scene;
	cr_assert(!plait_scene_load_string(json, "scene.json", dir, &scene, &error));
	snprintf(expected, sizeof expected,
	         "scene.json: objects[0].sequence: %s/floor.0004.obj: cannot read mesh: ", dir);
	cr_expect(strncmp(error.message, expected, strlen(expected)) == 0, "%s", error.message);
	write_text(dir, "floor.0004.obj",
	           "v -1 0 -1\nv 0 0 -1\nv 1 0 -1\nv -1 0 0\nv 0 nan 0\nv 1 0 0\nv -1 0 1\nv 0 0 1\nv 1 0 1\n"
	           "f 1 4 5 2\nf 2 5 6 3\nf 4 7 8 5\nf 5 8 9 6\n");
	cr_assert(!plait_scene_load_string(json, "scene.json", dir, &scene, &error));
	snprintf(expected, sizeof expected, "scene.json: objects[0].sequence: %s/floor.0004.obj: mesh 0 ", dir);
	cr_expect(strncmp(error.message, expected, strlen(expected)) == 0, "%s", error.message);
	cr_expect(strstr(error.message, "has a non-finite coordinate") != NULL, "%s", error.message);
	free(json);

	/* The key itself. */
	json = scene_with_sequence("\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"floor.obj\"");
	expect_scene_error(
	    dir, json,
	    "scene.json: objects[0].sequence: expected a file path pattern with one frame number, %d or "
	    "%0Nd as in \"arm.%04d.obj\", got \"floor.obj\" (no frame number)");
	free(json);
	json = scene_with_sequence("\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"f%d.%d.obj\"");
	expect_scene_error(
	    dir, json,
	    "scene.json: objects[0].sequence: expected a file path pattern with one frame number, %d or "
	    "%0Nd as in \"arm.%04d.obj\", got \"f%d.%d.obj\" (more than one frame number)");
	free(json);
	json =
	    scene_with_sequence("\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"floor.%s.obj\"");
	expect_scene_error(
	    dir, json,
	    "scene.json: objects[0].sequence: expected a file path pattern with one frame number, %d or "
	    "%0Nd as in \"arm.%04d.obj\", got \"floor.%s.obj\" (%s is not %d or %0Nd)");
	free(json);
	json = scene_with_sequence(
	    "\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": \"f%02d/floor.obj\"");
	expect_scene_error(
	    dir, json,
	    "scene.json: objects[0].sequence: expected a file path pattern with one frame number, %d or "
	    "%0Nd as in \"arm.%04d.obj\", got \"f%02d/floor.obj\" (the frame number is in a folder "
	    "name, not in the file name)");
	free(json);
	json = scene_with_sequence("\"shape\": \"mesh\", \"mesh\": \"floor.obj\", \"sequence\": 4");
	expect_scene_error(
	    dir, json,
	    "scene.json: objects[0].sequence: expected a file path pattern with one frame number, as in "
	    "\"arm.%04d.obj\" (relative to the scene file's folder), got 4");
	free(json);
	json = scene_with_sequence("\"shape\": \"sphere\", \"sequence\": \"floor.%04d.obj\"");
	expect_scene_error(
	    dir, json,
	    "scene.json: objects[0].sequence: not used by a sphere collider (a sphere takes center, "
	    "radius)");
	free(json);
	remove_tree(dir);
	free(dir);
}

/* `plait run` stops with status 1 before writing anything when a sequence file is bad. */
Test(deforming_collider, run_refuses_a_bad_sequence_before_writing)
{
	char *dir = make_temp_dir();
	write_floor(dir, "floor.obj", 0.0f);
	write_floor_frames(dir, 1, 3);
	write_text(dir, "floor.0002.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
	write_text(dir, "scene.json", floor_scene);
	char scene_path[1024], out_dir[1024];
	snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
	snprintf(out_dir, sizeof out_dir, "%s/out", dir);
	const char *argv[] = {"plait", "run", scene_path, "--out", out_dir};
	cli_result result = run_cli(5, argv);
	cr_expect_eq(result.code, 1);
	char expected[4096];
	snprintf(expected, sizeof expected,
	         "%s: objects[0].sequence: %s/floor.0002.obj: expected the 9 vertices and 4 faces of "
	         "%s/floor.obj, got "
	         "3 vertices and 1 face\n",
	         scene_path, dir, dir);
	cr_expect_str_eq(result.err, expected);
	struct stat info;
	cr_expect_neq(stat(out_dir, &info), 0, "the output folder was created");
	free_result(&result);

	/* Fixed, the same scene runs and says so. */
	write_floor(dir, "floor.0002.obj", 1.0f);
	result = run_cli(5, argv);
	cr_expect_eq(result.code, 0, "%s", result.err);
	free_result(&result);
	remove_tree(dir);
	free(dir);
}
