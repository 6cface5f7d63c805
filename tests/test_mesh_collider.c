/* Triangle-mesh colliders: cloth does not pass through a tessellated sphere, a fast particle
 * does not tunnel through a single thin triangle, a keyframed mesh pushes what it meets, and a
 * mesh file in a scene becomes a collider. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "scene.h"
#include "test_support.h"

/* An icosphere-like ball: an octahedron subdivided `levels` times, pushed onto the sphere. */
typedef struct ball_mesh {
	plait_vec3 *positions;
	int vertex_count;
	int *sizes, *indices;
	int face_count;
} ball_mesh;

static int midpoint(ball_mesh *b, int capacity, int (*cache)[3], int *cache_count, int u, int v)
{
	int a = u < v ? u : v, c = u < v ? v : u;
	for (int k = 0; k < *cache_count; ++k) {
		if (cache[k][0] == a && cache[k][1] == c) {
			return cache[k][2];
		}
	}
	cr_assert_lt(b->vertex_count, capacity);
	plait_vec3 p = {0.5f * (b->positions[a].x + b->positions[c].x),
	                0.5f * (b->positions[a].y + b->positions[c].y),
	                0.5f * (b->positions[a].z + b->positions[c].z)};
	float length = sqrtf(p.x * p.x + p.y * p.y + p.z * p.z);
	b->positions[b->vertex_count] = (plait_vec3){p.x / length, p.y / length, p.z / length};
	cache[*cache_count][0] = a;
	cache[*cache_count][1] = c;
	cache[*cache_count][2] = b->vertex_count;
	++*cache_count;
	return b->vertex_count++;
}

static ball_mesh make_ball(int levels, float radius, plait_vec3 centre)
{
	int capacity = 8000;
	ball_mesh b = {0};
	b.positions = malloc(sizeof *b.positions * (size_t)capacity);
	int *faces = malloc(sizeof(int) * 3 * 20000), count = 8;
	plait_vec3 start[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
	memcpy(b.positions, start, sizeof start);
	b.vertex_count = 6;
	int octahedron[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
	                        {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
	memcpy(faces, octahedron, sizeof octahedron);
	int(*cache)[3] = malloc(sizeof *cache * 20000);
	for (int level = 0; level < levels; ++level) {
		int cache_count = 0;
		int *next = malloc(sizeof(int) * 3 * 20000), next_count = 0;
		for (int f = 0; f < count; ++f) {
			int a = faces[3 * f], bb = faces[3 * f + 1], c = faces[3 * f + 2];
			int ab = midpoint(&b, capacity, cache, &cache_count, a, bb);
			int bc = midpoint(&b, capacity, cache, &cache_count, bb, c);
			int ca = midpoint(&b, capacity, cache, &cache_count, c, a);
			int tris[4][3] = {{a, ab, ca}, {ab, bb, bc}, {ca, bc, c}, {ab, bc, ca}};
			memcpy(next + 3 * next_count, tris, sizeof tris);
			next_count += 4;
		}
		free(faces);
		faces = next;
		count = next_count;
	}
	free(cache);
	for (int v = 0; v < b.vertex_count; ++v) {
		b.positions[v] =
		    (plait_vec3){centre.x + radius * b.positions[v].x, centre.y + radius * b.positions[v].y,
		                 centre.z + radius * b.positions[v].z};
	}
	b.face_count = count;
	b.indices = faces;
	b.sizes = malloc(sizeof(int) * (size_t)count);
	for (int f = 0; f < count; ++f) {
		b.sizes[f] = 3;
	}
	return b;
}

static void free_ball(ball_mesh *b)
{
	free(b->positions);
	free(b->sizes);
	free(b->indices);
}

Test(mesh_collider, cloth_drapes_over_a_tessellated_sphere_without_passing_through, .timeout = 300)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	ball_mesh ball = make_ball(4, 0.5f, (plait_vec3){0, 0.5f, 0}); /* 2,048 triangles */
	plait_collider_def collider = plait_default_collider_def();
	collider.name = "ball";
	collider.shape = PLAIT_SHAPE_MESH;
	collider.mesh =
	    (plait_mesh_def){ball.positions, ball.vertex_count, ball.sizes, ball.face_count, ball.indices};
	plait_error error;
	plait_object_id ball_id = plait_create_collider(world, &collider, &error);
	cr_assert(!plait_object_id_is_null(ball_id), "%s", error.message);
	plait_collider_def ground = plait_default_collider_def();
	plait_create_collider(world, &ground, NULL);
	test_grid grid = test_grid_make(24, 24, 1.6f, 1.6f);
	for (int i = 0; i < grid.vertex_count; ++i) {
		grid.positions[i].y = 1.3f;
	}
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(&grid);
	cloth.surface.thickness = 0.01f;
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
	cr_assert(!plait_object_id_is_null(cloth_id), "%s", error.message);
	plait_vec3 *x = malloc(sizeof *x * (size_t)grid.vertex_count);
	float lowest_over_ball = INFINITY;
	for (int frame = 0; frame < 72; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_object_get_positions(cloth_id, 0, grid.vertex_count, x, NULL);
		for (int v = 0; v < grid.vertex_count; ++v) {
			float d = plait_collider_signed_distance(ball_id, x[v]);
			cr_assert_geq(d, -1e-3f, "frame %d: vertex %d is %g m inside the ball", frame, v, (double)d);
			if (fabsf(x[v].x) < 0.05f && fabsf(x[v].z) < 0.05f) {
				lowest_over_ball = fminf(lowest_over_ball, x[v].y);
			}
		}
	}
	/* The cloth rests on the ball's top (1.0 m) at its thickness, not on the ground. */
	cr_assert_gt(lowest_over_ball, 0.95f, "the middle of the cloth sank to %g m", (double)lowest_over_ball);
	free(x);
	test_grid_free(&grid);
	free_ball(&ball);
	plait_destroy_world(world);
}

Test(mesh_collider, fast_particle_does_not_tunnel_through_one_thin_triangle)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.gravity = (plait_vec3){0, 0, 0};
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_vec3 corners[3] = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
	int sizes[1] = {3}, indices[3] = {0, 1, 2};
	plait_collider_def collider = plait_default_collider_def();
	collider.shape = PLAIT_SHAPE_MESH;
	collider.mesh = (plait_mesh_def){corners, 3, sizes, 1, indices};
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &collider, NULL)));
	/* 1000 m/s along +z, starting 2 m in front: it crosses the plane z = 0 within a substep. */
	plait_vec3 x = {0.1f, 0.0f, -2.0f}, v = {0.0f, 0.0f, 1000.0f};
	plait_particles_def particles = plait_default_particles_def();
	particles.positions = &x;
	particles.velocities = &v;
	particles.count = 1;
	particles.radius = 0.001f;
	plait_object_id p = plait_create_particles(world, &particles, NULL);
	cr_assert(test_step_frames(world, 3));
	plait_vec3 out;
	plait_object_get_positions(p, 0, 1, &out, NULL);
	cr_assert_lt(out.z, 0.0f, "the particle tunnelled to z = %g", (double)out.z);
	plait_destroy_world(world);
}

