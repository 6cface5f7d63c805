/* Triangle-mesh colliders (nRigid from a mesh): the triangles in the collider's shape space and
 * a bounding volume hierarchy (axis-aligned boxes) over them. A rigid collider moves by its
 * keyframed transform only, so its hierarchy is built once and never refitted: particles are
 * brought into shape space instead. A deforming one also moves its vertices: every substep they
 * go on straight lines from start to end positions, and the boxes are refitted to cover each
 * triangle's sweep (the topology, and so the tree, never changes). */
#ifndef PLAIT_COLLISION_MESH_SHAPE_H
#define PLAIT_COLLISION_MESH_SHAPE_H

#include "core/alloc.h"
#include "core/math.h"

typedef struct plait_bvh_node {
	vec3 lower, upper;
	int first; /* leaf: first entry in triangle_order; inner: left child (right is left + 1) */
	int count; /* leaf: triangle count; inner: 0 */
} plait_bvh_node;

typedef struct plait_mesh_shape {
	int vertex_count;
	vec3 *positions;
	int triangle_count;
	int (*triangles)[3];
	vec3 *normals; /* unit normal of each triangle (zero for a degenerate one) */
	int node_count;
	plait_bvh_node *nodes;
	int *triangle_order; /* slot k of the leaves holds triangle triangle_order[k] */
	/* Per slot, in leaf order so that a leaf's triangles are read without going through their
	 * vertex indices: the triangle's corners (slot_corners[3k .. 3k + 2], at positions) and its
	 * box (over its sweep when deforming). Kept with positions by build and deform. */
	vec3 *slot_corners;
	vec3 *slot_lower, *slot_upper;
	/* Deforming meshes only (NULL when rigid): vertex positions at the start of the current
	 * substep, positions holding those at its end. Normals are those at the end. */
	vec3 *start_positions;
	float largest_move; /* the longest vertex move over the substep (0 when rigid) */
	/* Closed: every edge is shared by exactly two triangles, so the mesh has an inside. Then
	 * outward is +1 when the triangles' normals point out of it (positive enclosed volume),
	 * -1 when they point in. 0 for an open mesh. */
	bool closed;
	float outward;
} plait_mesh_shape;

/* Whether every edge of the triangles is shared by exactly two of them. */
bool plait_triangles_are_closed(const int (*triangles)[3], int triangle_count,
                                const plait_allocator *allocator);

/* Copies positions and fans the faces into triangles; builds the hierarchy. */
plait_result plait_mesh_shape_build(plait_mesh_shape *shape, const plait_allocator *allocator,
                                    const plait_mesh_def *mesh, plait_error *error);
void plait_mesh_shape_destroy(plait_mesh_shape *shape, const plait_allocator *allocator);

/* Makes a built shape deforming (its vertices start at rest, where they were built). */
plait_result plait_mesh_shape_make_deforming(plait_mesh_shape *shape, const plait_allocator *allocator,
                                             plait_error *error);

/* Places the vertices of a deforming shape for the substep [t0, t1] of a frame in which vertex
 * v goes from from[v] to to[v] linearly; updates the normals and refits the boxes. */
void plait_mesh_shape_deform(plait_mesh_shape *shape, const vec3 *from, const vec3 *to, float t0, float t1);

/* Calls visit(triangle, context) for every triangle whose node box (and, with
 * test_triangles, whose own box: over its sweep when deforming) overlaps [lower, upper],
 * however many there are. */
typedef void plait_triangle_visitor(int triangle, void *context);
void plait_mesh_shape_visit(const plait_mesh_shape *shape, vec3 lower, vec3 upper, bool test_triangles,
                            plait_triangle_visitor *visit, void *context);
/* Whether any triangle's own box (over its sweep when deforming) overlaps [lower, upper]: the
 * test plait_mesh_shape_visit makes, stopping at the first. */
bool plait_mesh_shape_any(const plait_mesh_shape *shape, vec3 lower, vec3 upper);

/* The point of triangle (a, b, c) closest to p; *region is 0 inside the face, 1 on an edge or
 * corner; weights (may be NULL) receive its barycentric coordinates. */
vec3 plait_closest_point_on_triangle(vec3 p, vec3 a, vec3 b, vec3 c, int *region, float weights[3]);

/* Distance from p to the mesh, signed by the nearest triangle's normal (negative behind it),
 * and that normal (outward when the mesh is closed and consistently oriented). */
float plait_mesh_shape_distance(const plait_mesh_shape *shape, vec3 p, vec3 *normal);

#endif
