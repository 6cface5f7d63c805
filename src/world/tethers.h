/* Building tethers (long-range attachments) for a cloth from its pins. */
#ifndef PLAIT_WORLD_TETHERS_H
#define PLAIT_WORLD_TETHERS_H

#include "dynamics/sim.h"
#include "topology/topology.h"

/* Appends one tether per free vertex to its nearest pin (room must be reserved: one per
 * vertex). x are rest positions of the object's vertices, first its first particle. */
bool plait_build_tethers(plait_sim *sim, const plait_topology *topology, const vec3 *x, int first,
                         const int *pins, int pin_count, plait_tether_mode mode, float scale,
                         float stiffness);

#endif