Test(mesh_collider, keyframed_mesh_pushes_a_particle)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.gravity = (plait_vec3){0, 0, 0};
	wdef.air_density = 0.0f;
	plait_world_id world = plait_create_world(&wdef, NULL);
	/* A square wall in the plane x = 0, moved along +x by keyframes. */
	plait_vec3 corners[4] = {{0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1}};
	int sizes[1] = {4}, indices[4] = {0, 1, 2, 3};
	plait_collider_def collider = plait_default_collider_def();
	collider.shape = PLAIT_SHAPE_MESH;
	collider.mesh = (plait_mesh_def){corners, 4, sizes, 1, indices};
	collider.transform.translate.x = -0.5f;
	plait_object_id wall = plait_create_collider(world, &collider, NULL);
	plait_vec3 x = {0.0f, 0.0f, 0.0f};
	plait_particles_def particles = plait_default_particles_def();
	particles.positions = &x;
	particles.count = 1;
	particles.radius = 0.02f;
	plait_object_id p = plait_create_particles(world, &particles, NULL);
	for (int frame = 1; frame <= 10; ++frame) {
		plait_transform t = plait_identity_transform();
		t.translate.x = -0.5f + 0.15f * (float)frame;
		plait_collider_set_transform(wall, t, NULL);
		cr_assert(test_step_frames(world, 1));
	}
	plait_vec3 out;
	plait_object_get_positions(p, 0, 1, &out, NULL);
	cr_assert_geq(out.x, 1.0f + 0.02f - 1e-3f, "particle left behind at x = %g", (double)out.x);
	plait_destroy_world(world);
}

Test(mesh_collider, bad_meshes_are_rejected)
{
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_vec3 corners[3] = {{0, 0, 0}, {1, 0, 0}, {0, NAN, 0}};
	int sizes[1] = {3}, indices[3] = {0, 1, 2};
	plait_collider_def collider = plait_default_collider_def();
	collider.name = "wall";
	collider.shape = PLAIT_SHAPE_MESH;
	collider.mesh = (plait_mesh_def){corners, 3, sizes, 1, indices};
	plait_error error;
	cr_assert(plait_object_id_is_null(plait_create_collider(world, &collider, &error)));
	cr_assert(strstr(error.message, "collider 'wall': mesh vertex 2 is not finite") != NULL, "%s",
	          error.message);
	corners[2].y = 1.0f;
	indices[2] = 9;
	cr_assert(plait_object_id_is_null(plait_create_collider(world, &collider, &error)));
	cr_assert(strstr(error.message, "vertex index 9") != NULL, "%s", error.message);
	cr_assert_eq(plait_world_get_object_count(world), 0);
	plait_destroy_world(world);
}

