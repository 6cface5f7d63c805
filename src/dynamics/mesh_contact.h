/* Space-time collisions between the simplices of deforming objects (paper §7): the triangles of
 * cloths, the segments of curves and loose particles, against each other and (when an object
 * self-collides) against themselves. Two stages:
 *
 * Contacts, inside the collision iterations of the schedule. At the first collision iteration
 * of a substep the candidate pairs are gathered once: primitives (vertex-triangle, edge-edge,
 * vertex-edge, vertex-vertex) whose paths over the substep may come within their contact
 * distance (the sum of their thicknesses). Each collision iteration then projects every pair
 * to at least that distance apart, on the side it was on at the start of the substep (where the
 * state is known to be free of intersections), shared by inverse mass, with Coulomb friction.
 * Which side that is comes from the start of the substep and follows the pair as long as it
 * does not cross: a pair whose side changed is asked of the continuous test (collision/ccd.h)
 * whether it went through (then it is pushed back) or round (then the new side holds).
 *
 * Failsafe, at the end of the substep. Every pair is swept with the conservative continuous
 * test from the start of the substep to the end; pairs that cross join impact zones (vertex
 * sets merged by union-find) whose motion over the substep is made rigid, keeping their mean
 * displacement and angular momentum (Provot 1997, Bridson et al. 2002), until no pair crosses.
 * Zones that still cross after a fixed number of rounds are put back at their start positions,
 * which were free of intersections, as seen from a moving collider they lay on (carried with it,
 * and slid out of any other it then presses them into), and swept again; the last round puts
 * them back at their start positions themselves, so a substep never ends with primitives passed
 * through each other (pinned vertices, which cannot be put back, aside). */
#ifndef PLAIT_DYNAMICS_MESH_CONTACT_H
#define PLAIT_DYNAMICS_MESH_CONTACT_H

#include "dynamics/sim.h"

/* Whether any object takes part (so the stage has work). Builds the elements when objects came
 * or went. False only when out of memory. */
bool plait_mesh_contacts_prepare(plait_sim *sim, bool *active);

/* Starts a substep: the candidates are gathered at the first iteration. When a search for
 * crossings is due (objects came, positions were set, crossings remained), triangles that cross
 * at the substep's start are found and set about undoing (mesh_contact_untangle.c). False only
 * when out of memory. */
bool plait_mesh_contacts_begin_substep(plait_sim *sim);

/* Positions were set from outside the solver: the next substep searches for crossings. */
void plait_mesh_contacts_positions_set(plait_sim *sim);

/* One collision iteration over the candidates; returns the contacts resolved. */
int plait_mesh_contacts_project(plait_sim *sim);

/* A contact pass (contact.h): the listed pairs that pushed at the last collision iteration,
 * projected again, in the iteration's order. */
void plait_mesh_contacts_project_again(plait_sim *sim);
/* After a collision iteration's pass over the colliders: the listed pairs with a vertex on a
 * collider projected once more, so that cloth resting on cloth that rests on a collider ends
 * the iteration resting on it, held by its friction. Returns the contacts resolved. */
int plait_mesh_contacts_project_on_colliders(plait_sim *sim);

/* The end-of-substep guarantee; before the velocities are taken from the positions. */
void plait_mesh_contacts_failsafe(plait_sim *sim);

/* Whether some colliding object's surface asks for bounce or stickiness: the substep then ends
 * with plait_mesh_contacts_restitute after its velocity update. */
bool plait_mesh_contacts_restitution(const plait_sim *sim);

/* After the substep's velocity update: each pair that pushed in it leaves at `bounce` times the
 * normal speed it closed at (the mean of its two surfaces'; closing slower than gravity's pull
 * over two substeps is resting, and does not bounce), and each pair that pushed or began the
 * substep within its contact distance loses `stickiness` of its separating normal speed. In the
 * list's order, on the calling thread. */
void plait_mesh_contacts_restitute(plait_sim *sim);

void plait_mesh_contacts_destroy(plait_sim *sim);

/* Drops the list of candidates: the next substep gathers them again. For settings that change
 * which pairs are listed or how (plait_world_set_def), since a list at rest may otherwise serve
 * on for up to LIST_LIFE substeps. */
void plait_mesh_contacts_forget_list(plait_sim *sim);

/* Corners and edges of mesh and box colliders that the last listing met in element pairs with
 * cloth or curves (each once per pair): *kept those it tested, *left_out those smooth at the
 * scale of the other's triangles, left to the collider pass (for tests and benchmarks). */
void plait_mesh_contacts_collider_features(const plait_sim *sim, int *kept, int *left_out);

/* Lists gathered since the stage was made (for tests and benchmarks). */
long plait_mesh_contacts_listings(const plait_sim *sim);

/* Flat patches since the stage was made whose pairs with themselves a gather passed over, and
 * of those, the failsafe found not flat along the substep's paths and swept (for tests and
 * benchmarks; collision/flat_patches.h). */
void plait_mesh_contacts_flat_counts(const plait_sim *sim, long *culled, long *unflattened);

#endif
