/* The smooth reach of a rigid mesh's corners and edges: for a corner or an edge of the mesh,
 * the longest cloth edge D such that a cloth triangle with edges up to D, whose vertices are
 * held at least a given distance m outside the surface, cannot touch it (the argument, and how
 * mesh contacts use it to leave such corners and edges to the collider pass, is in
 * dynamics/mesh_contact_features.c). Found from how far the faces within reach of the feature turn
 * against its reference normal: the surface there is a graph of slope at most tan A(t) at
 * distance t, and the reach is where the integral F of that slope meets the budget
 * M = sqrt(3) m. A feature on an open edge, with faces turned back or nearly at right angles,
 * has no reach (-1: never left out). Where the mesh is fine against the range, features are
 * measured together in clusters (smooth_reach.c) and reach a little less than they would alone:
 * any D for which the argument holds will do, the longest only leaves out the most. */
#ifndef PLAIT_COLLISION_SMOOTH_REACH_H
#define PLAIT_COLLISION_SMOOTH_REACH_H

#include "collision/mesh_shape.h"
#include "core/alloc.h"
#include "core/parallel.h"

/* Reaches of every vertex (vertex_reach, vertex_count entries) and of every triangle's edges
 * (edge_reach[3 t + k]: the edge from corner k of triangle t to corner k + 1), in scene units,
 * at most range - budget (faces farther than range from a feature are not looked at). False
 * only when out of memory (then nothing is written). Features are measured on the workers of
 * `parallel` (NULL: on the calling thread), with the same results on any number. Costs grow
 * with the faces within range of each feature, and within its reach where that ends sooner;
 * on a fine mesh, with the clusters. On one thread, at hang-self's budget and range
 * (bench_mesh_queries --reaches): 45 ms for a sphere of radius 0.5 m in 4,900 triangles, 0.55 s
 * in 19,800 and 2.5 s in 79,600 (most of its features smooth over the whole range, passed by
 * a bound without measuring their faces); 0.3 s for a ball of radius 5 cm in 19,800 and 1.1 s
 * for one of 10 cm in 79,600 (clusters: 17 s and 81 s feature by feature). */
bool plait_mesh_smooth_reaches(const plait_mesh_shape *shape, const plait_allocator *allocator,
                               plait_parallel *parallel, float budget, float range, float *vertex_reach,
                               float *edge_reach);
/* The same, and the unit reference normal each reach holds with (the argument's n0): a
 * feature's own (the mean of its faces' normals) or its cluster's (smooth_reach.c); zero where
 * the reach is -1 for want of one. vertex_normal and edge_normal are laid out as the reaches. */
bool plait_mesh_smooth_reaches_with_normals(const plait_mesh_shape *shape, const plait_allocator *allocator,
                                            plait_parallel *parallel, float budget, float range,
                                            float *vertex_reach, float *edge_reach, vec3 *vertex_normal,
                                            vec3 *edge_normal);

#endif
