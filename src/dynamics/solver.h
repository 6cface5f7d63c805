/* The frame loop: the one place to read how a frame is simulated. */
#ifndef PLAIT_DYNAMICS_SOLVER_H
#define PLAIT_DYNAMICS_SOLVER_H

#include "dynamics/sim.h"

extern const char *const plait_kind_names[PLAIT_KIND_COUNT];

/* Rebuilds the schedule from the kinds' importance if anything changed. */
plait_result plait_sim_update_schedule(plait_sim *sim, plait_error *error);

/* Advances one frame; on a non-finite result restores the frame's start state and fails. */
plait_result plait_sim_step(plait_sim *sim, plait_error *error);

typedef struct plait_sim_stats {
	double kinetic_energy;
	float max_strain;
	int penetrations;
	int nonfinite;
} plait_sim_stats;

plait_sim_stats plait_sim_measure(const plait_sim *sim);

#endif
