/* Contacts between a vertex and a triangle of another object's surface (paper §7: the
 * point-triangle pair of space-time collisions, here between simplicial complexes): the
 * vertex of a cloth, curve or particle object against the triangles of a cloth. Both sides
 * move: the correction is shared by inverse mass, with the triangle's share spread over its
 * corners by the contact's barycentric weights. A path longer than the contact distance is
 * swept with the conservative vertex-face test (collision/ccd.h); every pair found within the
 * distance at the end is pushed apart on the side the vertex started on. */
#ifndef PLAIT_DYNAMICS_SURFACE_CONTACT_H
#define PLAIT_DYNAMICS_SURFACE_CONTACT_H

#include "dynamics/sim.h"

bool plait_sim_reserve_surfaces(plait_sim *sim, int count);

/* One collision iteration of every vertex against every other object's surface. */
int plait_collide_surfaces(plait_sim *sim);

#endif
