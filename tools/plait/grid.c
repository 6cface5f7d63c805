#include "grid.h"

#include <math.h>
#include <stdlib.h>

plait_grid_def plait_default_grid_def(void)
{
	plait_grid_def def = {0};
	def.normal = (plait_vec3){0.0f, 1.0f, 0.0f};
	return def;
}

// Rows of the rotation taking +Y to n (unit length), by Rodrigues' formula.
static void plait_grid_rotation(plait_vec3 n, float r[3][3])
{
	if (n.y < -0.9999f) {
		// Opposite to +Y the smallest rotation is not unique: pick half a turn about X.
		float flip[3][3] = {{1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
		for (int i = 0; i < 3; ++i)
			for (int j = 0; j < 3; ++j)
				r[i][j] = flip[i][j];
		return;
	}
	// v = Y x n, c = Y . n; R = I + [v]x + [v]x^2 / (1 + c).
	float vx = n.z, vy = 0.0f, vz = -n.x, c = n.y;
	float k = 1.0f / (1.0f + c);
	float cross[3][3] = {{0, -vz, vy}, {vz, 0, -vx}, {-vy, vx, 0}};
	for (int i = 0; i < 3; ++i) {
		for (int j = 0; j < 3; ++j) {
			float square = 0.0f;
			for (int m = 0; m < 3; ++m)
				square += cross[i][m] * cross[m][j];
			r[i][j] = (i == j ? 1.0f : 0.0f) + cross[i][j] + square * k;
		}
	}
}

bool plait_grid_build(const plait_grid_def *def, plait_soup *soup)
{
	*soup = (plait_soup){0};
	int nx = def->nx, ny = def->ny;
	int vertex_count = (nx + 1) * (ny + 1);
	int face_count = nx * ny;
	soup->positions = malloc(sizeof(plait_vec3) * (size_t)vertex_count);
	soup->face_sizes = malloc(sizeof(int) * (size_t)face_count);
	soup->face_indices = malloc(sizeof(int) * 4 * (size_t)face_count);
	if (soup->positions == NULL || soup->face_sizes == NULL || soup->face_indices == NULL) {
		plait_soup_free(soup);
		return false;
	}
	plait_vec3 n = def->normal;
	float length = sqrtf(n.x * n.x + n.y * n.y + n.z * n.z);
	n = (plait_vec3){n.x / length, n.y / length, n.z / length};
	float r[3][3];
	plait_grid_rotation(n, r);
	for (int j = 0; j <= ny; ++j) {
		for (int i = 0; i <= nx; ++i) {
			float u = def->width * ((float)i / (float)nx - 0.5f);
			float w = def->height * ((float)j / (float)ny - 0.5f);
			// Local point (u, 0, w), rotated, then placed at the center.
			plait_vec3 p = {def->center.x + r[0][0] * u + r[0][2] * w,
			                def->center.y + r[1][0] * u + r[1][2] * w,
			                def->center.z + r[2][0] * u + r[2][2] * w};
			soup->positions[j * (nx + 1) + i] = p;
		}
	}
	int f = 0;
	for (int j = 0; j < ny; ++j) {
		for (int i = 0; i < nx; ++i) {
			int a = j * (nx + 1) + i;
			soup->face_sizes[f] = 4;
			// (i,j), (i,j+1), (i+1,j+1), (i+1,j): counter-clockwise seen from +Y.
			soup->face_indices[4 * f + 0] = a;
			soup->face_indices[4 * f + 1] = a + nx + 1;
			soup->face_indices[4 * f + 2] = a + nx + 2;
			soup->face_indices[4 * f + 3] = a + 1;
			++f;
		}
	}
	soup->vertex_count = vertex_count;
	soup->face_count = face_count;
	soup->index_count = 4 * face_count;
	return true;
}
