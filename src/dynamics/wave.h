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
 * Pieces (several threads). The wave's order is one sequence of tasks: a region's part of a slot,
 * or a cut's boundary before (head) or after (tail) the regions. Two tasks depend on each other
 * when they touch one particle: a region's particles, or a cut's, which lie in its two regions (no
 * particle in two cuts: banded). P threads share the frame in pieces that move one region a slot:
 * thread k runs the regions from line[k] + o on at slot o (to the next thread's line), so
 * everything a region at slot o needs of slot o - 1 (its neighbours' regions and cuts) is its own
 * thread's or the next thread's, never the one before. A cut on a line goes to the thread that
 * runs it last among its two regions' (a head to the later thread, a tail to the earlier). Each
 * thread runs its tasks in the wave's order and, before a task, waits for the tasks before it on
 * its particles that another thread runs (a flag a task). Every pair of touching tasks thus keeps
 * the wave's order, so the bits are the same for any thread count; and since each thread takes
 * its tasks in the wave's order, the earliest task not yet run can always run: no thread waits
 * for ever, once every worker task runs (the solver checks that first:
 * plait_parallel_all_running). All regions go into columns before the tasks start (a close
 * reads tether anchors from columns, wherever they are).
 * Thread k only waits for thread k + 1, which starts its regions a line later in the wave's order
 * and so runs ahead; with the lines set for equal shares (and each moved by a region where the
 * threads before it ran longer than their share: collisions are not spread evenly), the waits are
 * a small part of the frame.
 * The lines must stay within the cloth through the frame (each thread has regions at every slot):
 * two threads need about slots + 2 regions. A frame taller than that runs in rows of fewer slots
 * (all of one height, preferably at most a quarter of the regions: wave.c), a wave in pieces
 * each, with a barrier between rows (hang-128: 16 regions, 24 slots, six rows of 4); rows of
 * fewer than PLAIT_WAVE_LEAST_ROW slots keep the passes.
 * Tried before (performance.md, sessions 20 and 21): two chunks of regions meeting in the middle
 * (they wait on each other at the cut between them every slot), the slots in two halves, one
 * behind the other (the second waits for the first at the first regions), and tiles in rows of
 * slots with wedges between pieces after a barrier (the frame's data loaded once a row). */
#ifndef PLAIT_DYNAMICS_WAVE_H
#define PLAIT_DYNAMICS_WAVE_H

#include "core/alloc.h"
#include "core/parallel.h"
#include "dynamics/constraints.h"
#include "dynamics/sim.h"

#define PLAIT_WAVE_MAX_SLOTS 96
#define PLAIT_WAVE_LEAST_ROW 4 /* slots: the lowest rows a wave in pieces is cut into */

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

/* A task of a wave run in pieces: a region's part of a slot, or a cut's boundary ahead of or
 * after it. */
enum { PLAIT_WAVE_HEAD, PLAIT_WAVE_REGION, PLAIT_WAVE_TAIL };
typedef struct plait_wave_task {
	int16_t slot;
	int16_t kind;
	int32_t index; /* region or cut */
} plait_wave_task;

/* A wave's tasks in a list per row and thread (row r, thread k: list l = r * participants + k,
 * [list_start[l], list_start[l + 1]) of tasks), made once for a frame's shape and kept
 * (plait_wave_plan_make). */
typedef struct plait_wave_plan {
	/* what it was made for */
	int regions, frame_slots, participants;
	int8_t slot_shape[PLAIT_WAVE_MAX_SLOTS]; /* the frame's: the sweep, or -1 for a close */
	bool made;
	int rows, slot_count;        /* the frame's slots in rows of slot_count, a wave in pieces each */
	int line[PLAIT_MAX_WORKERS]; /* [k], k >= 1: thread k's first region at slot o is line[k] + o */
	int *list_start;
	plait_wave_task *tasks;
	int (*waits)[3];                /* [task]: tasks of other threads it waits for, or -1 */
	_Atomic uint32_t *done;         /* [task]: the run (epoch) it was last done in */
	uint32_t epoch;                 /* of the current run */
	double busy[PLAIT_MAX_WORKERS]; /* [k]: seconds thread k ran tasks in the last row, not waiting */
	double lean[PLAIT_MAX_WORKERS]; /* [k]: how much longer threads 0..k-1 ran than their share, smoothed */
	/* scratch while planning */
	plait_wave_task *in_order; /* the tasks in the wave's order */
	int (*before)[3];          /* what each waits for, in the wave's order */
	int *owner;                /* each task's thread, then each particle set's last task */
	int *position;             /* each task's place in tasks */
	int task_capacity, region_capacity, participant_capacity;
} plait_wave_plan;

/* Room for plans over `regions` regions on up to `participants` threads; false without the memory
 * (the plan is then empty and never made). */
bool plait_wave_plan_reserve(plait_wave_plan *plan, const plait_allocator *allocator, int regions,
                             int participants);
void plait_wave_plan_destroy(plait_wave_plan *plan, const plait_allocator *allocator);

/* Plans `wave` (its slots, regions and particles set) on `participants` >= 2 threads, or keeps
 * the plan already made for the same shape; false when the pieces do not fit the cloth. */
bool plait_wave_plan_make(plait_wave_plan *plan, const plait_wave *wave, int participants);

/* Moves the lines to lines[1 .. participants - 1] and plans the lists again (the balance does;
 * tests move them to show any lines give the same bits); false, the plan unchanged, when they do
 * not fit the cloth or no plan was made. */
bool plait_wave_plan_set_lines(plait_wave_plan *plan, const int *lines);

/* Runs the wave as planned on the loops of `parallel` (the regions into columns first, then each
 * row: each thread its list), moving the lines toward balance after each row. */
void plait_wave_run_pieces(plait_wave *wave, plait_wave_plan *plan, plait_parallel *parallel);

/* Whether a distance block can take part in a wave over `particle_count` particles cut into
 * `regions` regions: rigid (no multipliers to reset each substep), coloured whole for those
 * particles and regions, its boundary banded. */
bool plait_wave_takes(const plait_distance_block *block, int regions, int particle_count);

/* Runs the wave on the calling thread. */
void plait_wave_run(plait_wave *wave);

#endif
