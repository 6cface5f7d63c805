/* hello_cloth: a square of cloth dropped on a sphere that rests on the ground.
 * Prints the kinetic energy of every frame and, at the end, the height of the lowest vertex.
 * Uses only the public API: cc hello_cloth.c $(pkg-config --cflags --libs plait) */
#include <stdio.h>

#include <plait/plait.h>

#define N 30 /* quads along each side of the cloth */
#define VERTICES ((N + 1) * (N + 1))

static plait_vec3 positions[VERTICES];
static int face_sizes[N * N], face_indices[4 * N * N];

/* A 1.6 m square of N x N quads at height 1.2 m, counter-clockwise seen from above. */
static plait_mesh_def make_square(void)
{
	for (int v = 0; v < VERTICES; ++v) {
		float x = (float)(v % (N + 1)) / N, z = (float)(v / (N + 1)) / N;
		positions[v] = (plait_vec3){1.6f * x - 0.8f, 1.2f, 1.6f * z - 0.8f};
	}
	for (int f = 0; f < N * N; ++f) {
		int v = f / N * (N + 1) + f % N, *quad = &face_indices[4 * f];
		face_sizes[f] = 4;
		quad[0] = v, quad[1] = v + N + 1, quad[2] = v + N + 2, quad[3] = v + 1;
	}
	return (plait_mesh_def){positions, VERTICES, face_sizes, N * N, face_indices};
}

static int fail(const plait_error *error)
{
	fprintf(stderr, "hello_cloth: %s: %s\n", plait_result_name(error->code), error->message);
	return 1;
}

int main(void)
{
	plait_error error;
	plait_world_def world_def = plait_default_world_def(); /* 24 fps, 3 substeps, gravity -y */
	plait_world_id world = plait_create_world(&world_def, &error);
	if (plait_world_id_is_null(world)) {
		return fail(&error);
	}
	plait_cloth_def cloth_def = plait_default_cloth_def();
	cloth_def.mesh = make_square();
	cloth_def.surface.friction = 0.3f;
	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.0f, 0.5f, 0.0f};
	sphere.radius = 0.5f;
	plait_collider_def ground = plait_default_collider_def(); /* the plane y = 0, solid below */
	plait_object_id cloth = plait_create_cloth(world, &cloth_def, &error);
	if (plait_object_id_is_null(cloth) ||
	    plait_object_id_is_null(plait_create_collider(world, &sphere, &error)) ||
	    plait_object_id_is_null(plait_create_collider(world, &ground, &error))) {
		return fail(&error);
	}
	for (int frame = 1; frame <= 72; ++frame) { /* three seconds */
		if (plait_world_step(world, &error) != PLAIT_OK) {
			return fail(&error);
		}
		printf("frame %2d  kinetic energy %.6f J\n", frame, plait_world_get_stats(world).kinetic_energy);
	}
	plait_vec3 end[VERTICES];
	if (plait_object_get_positions(cloth, 0, VERTICES, end, &error) != PLAIT_OK) {
		return fail(&error);
	}
	float lowest = end[0].y;
	for (int v = 1; v < VERTICES; ++v) {
		lowest = end[v].y < lowest ? end[v].y : lowest;
	}
	printf("lowest vertex: %.4f m above the ground\n", lowest);
	plait_destroy_world(world);
	return 0;
}
