/* A polygon soup owned by the tool: what grids and mesh files turn into before becoming a cloth. */
#ifndef PLAIT_SOUP_H
#define PLAIT_SOUP_H

#include <plait/plait.h>

typedef struct plait_soup {
	plait_vec3 *positions;
	int vertex_count;
	int *face_sizes; /* vertices per face, >= 3 */
	int face_count;
	int *face_indices; /* 0-based, faces back to back */
	int index_count;
} plait_soup;

void plait_soup_free(plait_soup *soup);

#endif
