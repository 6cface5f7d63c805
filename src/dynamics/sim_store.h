/* Growing the particle store and the constraint blocks, and compacting them when an object is
 * destroyed. Growth happens only when objects are created, never inside a step. */
#ifndef PLAIT_DYNAMICS_SIM_STORE_H
#define PLAIT_DYNAMICS_SIM_STORE_H

#include "dynamics/sim.h"

void plait_sim_init(plait_sim *sim, const plait_allocator *allocator);
void plait_sim_destroy(plait_sim *sim);

/* Make room for count more particles / constraints; false when out of memory. */
bool plait_sim_reserve_particles(plait_sim *sim, int count);
bool plait_sim_reserve_distance(plait_sim *sim, plait_distance_block *block, int count);
bool plait_sim_reserve_bend(plait_sim *sim, int count);
bool plait_sim_reserve_rod_bend(plait_sim *sim, int count);
bool plait_sim_reserve_aero(plait_sim *sim, int count);
bool plait_sim_reserve_tethers(plait_sim *sim, int count);
bool plait_sim_reserve_materials(plait_sim *sim, int count);
bool plait_sim_reserve_colliders(plait_sim *sim, int count);

/* Appends one particle (room must be reserved); returns its index. */
int plait_sim_add_particle(plait_sim *sim, vec3 position, vec3 velocity, float mass, float radius,
                           int material, uint8_t flags);
void plait_sim_add_distance(plait_distance_block *block, int i, int j, float rest, float compliance_tension,
                            float compliance_compression);

/* Removes every particle whose keep[] entry is false, every constraint touching one, and
 * renumbers the rest; materials and colliders of the object are removed by the caller. */
bool plait_sim_compact(plait_sim *sim, const bool *keep);

/* Room for `count` more cloth surfaces. */
bool plait_sim_reserve_surfaces(plait_sim *sim, int count);

/* Room for `count` more curve chains. */
bool plait_sim_reserve_chains(plait_sim *sim, int count);

#endif
