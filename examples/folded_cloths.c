/* folded_cloths: two self-colliding cloths dropped on each other over a ball, and a rope thrown
 * across them. Shows the collision settings of the API (self_collide, the self-collision flag,
 * collision layers, curve self-collision) and how to check a result: every half second it prints
 * the frame's contacts, continuous-collision hits and failsafe activations, and the intersection
 * check of the current state, which must find nothing. Exits 1 if it ever does. */
#include <stdio.h>
#include <stdlib.h>

#include <plait/plait.h>

#define FRAMES 48
#define N 20 /* vertices per side of each cloth */

/* An n x n sheet of side `size`, flat at height y; arrays are malloc'ed. */
static plait_mesh_def make_sheet(int n, float size, float y, float shift)
{
	plait_vec3 *x = malloc(sizeof *x * (size_t)(n * n));
	int *sizes = malloc(sizeof(int) * (size_t)((n - 1) * (n - 1)));
	int *indices = malloc(sizeof(int) * 4 * (size_t)((n - 1) * (n - 1)));
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i) {
			x[j * n + i] = (plait_vec3){size * ((float)i / (float)(n - 1) - 0.5f) + shift, y,
			                            size * ((float)j / (float)(n - 1) - 0.5f) - shift};
		}
	}
	int f = 0;
	for (int j = 0; j + 1 < n; ++j) {
		for (int i = 0; i + 1 < n; ++i, ++f) {
			int a = j * n + i;
			sizes[f] = 4;
			indices[4 * f + 0] = a;
			indices[4 * f + 1] = a + n;
			indices[4 * f + 2] = a + n + 1;
			indices[4 * f + 3] = a + 1;
		}
	}
	return (plait_mesh_def){x, n * n, sizes, f, indices};
}

static void free_sheet(plait_mesh_def *mesh)
{
	free((void *)mesh->positions);
	free((void *)mesh->face_sizes);
	free((void *)mesh->face_indices);
}

int main(void)
{
	plait_error error;
	plait_world_def world_def = plait_default_world_def();
	world_def.fps = 24.0f;
	plait_world_id world = plait_create_world(&world_def, &error);
	if (plait_world_id_is_null(world)) {
		fprintf(stderr, "folded_cloths: %s\n", error.message);
		return 1;
	}

	plait_collider_def ball = plait_default_collider_def();
	ball.shape = PLAIT_SHAPE_SPHERE;
	ball.center = (plait_vec3){0.0f, 0.35f, 0.0f};
	ball.radius = 0.35f;
	plait_collider_def ground = plait_default_collider_def(); /* the plane y = 0 */
	if (plait_object_id_is_null(plait_create_collider(world, &ball, &error)) ||
	    plait_object_id_is_null(plait_create_collider(world, &ground, &error))) {
		fprintf(stderr, "folded_cloths: %s\n", error.message);
		return 1;
	}

	/* Two cloths that collide with themselves (vertex-triangle and edge-edge, the default flag)
	 * and with each other. The lower one is on a lower collision layer: it pushes the upper
	 * one but is not pushed by it, as an inner garment under an outer one. */
	plait_object_id cloths[2];
	for (int k = 0; k < 2; ++k) {
		plait_mesh_def mesh = make_sheet(N, 1.4f - 0.2f * (float)k, 0.8f + 0.2f * (float)k, 0.03f * (float)k);
		plait_cloth_def cloth = plait_default_cloth_def();
		cloth.name = k == 0 ? "inner" : "outer";
		cloth.mesh = mesh;
		cloth.self_collide = true;
		cloth.self_collision_flag = PLAIT_SELF_COLLIDE_FULL_SURFACE;
		cloth.surface.thickness = 0.01f;
		cloth.surface.friction = 0.4f;
		cloth.surface.collision_layer = k;
		cloths[k] = plait_create_cloth(world, &cloth, &error);
		free_sheet(&mesh);
		if (plait_object_id_is_null(cloths[k])) {
			fprintf(stderr, "folded_cloths: %s\n", error.message);
			return 1;
		}
	}

	/* A rope thrown across both; its segments collide with the cloths and with itself. (On
	 * layer 0 it would be below the outer cloth's layer: the outer cloth, pressed between it
	 * and the inner one and pushed by both, could not give way.) */
	enum { ROPE = 24 };
	plait_vec3 rope_x[ROPE], rope_v[ROPE];
	for (int i = 0; i < ROPE; ++i) {
		rope_x[i] = (plait_vec3){-0.9f + 1.8f * (float)i / (float)(ROPE - 1), 1.4f, 0.1f};
		rope_v[i] = (plait_vec3){0.0f, -2.0f, 0.0f};
	}
	plait_curve_def rope = plait_default_curve_def();
	rope.name = "rope";
	rope.positions = rope_x;
	rope.velocities = rope_v;
	rope.vertex_count = ROPE;
	rope.mass = 0.02f;
	rope.self_collide = true;
	rope.surface.thickness = 0.008f;
	rope.surface.collision_layer = 2; /* on top of both: it pushes them, they do not push it */
	if (plait_object_id_is_null(plait_create_curve(world, &rope, &error))) {
		fprintf(stderr, "folded_cloths: %s\n", error.message);
		return 1;
	}

	int failures = 0;
	for (int frame = 1; frame <= FRAMES; ++frame) {
		if (plait_world_step(world, &error) != PLAIT_OK) {
			fprintf(stderr, "folded_cloths: frame %d: %s\n", frame, error.message);
			return 1;
		}
		plait_intersection_report report;
		if (plait_world_check_intersections(world, &report, &error) != PLAIT_OK) {
			fprintf(stderr, "folded_cloths: %s\n", error.message);
			return 1;
		}
		failures += report.triangle_pairs > 0 || report.inside_colliders > 0;
		if (frame % 12 == 0) {
			plait_frame_stats stats = plait_world_get_stats(world);
			printf("t = %.1f s: %5d contacts, %4d ccd hits, %3d failsafe, %.1f ms in collisions; "
			       "%d crossing triangle pairs, %d vertices inside colliders\n",
			       (double)frame / world_def.fps, stats.contacts, stats.ccd_hits, stats.failsafe,
			       stats.collision_ms, report.triangle_pairs, report.inside_colliders);
		}
	}
	plait_destroy_world(world);
	if (failures > 0) {
		fprintf(stderr, "folded_cloths: %d frames with crossings or vertices inside colliders\n", failures);
		return 1;
	}
	return 0;
}
