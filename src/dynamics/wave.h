/* A frame as one wave down the regions.
 *
 * A frame is a sequence of passes over the particles: each substep's distance sweeps, then its
 * close (tethers, colliders, the velocity update and the next substep's start). Run one after
 * another, each pass loads every point and constraint again; a 512 x 512 cloth's (about 23 MB a
 * substep) overflow the cache. Where the blocks are banded (colouring.h, "Bands") the frame's
 * passes ("slots") can instead follow each other down the regions one region apart, each region
 * used by every slot of the frame within a few steps of the slot before.
 *
 * The order. Number the slots o = 0, 1, ...: the distance sweeps of substep 0, its close, those of
 * substep 1, and so on. At step t = 0, 1, ..., region t is copied into columns, then slot o works
 * at region q = t - 1 - o, slots in order (so regions downward):
 *   - the head boundary of cut q (between regions q and q + 1): a backward or symmetric sweep
 *     starts with the boundary;
 *   - region q (for a close: its particles; after the last slot they go back from columns);
 *   - the tail boundary of cut q - 1: a forward or symmetric sweep ends with it.
 * Every two projections that touch one particle keep the order they have in the passes one after
 * another. Within a slot, regions and the boundary constraints of different cuts share no
 * particle (banded), so only the order around each cut matters: slot o's head boundary of cut q
 * comes before its regions q and q + 1, its tail boundary after both, and slot o + 1 reaches
 * region q (step q + 2 + o) after slot o's tail boundary of cut q (step q + 2 + o, earlier in the
 * step) and head boundary of cut q (step q + 1 + o). What a close reads of other particles is
 * tether anchors, pinned and kept to the bit through the frame
 * (plait_tether_block.anchors_keep_bits); colliders must not move in the frame, since closes of
 * several substeps are under way at once. So the bits are those of the passes one after another
 * (test_threads, a_wave_gives_the_passes_bits).
 *
 * One thread only. Two threads were tried both ways: two chunks of regions meeting in the middle
 * (the threads wait on each other at the cut between them every slot: 7-11% slower than the
 * passes on two threads), and the slots in two halves, one behind the other (the second waits for
 * the first to get through its half's slots at the first regions: 7-65% slower). */
#ifndef PLAIT_DYNAMICS_WAVE_H
#define PLAIT_DYNAMICS_WAVE_H

#include "dynamics/constraints.h"
#include "dynamics/sim.h"

#define PLAIT_WAVE_MAX_SLOTS 96

/* A distance sweep of a block, or (block NULL) the close of `substep`. */
typedef struct plait_wave_slot {
	plait_distance_block *block;
	plait_sweep sweep;
	int substep;
} plait_wave_slot;

/* Particles [begin, end) into columns before the first slot, through the close of a substep, and
 * back from columns after the last slot. */
typedef void plait_wave_enter_fn(void *context, int begin, int end);
typedef void plait_wave_close_fn(void *context, int substep, int begin, int end);
typedef void plait_wave_leave_fn(void *context, int begin, int end);

typedef struct plait_wave {
	plait_wave_slot slots[PLAIT_WAVE_MAX_SLOTS];
	int slot_count;
	int regions, particle_count;
	const plait_columns *columns;
	float inverse_h_squared;
	plait_wave_enter_fn *enter;
	plait_wave_close_fn *close;
	plait_wave_leave_fn *leave;
	void *context;
} plait_wave;

/* Whether a distance block can take part in a wave over `particle_count` particles cut into
 * `regions` regions: rigid (no multipliers to reset each substep), coloured whole for those
 * particles and regions, its boundary banded. */
bool plait_wave_takes(const plait_distance_block *block, int regions, int particle_count);

/* Runs the wave on the calling thread. */
void plait_wave_run(plait_wave *wave);

#endif
