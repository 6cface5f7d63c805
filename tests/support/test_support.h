/* Small helpers shared by the tests: building worlds and meshes without repeating setup. */
#ifndef PLAIT_TEST_SUPPORT_H
#define PLAIT_TEST_SUPPORT_H

#include <stdint.h>

#include <plait/plait.h>

/* A grid of nx*ny quads, (nx+1)*(ny+1) vertices, in the XZ plane centred at the origin with
 * size w (x) by h (z), vertex (i, j) at index j*(nx+1)+i. Arrays are malloc'ed. */
typedef struct test_grid {
	plait_vec3 *positions;
	int vertex_count;
	int *face_sizes;
	int *face_indices;
	int face_count;
} test_grid;

test_grid test_grid_make(int nx, int ny, float w, float h);
void test_grid_free(test_grid *grid);
plait_mesh_def test_grid_mesh(const test_grid *grid);

/* Deterministic random numbers (xorshift), so a failure can be replayed: the next number of
 * *state (which must not start at 0), and a uniform float in [low, high]. */
uint32_t test_random(uint32_t *state);
float test_uniform(uint32_t *state, float low, float high);

/* Steps the world n frames; returns false (and prints the message) on the first failure. */
bool test_step_frames(plait_world_id world, int n);

#endif
