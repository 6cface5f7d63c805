/* Bend as distances (PLAIT_BEND_DISTANCE): the pairs of vertices two edges apart along a line
 * of the mesh, whose distance resists folding across the vertex between them (the "skip-one"
 * springs of mass-spring cloth, NvCloth's bending constraints). */
#ifndef PLAIT_WORLD_BEND_PAIRS_H
#define PLAIT_WORLD_BEND_PAIRS_H

#include "core/math.h"
#include "topology/topology.h"

/* For each vertex b and each polygon edge (a, b), the partner c is the other polygon edge
 * (b, c) that shares no polygon with (a, b) and runs most nearly straight on (the angle a-b-c
 * at rest over 120 degrees). Each pair {a, c} is written once, smaller index first, sorted.
 * Returns the number of pairs (at most 2 * edge_count) written to pairs, or -1 when out of
 * memory; pairs must have room for 2 * topology->edge_count entries. */
int plait_bend_pairs(const plait_topology *topology, const plait_vec3 *positions,
                     const plait_allocator *allocator, int (*pairs)[2]);

#endif
