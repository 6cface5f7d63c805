#include "core/parallel.h"

#include "core/clock.h"
#include "core/float_mode.h"

#include <string.h>

#if !defined(__STDC_NO_THREADS__)
#include <threads.h>
#endif

#define CHUNK_BITS 20
#define CHUNK_MASK ((UINT64_C(1) << CHUNK_BITS) - 1)
#define GENERATION_MASK 0xFFFFFFu

static inline uint64_t pack_ticket(uint32_t generation, int end, int next)
{
	return ((uint64_t)generation << (2 * CHUNK_BITS)) | ((uint64_t)end << CHUNK_BITS) | (uint64_t)next;
}
static inline uint32_t ticket_generation(uint64_t ticket)
{
	return (uint32_t)(ticket >> (2 * CHUNK_BITS));
}
static inline int ticket_end(uint64_t ticket)
{
	return (int)((ticket >> CHUNK_BITS) & CHUNK_MASK);
}
static inline int ticket_next(uint64_t ticket)
{
	return (int)(ticket & CHUNK_MASK);
}

/* Busy-wait step: a pause for the first spins, then give the processor away, so that more
 * workers than cores (or a busy machine) slow the frame down instead of stalling it. */
void plait_spin_wait(int *spins)
{
	*spins += 1;
	if (*spins < 2000) {
#if defined(__x86_64__) || defined(__i386__)
		__builtin_ia32_pause();
#endif
		return;
	}
#if !defined(__STDC_NO_THREADS__)
	thrd_yield();
#endif
}

void plait_parallel_init(plait_parallel *parallel, plait_enqueue_task_fn *enqueue_task,
                         plait_finish_task_fn *finish_task, void *user_context, int worker_count)
{
	memset(parallel, 0, sizeof *parallel);
	bool hooks = enqueue_task != NULL && finish_task != NULL;
	parallel->enqueue_task = enqueue_task;
	parallel->finish_task = finish_task;
	parallel->user_context = user_context;
	worker_count = worker_count < 1 ? 1 : worker_count;
	worker_count = worker_count > PLAIT_MAX_WORKERS ? PLAIT_MAX_WORKERS : worker_count;
	parallel->worker_count = hooks ? worker_count : 1;
	atomic_init(&parallel->announce, 0);
	atomic_init(&parallel->done, 0);
	atomic_init(&parallel->quit, 0);
	atomic_init(&parallel->running_workers, 0);
	for (int k = 0; k < PLAIT_MAX_WORKERS; ++k) {
		atomic_init(&parallel->shares[k].ticket, 0);
		parallel->workers[k].parallel = parallel;
		parallel->workers[k].index = k;
	}
}

/* Claims and runs chunks of one share of loop `generation` until it is empty. The loop's
 * description is read only after a chunk was claimed: the calling thread cannot move on to
 * another loop while that chunk is pending, so the description is the claimed loop's. The
 * chunks run are counted into `done` once, when the share is empty: a count per chunk bounced
 * its cache line between the threads at every chunk. */
static void run_share(plait_parallel *parallel, uint32_t generation, int share)
{
	_Atomic uint64_t *slot = &parallel->shares[share].ticket;
	uint64_t ticket = atomic_load_explicit(slot, memory_order_acquire);
	int finished = 0;
	for (;;) {
		if (ticket_generation(ticket) != generation || ticket_next(ticket) >= ticket_end(ticket)) {
			break;
		}
		if (atomic_compare_exchange_weak_explicit(slot, &ticket, ticket + 1, memory_order_acq_rel,
		                                          memory_order_acquire)) {
			int chunk = ticket_next(ticket);
			int begin = parallel->begin + chunk * parallel->grain;
			int end = begin + parallel->grain < parallel->end ? begin + parallel->grain : parallel->end;
			parallel->fn(parallel->context, begin, end);
			finished += 1;
			ticket = atomic_load_explicit(slot, memory_order_acquire);
		}
	}
	if (finished > 0) {
		atomic_fetch_add_explicit(&parallel->done, finished, memory_order_release);
	}
}

/* Participant `self` empties its own share, then the others'. */
static void run_chunks(plait_parallel *parallel, uint32_t generation, int self)
{
	int count = parallel->worker_count;
	for (int k = 0; k < count; ++k) {
		run_share(parallel, generation, (self + k) % count);
	}
}