Test(mesh_collider, scene_mesh_file_becomes_a_collider)
{
	const char *json =
	    "{\"frames\": 24, \"objects\": ["
	    "{\"name\": \"floor\", \"type\": \"collider\", \"shape\": \"mesh\", \"mesh\": \"floor_quad.obj\"},"
	    "{\"name\": \"dots\", \"type\": \"particles\", \"positions\": [[0, 0.5, 0], [0.2, 0.8, 0.1]],"
	    " \"radius\": 0.02}]}";
	plait_scene scene;
	plait_tool_error error;
	cr_assert(plait_scene_load_string(json, "scene.json", PLAIT_SOURCE_DIR "/tests/data", &scene, &error),
	          "%s", error.message);
	plait_world_id world;
	cr_assert(plait_scene_create_world(&scene, &world, &error), "%s", error.message);
	cr_assert(test_step_frames(world, 48));
	plait_object_id dots = plait_world_get_object(world, 1);
	plait_vec3 x[2];
	plait_object_get_positions(dots, 0, 2, x, NULL);
	for (int k = 0; k < 2; ++k) {
		cr_assert_float_eq(x[k].y, 0.02f, 2e-3f, "particle %d rests at y = %g", k, (double)x[k].y);
	}
	plait_destroy_world(world);
	plait_scene_free(&scene);
}

Test(mesh_collider, fast_particle_over_a_fine_mesh_finds_the_triangle_it_crosses)
{
	/* 300 x 300 quads: an oblique fast path overlaps thousands of candidate triangles. */
	int n = 300, vertex_count = (n + 1) * (n + 1);
	plait_vec3 *v = malloc(sizeof *v * (size_t)vertex_count);
	int *sizes = malloc(sizeof(int) * (size_t)(n * n)), *indices = malloc(sizeof(int) * 4 * (size_t)(n * n));
	for (int j = 0; j <= n; ++j) {
		for (int i = 0; i <= n; ++i) {
			v[j * (n + 1) + i] =
			    (plait_vec3){-1.0f + 4.0f * (float)i / (float)n, 0.0f, -1.0f + 3.0f * (float)j / (float)n};
		}
	}
	for (int f = 0, j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i, ++f) {
			int a = j * (n + 1) + i;
			sizes[f] = 4;
			int quad[4] = {a, a + n + 1, a + n + 2, a + 1};
			memcpy(indices + 4 * f, quad, sizeof quad);
		}
	}
	plait_world_def wdef = plait_default_world_def();
	wdef.gravity = (plait_vec3){0, 0, 0};
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def collider = plait_default_collider_def();
	collider.shape = PLAIT_SHAPE_MESH;
	collider.mesh = (plait_mesh_def){v, vertex_count, sizes, n * n, indices};
	plait_error error;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &collider, &error)), "%s", error.message);
	plait_vec3 x = {0.0f, 0.2f, 0.5f}, velocity = {30.0f, -30.0f, 0.0f};
	plait_particles_def particles = plait_default_particles_def();
	particles.positions = &x;
	particles.velocities = &velocity;
	particles.count = 1;
	plait_object_id p = plait_create_particles(world, &particles, NULL);
	cr_assert(test_step_frames(world, 1));
	plait_object_get_positions(p, 0, 1, &x, NULL);
	cr_assert_geq(x.y, 0.0f, "the particle went through the mesh to y = %g", (double)x.y);
	plait_destroy_world(world);
	free(v);
	free(sizes);
	free(indices);
}

Test(mesh_collider, signed_distance_is_right_beyond_sharp_edges)
{
	/* A closed, outward-facing tetrahedron: points outside are positive, inside negative, also
	 * where the nearest point is an edge or a corner. */
	plait_vec3 corners[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
	int sizes[4] = {3, 3, 3, 3};
	int indices[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	plait_collider_def collider = plait_default_collider_def();
	collider.shape = PLAIT_SHAPE_MESH;
	collider.mesh = (plait_mesh_def){corners, 4, sizes, 4, indices};
	plait_object_id id = plait_create_collider(world, &collider, NULL);
	uint32_t state = 7u;
	int wrong = 0;
	for (int k = 0; k < 20000; ++k) {
		float c[3];
		for (int axis = 0; axis < 3; ++axis) {
			state = state * 1664525u + 1013904223u;
			c[axis] = -1.0f + 3.0f * (float)(state >> 8) / (float)(1u << 24);
		}
		plait_vec3 point = {c[0], c[1], c[2]};
		bool inside = c[0] > 0.0f && c[1] > 0.0f && c[2] > 0.0f && c[0] + c[1] + c[2] < 1.0f;
		float d = plait_collider_signed_distance(id, point);
		if (fabsf(d) > 1e-4f && (d < 0.0f) != inside) {
			++wrong;
		}
	}
	cr_assert_eq(wrong, 0, "%d of 20000 points got the wrong sign", wrong);
	plait_destroy_world(world);
}
