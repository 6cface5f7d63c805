/* Parallel loops over the user's task system (plait_world_def.enqueue_task / finish_task), in
 * the manner of Box2D v3's solver: for the length of one frame the world keeps worker_count - 1
 * worker tasks running, and each parallel loop of the frame is handed to them through one
 * atomic ticket instead of one enqueue per loop (a frame has hundreds of loops, one per colour
 * of every constraint sweep).
 *
 * A loop is cut into chunks of `grain` items. Participant k (the calling thread is 0) owns the
 * k-th of worker_count equal shares of the chunks and claims its own first, then takes what is
 * left of the others' shares; the loop returns when every chunk is done. The same items thus
 * tend to stay on the same core from one loop to the next, where their data is in cache. Callers only pass
 * loops whose items are independent, so the result does not depend on who ran which chunk: output is the same
 * for any thread count. The calling thread can finish such a loop alone, so a worker that starts late only
 * costs time. The one loop whose items wait for each other (the wave in pieces, dynamics/wave.h) runs only
 * when every worker is running (plait_parallel_all_running).
 *
 * The contract for the task system is Box2D's: with worker_count > 1, each enqueued task must
 * start on a thread of its own without waiting for finish_task (the workers wait for loops
 * inside the task). */
#ifndef PLAIT_CORE_PARALLEL_H
#define PLAIT_CORE_PARALLEL_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include <plait/plait.h>

#define PLAIT_MAX_WORKERS 256

typedef void plait_range_fn(void *context, int begin, int end);

typedef struct plait_parallel {
	plait_enqueue_task_fn *enqueue_task;
	plait_finish_task_fn *finish_task;
	void *user_context;
	int worker_count; /* including the calling thread */
	bool running;     /* between plait_parallel_begin and plait_parallel_end */
	void *tasks[PLAIT_MAX_WORKERS];

	/* The current loop; written by the calling thread only while no chunk is pending. */
	plait_range_fn *fn;
	void *context;
	int begin, end, grain;

	uint32_t generation;       /* of the current loop, never 0 once a loop was posted */
	uint32_t begin_generation; /* of the last loop before plait_parallel_begin */
	_Atomic uint32_t announce; /* the generation workers wait for */
	_Atomic int done;          /* chunks of the current loop finished */
	_Atomic int quit;
	_Atomic int running_workers; /* worker tasks of this frame that have started */
	struct plait_parallel_share {
		/* generation (24 bits) | end of the share (20) | next chunk (20); a claim is a
		 * compare-and-swap that also checks the generation, so a late worker cannot take a
		 * chunk of a newer loop for an older one. */
		_Alignas(64) _Atomic uint64_t ticket;
	} shares[PLAIT_MAX_WORKERS];
	struct plait_parallel_worker {
		struct plait_parallel *parallel;
		int index;
	} workers[PLAIT_MAX_WORKERS];
} plait_parallel;

/* Task hooks as given in the world def; worker_count is clamped to [1, PLAIT_MAX_WORKERS] and
 * taken as 1 without hooks. */
void plait_parallel_init(plait_parallel *parallel, plait_enqueue_task_fn *enqueue_task,
                         plait_finish_task_fn *finish_task, void *user_context, int worker_count);

/* Starts the worker tasks (nothing with one worker). */
void plait_parallel_begin(plait_parallel *parallel);
/* Stops them and waits for their tasks to return. */
void plait_parallel_end(plait_parallel *parallel);

/* Whether every worker task of the frame has started (always with one worker), waiting up to
 * `seconds` for those not yet started: each then takes its own share of every loop posted from
 * now on. False at once when the task system gave a NULL handle (a task it did not start). */
bool plait_parallel_all_running(plait_parallel *parallel, double seconds);

/* Runs fn over [begin, end) in chunks of grain items (the last may be shorter), on the workers
 * when they are running and the loop has more than one chunk, else on the calling thread. */
void plait_parallel_for(plait_parallel *parallel, plait_range_fn *fn, void *context, int begin, int end,
                        int grain);

/* One step of a busy wait (start *spins at 0): a pause for the first steps, then the processor
 * given away, so that more workers than cores (or a busy machine) slow a wait down instead of
 * stalling it. */
void plait_spin_wait(int *spins);

#endif