static void worker_task(int start_index, int end_index, int worker_index, void *task_context)
{
	(void)start_index;
	(void)end_index;
	(void)worker_index;
	struct plait_parallel_worker *worker = task_context;
	plait_parallel *parallel = worker->parallel;
	plait_float_mode saved_mode = plait_float_mode_enter();
	/* The loops of this frame so far, not the last announced: a worker that starts after the
	 * first loop was posted still joins it (the frame's first loop, a pass over every particle,
	 * otherwise ran on the calling thread alone). */
	uint32_t seen = parallel->begin_generation;
	atomic_fetch_add_explicit(&parallel->running_workers, 1, memory_order_release);
	for (;;) {
		int spins = 0;
		uint32_t announced;
		for (;;) {
			announced = atomic_load_explicit(&parallel->announce, memory_order_acquire);
			if (announced != seen) {
				break;
			}
			if (atomic_load_explicit(&parallel->quit, memory_order_acquire)) {
				plait_float_mode_leave(saved_mode);
				return;
			}
			plait_spin_wait(&spins);
		}
		seen = announced;
		run_chunks(parallel, seen, worker->index);
	}
}

void plait_parallel_begin(plait_parallel *parallel)
{
	if (parallel->worker_count <= 1 || parallel->running) {
		return;
	}
	atomic_store_explicit(&parallel->quit, 0, memory_order_release);
	parallel->running = true;
	parallel->begin_generation = parallel->generation;
	atomic_store_explicit(&parallel->running_workers, 0, memory_order_relaxed);
	for (int k = 1; k < parallel->worker_count; ++k) {
		parallel->tasks[k] =
		    parallel->enqueue_task(worker_task, 1, 1, &parallel->workers[k], parallel->user_context);
	}
}

void plait_parallel_end(plait_parallel *parallel)
{
	if (!parallel->running) {
		return;
	}
	atomic_store_explicit(&parallel->quit, 1, memory_order_release);
	for (int k = 1; k < parallel->worker_count; ++k) {
		if (parallel->tasks[k] != NULL) {
			parallel->finish_task(parallel->tasks[k], parallel->user_context);
			parallel->tasks[k] = NULL;
		}
	}
	parallel->running = false;
}

bool plait_parallel_all_running(plait_parallel *parallel, double seconds)
{
	if (parallel->worker_count <= 1) {
		return true;
	}
	if (!parallel->running) {
		return false;
	}
	for (int k = 1; k < parallel->worker_count; ++k) {
		if (parallel->tasks[k] == NULL) {
			return false;
		}
	}
	double give_up = plait_seconds() + seconds;
	int spins = 0;
	while (atomic_load_explicit(&parallel->running_workers, memory_order_acquire) !=
	       parallel->worker_count - 1) {
		if (plait_seconds() > give_up) {
			return false;
		}
		plait_spin_wait(&spins);
	}
	return true;
}

void plait_parallel_for(plait_parallel *parallel, plait_range_fn *fn, void *context, int begin, int end,
                        int grain)
{
	if (end <= begin) {
		return;
	}
	grain = grain < 1 ? 1 : grain;
	int count = end - begin;
	if (!parallel->running || count <= grain) {
		fn(context, begin, end);
		return;
	}
	int chunks = (count + grain - 1) / grain;
	if ((uint64_t)chunks > CHUNK_MASK) {
		grain = (int)(((uint64_t)count + CHUNK_MASK - 1) / CHUNK_MASK);
		chunks = (count + grain - 1) / grain;
	}
	parallel->fn = fn;
	parallel->context = context;
	parallel->begin = begin;
	parallel->end = end;
	parallel->grain = grain;
	atomic_store_explicit(&parallel->done, 0, memory_order_relaxed);
	parallel->generation = (parallel->generation + 1) & GENERATION_MASK;
	parallel->generation = parallel->generation == 0 ? 1 : parallel->generation;
	/* Shares first, then the announcement: a worker that sees the new generation finds every
	 * share ready. (One that reads a share early sees the old generation and claims nothing.) */
	int workers = parallel->worker_count;
	for (int k = 0; k < workers; ++k) {
		int first = (int)((int64_t)chunks * k / workers), last = (int)((int64_t)chunks * (k + 1) / workers);
		atomic_store_explicit(&parallel->shares[k].ticket, pack_ticket(parallel->generation, last, first),
		                      memory_order_release);
	}
	atomic_store_explicit(&parallel->announce, parallel->generation, memory_order_release);
	run_chunks(parallel, parallel->generation, 0);
	int spins = 0;
	while (atomic_load_explicit(&parallel->done, memory_order_acquire) < chunks) {
		plait_spin_wait(&spins);
	}
}
