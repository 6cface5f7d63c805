/* The thread pool behind the world's task hooks: see thread_pool.h for the contract.
 *
 * An enqueue takes a slot from a fixed table and queues it; idle threads sleep on work_ready
 * and claim the queued slots' ranges one at a time, in order. The thread that completes a
 * slot's last range frees the slot, bumps its generation and wakes the finishers. A handle is
 * (generation, slot) packed in a pointer-sized integer, so finish_task knows its enqueue is done
 * when the slot's generation has moved on, even if the slot already serves a later enqueue. */
#include "thread_pool.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

// How long an idle thread watches for work before it sleeps (plait_pool_spin_for_work).
#define PLAIT_THREAD_POOL_SPIN_NS 200000

typedef struct plait_pool_slot {
	plait_task_fn *task;
	void *context;
	int item_count;
	int range_count;
	int next_range;              /* ranges claimed so far; under the mutex */
	atomic_int ranges_left;      /* ranges not yet completed */
	atomic_uintptr_t generation; /* bumped when the slot completes */
} plait_pool_slot;

typedef struct plait_pool_thread {
	plait_thread_pool *pool;
	int index; /* 1..thread_count-1 */
	pthread_t thread;
} plait_pool_thread;

struct plait_thread_pool {
	int thread_count; /* workers, the caller included */
	pthread_mutex_t mutex;
	pthread_cond_t work_ready; /* a slot was queued, or the pool stops */
	pthread_cond_t slot_done;  /* a slot completed */
	bool stopping;
	atomic_int waiting_work; /* queue_count, readable without the mutex (a hint for spinning) */
	plait_pool_slot slots[PLAIT_THREAD_POOL_SLOTS];
	int free_slots[PLAIT_THREAD_POOL_SLOTS]; /* a stack */
	int free_count;
	int queue[PLAIT_THREAD_POOL_SLOTS]; /* slots with unclaimed ranges, oldest first */
	int queue_head, queue_count;
	plait_pool_thread *threads; /* thread_count - 1 */
	int started;                /* threads actually running */
};

/* A handle keeps the slot in the low bits and as much of the generation as fits above them. */
#define PLAIT_POOL_SLOT_BITS 7
#define PLAIT_POOL_GENERATION_MASK (UINTPTR_MAX >> PLAIT_POOL_SLOT_BITS)

static void *plait_pool_handle(int slot, uintptr_t generation)
{
	uintptr_t bits =
	    ((generation & PLAIT_POOL_GENERATION_MASK) << PLAIT_POOL_SLOT_BITS) | (uintptr_t)(slot + 1);
	return (void *)bits;
}

// Range r of n over [0, count): sizes differ by at most one item, larger ranges first.
static void plait_pool_range(int count, int n, int r, int *start, int *end)
{
	int base = count / n, extra = count % n;
	*start = r * base + (r < extra ? r : extra);
	*end = *start + base + (r < extra ? 1 : 0);
}

