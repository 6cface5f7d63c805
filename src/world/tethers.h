/* Building tethers (long-range attachments) for a cloth from its pins. */
#ifndef PLAIT_WORLD_TETHERS_H
#define PLAIT_WORLD_TETHERS_H

#include "dynamics/sim.h"
#include "topology/topology.h"

/* Tethers per free vertex for a cloth with pin_count pins: room to reserve is this times the
 * vertex count. */
int plait_tethers_per_vertex(int pin_count);

/* Appends the tethers of each free vertex to its nearest pins, the nearest last. x are rest
 * positions of the object's vertices, first its first particle. */
bool plait_build_tethers(plait_sim *sim, const plait_topology *topology, const vec3 *x, int first,
                         const int *pins, int pin_count, plait_tether_mode mode, float scale,
                         float stiffness);

#endif
