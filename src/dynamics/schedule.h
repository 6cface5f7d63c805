/* The interleaved scheduler of paper §6 and seed 000 §2.2, §4.1, §4.2, §9.
 *
 * Each kind of constraint has an importance I (iterations per frame) and an order O. Over a
 * frame of S substeps, kind k runs N_k = max(I_k, S) times: every kind runs at least once per
 * substep. The N_k iterations are spread over the substeps by rounding their frame positions
 * ((i + 1) / N_k) to the substep they fall in, so substep s gets
 * floor((s + 1) N_k / S) - floor(s N_k / S) of them. Inside a substep with n_k iterations of
 * kind k, iteration j sits at (j + 1) / n_k, and all events run sorted by (position, order).
 * Every kind's last iteration sits at 1, so each substep ends with one iteration of every
 * kind in order, and collisions (the highest order) run last.
 *
 * Example: stretch 20 and collision 4 with S <= 4 give s s s s s c per 5 stretches; with
 * S = 10 there are 10 collisions per frame (s s c in each substep); with S = 30, 30 of each.
 * The schedule is pure data built once when settings change. */
#ifndef PLAIT_DYNAMICS_SCHEDULE_H
#define PLAIT_DYNAMICS_SCHEDULE_H

#include "core/alloc.h"

#define PLAIT_MAX_KINDS 16
#define PLAIT_MAX_IMPORTANCE 1000

typedef struct plait_kind_desc {
	const char *name;
	int order;      /* lower runs first at equal position */
	int importance; /* iterations per frame, >= 0 */
} plait_kind_desc;

typedef struct plait_schedule {
	int substep_count;
	int *substep_start; /* substep s owns events [substep_start[s], substep_start[s + 1]) */
	int event_count;
	int *events; /* kind index per event */
} plait_schedule;

plait_result plait_schedule_build(plait_schedule *schedule, const plait_allocator *allocator, int substeps,
                                  const plait_kind_desc *kinds, int kind_count, plait_error *error);
void plait_schedule_destroy(plait_schedule *schedule, const plait_allocator *allocator);

/* Iterations of kind k in substep s (the n_k above). */
int plait_schedule_substep_iterations(int importance, int substeps, int substep);

#endif
