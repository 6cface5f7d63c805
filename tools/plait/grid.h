/* Rectangular cloth grids described in scene files. */
#ifndef PLAIT_GRID_H
#define PLAIT_GRID_H

#include "soup.h"

#include <stdbool.h>

typedef struct plait_grid_def {
	float width, height; /* metres (scene units) along the grid's two in-plane axes */
	int nx, ny;          /* quads along each axis */
	plait_vec3 center;
	plait_vec3 normal; /* non-zero; need not be normalised */
} plait_grid_def;

/* center [0, 0, 0], normal +Y; size and resolution have no default. */
plait_grid_def plait_default_grid_def(void);

/* Builds (nx+1)*(ny+1) vertices and nx*ny quads; vertex (i, j) has index j*(nx+1)+i. For
 * normal +Y, i runs along +X and j along +Z; other normals rotate that layout by the smallest
 * rotation taking +Y to the normal (-Y: half a turn about X). Quads wind counter-clockwise
 * seen from the normal side. Returns false only when out of memory. */
bool plait_grid_build(const plait_grid_def *def, plait_soup *soup);

#endif
