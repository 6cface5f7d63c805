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

/* Reaches of every vertex (vertex_reach, vertex_count entries) and of every triangle's edges
 * (edge_reach[3 t + k]: the edge from corner k of triangle t to corner k + 1), in scene units,
 * at most range - budget (faces farther than range from a feature are not looked at). False
 * only when out of memory (then nothing is written). Costs about a microsecond per face met
 * around each feature: 1.4 G instructions for a 4,900-triangle sphere against centimetre cloth
 * triangles. */
bool plait_mesh_smooth_reaches(const plait_mesh_shape *shape, const plait_allocator *allocator, float budget,
                               float range, float *vertex_reach, float *edge_reach);

#endif
