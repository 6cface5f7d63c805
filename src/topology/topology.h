/* The simplicial complex of one object, built from a polygon soup (paper §3). Ints only: the
 * topology knows nothing of positions. Vertices are 0-simplices, edges 1-simplices,
 * triangles 2-simplices; each simplex knows its children (the simplices of one dimension
 * lower on its border) and, for edges, its parent triangles. */
#ifndef PLAIT_TOPOLOGY_H
#define PLAIT_TOPOLOGY_H

#include <stdint.h>

#include "core/alloc.h"

enum {
	/* An edge on the border of an input polygon: a structural (stretch) edge. */
	PLAIT_EDGE_POLYGON = 1,
	/* An edge added inside a polygon when it was fanned into triangles. */
	PLAIT_EDGE_DIAGONAL = 2,
};

typedef struct plait_topology {
	int vertex_count;

	/* Input polygons, kept for writing meshes (quads stay quads). */
	int polygon_count;
	int *polygon_sizes;
	int *polygon_starts;
	int *polygon_indices;
	int polygon_index_count;

	/* Triangles, oriented as the input polygon; a polygon (a,b,c,d,...) is fanned from a. */
	int triangle_count;
	int (*triangles)[3];
	int *triangle_polygon;    /* the polygon each triangle came from */
	int (*triangle_edges)[3]; /* children: edge k joins corners k and k+1 */

	/* Edges with vertex[0] < vertex[1] (lexicographic order, paper §3). */
	int edge_count;
	int (*edges)[2];
	uint8_t *edge_flags;      /* PLAIT_EDGE_* */
	int (*edge_triangles)[2]; /* first two parent triangles, -1 when absent */
	int *edge_triangle_count; /* all parents: 1 = border, 2 = interior, >2 = non-manifold */

	int *vertex_valence; /* parent edges of each vertex */
} plait_topology;

/* Builds the complex. Fails (returning PLAIT_ERROR_INVALID_MESH with a message) on a face with
 * fewer than 3 vertices, an index out of range, or a face that repeats a vertex. */
plait_result plait_topology_build(plait_topology *topology, const plait_allocator *allocator,
                                  int vertex_count, const int *face_sizes, int face_count,
                                  const int *face_indices, plait_error *error);
void plait_topology_destroy(plait_topology *topology, const plait_allocator *allocator);

/* The edge joining a and b, or -1. Binary search: edges are sorted. */
int plait_topology_find_edge(const plait_topology *topology, int a, int b);

/* Number of border edges (edges with one parent triangle). */
int plait_topology_border_edge_count(const plait_topology *topology);

/* One edge of a triangle: edge low-high (low < high) is the triangle's corner `corner` to
 * corner + 1. `triangle` is the caller's number for it (a triangle, or an element holding
 * one). Sorted by edge, then triangle and corner, the triangles sharing an edge come together in
 * a fixed order: how neighbours and edge owners are found from a list of triangles. */
typedef struct plait_triangle_edge {
	int low, high, triangle, corner;
} plait_triangle_edge;

void plait_sort_triangle_edges(plait_triangle_edge *edges, int count);

#endif
