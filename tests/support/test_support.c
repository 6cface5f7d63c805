#include "test_support.h"

#include <stdio.h>
#include <stdlib.h>

test_grid test_grid_make(int nx, int ny, float w, float h)
{
	test_grid grid = {0};
	grid.vertex_count = (nx + 1) * (ny + 1);
	grid.face_count = nx * ny;
	grid.positions = malloc(sizeof(plait_vec3) * (size_t)grid.vertex_count);
	grid.face_sizes = malloc(sizeof(int) * (size_t)grid.face_count);
	grid.face_indices = malloc(sizeof(int) * 4 * (size_t)grid.face_count);
	for (int j = 0; j <= ny; ++j) {
		for (int i = 0; i <= nx; ++i) {
			plait_vec3 p = {-0.5f * w + w * (float)i / (float)nx, 0.0f, -0.5f * h + h * (float)j / (float)ny};
			grid.positions[j * (nx + 1) + i] = p;
		}
	}
	int f = 0;
	for (int j = 0; j < ny; ++j) {
		for (int i = 0; i < nx; ++i) {
			int a = j * (nx + 1) + i;
			grid.face_sizes[f] = 4;
			grid.face_indices[4 * f + 0] = a;
			grid.face_indices[4 * f + 1] = a + nx + 1;
			grid.face_indices[4 * f + 2] = a + nx + 2;
			grid.face_indices[4 * f + 3] = a + 1;
			++f;
		}
	}
	return grid;
}

void test_grid_free(test_grid *grid)
{
	free(grid->positions);
	free(grid->face_sizes);
	free(grid->face_indices);
	*grid = (test_grid){0};
}

plait_mesh_def test_grid_mesh(const test_grid *grid)
{
	plait_mesh_def mesh = {grid->positions, grid->vertex_count, grid->face_sizes, grid->face_count,
	                       grid->face_indices};
	return mesh;
}

bool test_step_frames(plait_world_id world, int n)
{
	for (int i = 0; i < n; ++i) {
		plait_error error = {0};
		if (plait_world_step(world, &error) != PLAIT_OK) {
			fprintf(stderr, "step failed: %s\n", error.message);
			return false;
		}
	}
	return true;
}

uint32_t test_random(uint32_t *state)
{
	uint32_t x = *state;
	x ^= x << 13;
	x ^= x >> 17;
	x ^= x << 5;
	return *state = x;
}

float test_uniform(uint32_t *state, float low, float high)
{
	return low + (high - low) * (float)(test_random(state) & 0xFFFFFF) / (float)0xFFFFFF;
}
