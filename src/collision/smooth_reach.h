/* The smooth reach of a rigid mesh's corners and edges: for a corner or an edge of the mesh,
 * the longest cloth edge D such that a cloth triangle with edges up to D, whose vertices are
 * held at least a given distance m outside the surface, cannot touch it (the argument, and how
 * mesh contacts use it to leave such corners and edges to the collider pass, is in
 * dynamics/mesh_contact_features.c). Found from how far the faces within reach of the feature turn
 * against its reference normal: the surface there is a graph of slope at most tan A(t) at
 * distance t, and the reach is where the integral F of that slope meets the budget
 * M = sqrt(3) m. A feature on an open edge, with faces turned back or nearly at right angles,
 * has no reach (-1: never left out). */
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
 * with the faces within range of each feature, and within its reach where that ends sooner:
 * on one thread, at hang-self's budget and range (bench_mesh_queries --reaches), 45 ms for a
 * sphere of radius 0.5 m in 4,900 triangles, 0.55 s in 19,800 and 2.7 s in 79,600 (most of
 * its features smooth over the whole range, passed by a bound without measuring their faces);
 * 8 s for a sphere of radius 5 cm in 19,800 (a limb: reaches end early, but every face within
 * them is measured). */
bool plait_mesh_smooth_reaches(const plait_mesh_shape *shape, const plait_allocator *allocator,
                               plait_parallel *parallel, float budget, float range, float *vertex_reach,
                               float *edge_reach);

#endif