// Nanoseconds of a monotonic clock.
static int64_t plait_pool_now_ns(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

// Watches for work without the mutex for a while before sleeping: a world hands its workers a
// task at every frame (plait_parallel_begin), and waking a sleeping thread took tens of
// microseconds on this project's machine, a few percent of a millisecond frame. Called and
// returns with the mutex held.
static void plait_pool_spin_for_work(plait_thread_pool *pool)
{
	pthread_mutex_unlock(&pool->mutex);
	int64_t until = plait_pool_now_ns() + PLAIT_THREAD_POOL_SPIN_NS;
	for (int spins = 0; atomic_load_explicit(&pool->waiting_work, memory_order_relaxed) == 0; ++spins) {
#if defined(__x86_64__) || defined(__i386__)
		__builtin_ia32_pause();
#endif
		if ((spins & 255) == 255 && plait_pool_now_ns() > until)
			break;
	}
	pthread_mutex_lock(&pool->mutex);
}

static void *plait_pool_thread_main(void *argument)
{
	plait_pool_thread *self = argument;
	plait_thread_pool *pool = self->pool;
	pthread_mutex_lock(&pool->mutex);
	for (;;) {
		if (pool->queue_count == 0 && !pool->stopping)
			plait_pool_spin_for_work(pool);
		while (pool->queue_count == 0 && !pool->stopping)
			pthread_cond_wait(&pool->work_ready, &pool->mutex);
		if (pool->queue_count == 0)
			break; /* stopping, and nothing left to run */
		int index = pool->queue[pool->queue_head];
		plait_pool_slot *slot = &pool->slots[index];
		int range = slot->next_range++;
		if (slot->next_range == slot->range_count) {
			pool->queue_head = (pool->queue_head + 1) % PLAIT_THREAD_POOL_SLOTS;
			pool->queue_count -= 1;
			atomic_store_explicit(&pool->waiting_work, pool->queue_count, memory_order_relaxed);
		}
		plait_task_fn *task = slot->task;
		void *context = slot->context;
		int start, end;
		plait_pool_range(slot->item_count, slot->range_count, range, &start, &end);
		pthread_mutex_unlock(&pool->mutex);

		task(start, end, self->index, context);

		bool last = atomic_fetch_sub_explicit(&slot->ranges_left, 1, memory_order_acq_rel) == 1;
		pthread_mutex_lock(&pool->mutex);
		if (last) {
			// The generation moves under the mutex so a finisher checking it there cannot miss
			// the broadcast; release so a finisher seeing it also sees the task's writes.
			atomic_fetch_add_explicit(&slot->generation, 1, memory_order_release);
			pool->free_slots[pool->free_count++] = index;
			pthread_cond_broadcast(&pool->slot_done);
		}
	}
	pthread_mutex_unlock(&pool->mutex);
	return NULL;
}

void *plait_thread_pool_enqueue(plait_task_fn *task, int item_count, int min_range, void *task_context,
                                void *user_context)
{
	plait_thread_pool *pool = user_context;
	if (item_count <= 0)
		return NULL;
	int threads = pool->thread_count - 1;
	if (threads == 0) {
		// No thread to hand it to: the only place it can run is here.
		task(0, item_count, 0, task_context);
		return NULL;
	}
	if (min_range < 1)
		min_range = 1;
	int range_count = item_count / min_range;
	if (range_count > threads)
		range_count = threads;
	if (range_count < 1)
		range_count = 1;

	pthread_mutex_lock(&pool->mutex);
	while (pool->free_count == 0)
		pthread_cond_wait(&pool->slot_done, &pool->mutex);
	int index = pool->free_slots[--pool->free_count];
	plait_pool_slot *slot = &pool->slots[index];
	slot->task = task;
	slot->context = task_context;
	slot->item_count = item_count;
	slot->range_count = range_count;
	slot->next_range = 0;
	atomic_store_explicit(&slot->ranges_left, range_count, memory_order_relaxed);
	uintptr_t generation = atomic_load_explicit(&slot->generation, memory_order_relaxed);
	pool->queue[(pool->queue_head + pool->queue_count) % PLAIT_THREAD_POOL_SLOTS] = index;
	pool->queue_count += 1;
	atomic_store_explicit(&pool->waiting_work, pool->queue_count, memory_order_relaxed);
	if (range_count == 1)
		pthread_cond_signal(&pool->work_ready);
	else
		pthread_cond_broadcast(&pool->work_ready);
	pthread_mutex_unlock(&pool->mutex);
	return plait_pool_handle(index, generation);
}

void plait_thread_pool_finish(void *user_task, void *user_context)
{
	plait_thread_pool *pool = user_context;
	if (user_task == NULL)
		return;
	uintptr_t bits = (uintptr_t)user_task;
	int index = (int)(bits & (((uintptr_t)1 << PLAIT_POOL_SLOT_BITS) - 1)) - 1;
	uintptr_t generation = bits >> PLAIT_POOL_SLOT_BITS;
	plait_pool_slot *slot = &pool->slots[index];
	// Usually done already (the caller ran its own share meanwhile): no lock then.
	if ((atomic_load_explicit(&slot->generation, memory_order_acquire) & PLAIT_POOL_GENERATION_MASK) !=
	    generation)
		return;
	pthread_mutex_lock(&pool->mutex);
	while ((atomic_load_explicit(&slot->generation, memory_order_acquire) & PLAIT_POOL_GENERATION_MASK) ==
	       generation)
		pthread_cond_wait(&pool->slot_done, &pool->mutex);
	pthread_mutex_unlock(&pool->mutex);
}

// Stops the threads started so far (after the queued work) and joins them.
static void plait_pool_stop(plait_thread_pool *pool)
{
	pthread_mutex_lock(&pool->mutex);
	pool->stopping = true;
	pthread_cond_broadcast(&pool->work_ready);
	pthread_mutex_unlock(&pool->mutex);
	for (int t = 0; t < pool->started; ++t)
		pthread_join(pool->threads[t].thread, NULL);
	pool->started = 0;
}

plait_thread_pool *plait_thread_pool_create(int thread_count)
{
	if (thread_count < 1 || thread_count > PLAIT_THREAD_POOL_MAX_THREADS)
		return NULL;
	plait_thread_pool *pool = calloc(1, sizeof *pool);
	if (pool == NULL)
		return NULL;
	pool->thread_count = thread_count;
	atomic_init(&pool->waiting_work, 0);
	for (int s = 0; s < PLAIT_THREAD_POOL_SLOTS; ++s) {
		atomic_init(&pool->slots[s].ranges_left, 0);
		atomic_init(&pool->slots[s].generation, 0);
		pool->free_slots[s] = PLAIT_THREAD_POOL_SLOTS - 1 - s;
	}
	pool->free_count = PLAIT_THREAD_POOL_SLOTS;
	if (pthread_mutex_init(&pool->mutex, NULL) != 0) {
		free(pool);
		return NULL;
	}
	if (pthread_cond_init(&pool->work_ready, NULL) != 0) {
		pthread_mutex_destroy(&pool->mutex);
		free(pool);
		return NULL;
	}
	if (pthread_cond_init(&pool->slot_done, NULL) != 0) {
		pthread_cond_destroy(&pool->work_ready);
		pthread_mutex_destroy(&pool->mutex);
		free(pool);
		return NULL;
	}
	if (thread_count > 1) {
		pool->threads = calloc((size_t)(thread_count - 1), sizeof *pool->threads);
		if (pool->threads == NULL) {
			plait_thread_pool_destroy(pool);
			return NULL;
		}
		for (int t = 0; t < thread_count - 1; ++t) {
			pool->threads[t].pool = pool;
			pool->threads[t].index = t + 1;
			if (pthread_create(&pool->threads[t].thread, NULL, plait_pool_thread_main, &pool->threads[t]) !=
			    0) {
				plait_thread_pool_destroy(pool);
				return NULL;
			}
			pool->started = t + 1;
		}
	}
	return pool;
}

void plait_thread_pool_destroy(plait_thread_pool *pool)
{
	if (pool == NULL)
		return;
	plait_pool_stop(pool);
	pthread_cond_destroy(&pool->slot_done);
	pthread_cond_destroy(&pool->work_ready);
	pthread_mutex_destroy(&pool->mutex);
	free(pool->threads);
	free(pool);
}

int plait_thread_pool_worker_count(const plait_thread_pool *pool)
{
	return pool != NULL ? pool->thread_count : 1;
}

void plait_thread_pool_attach(plait_thread_pool *pool, plait_world_def *def)
{
	if (pool == NULL || pool->thread_count < 2) {
		def->enqueue_task = NULL;
		def->finish_task = NULL;
		def->task_context = NULL;
		def->worker_count = 1;
		return;
	}
	def->enqueue_task = plait_thread_pool_enqueue;
	def->finish_task = plait_thread_pool_finish;
	def->task_context = pool;
	def->worker_count = pool->thread_count;
}

int plait_thread_pool_default_count(void)
{
	long online = sysconf(_SC_NPROCESSORS_ONLN);
	if (online < 1)
		return 1;
	return online > PLAIT_THREAD_POOL_MAX_THREADS ? PLAIT_THREAD_POOL_MAX_THREADS : (int)online;
}
