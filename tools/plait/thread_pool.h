/* A small persistent thread pool (pthreads) behind the world's task hooks (plait_world_def
 * enqueue_task / finish_task), for the tool, the benchmarks and the tests. The library core
 * never uses threads itself: it only calls these hooks.
 *
 * Contract, as the solver needs it (it runs worker 0 on the calling thread and workers
 * 1..worker_count-1 as tasks that spin-wait for each other):
 *   - every range of an enqueued task starts promptly on a pool thread: it is never deferred to
 *     finish_task and never run inside enqueue_task (except in a pool with no threads, below);
 *   - a pool thread runs one range at a time, so up to (thread_count - 1) ranges that wait for
 *     each other all run at once; worker_count is set to thread_count;
 *   - the worker_index given to the task is the pool thread's own index, 1..thread_count-1; the
 *     calling thread (index 0) never runs pool tasks;
 *   - enqueue_task splits [0, item_count) into at most (thread_count - 1) ranges of at least
 *     min_range items, and finish_task returns once every range of that enqueue has run;
 *   - at most PLAIT_THREAD_POOL_SLOTS enqueues are in flight; one more blocks until one of them
 *     completes (not until it is finished).
 * Idle threads sleep on a condition variable. Nothing is allocated per enqueue. */
#ifndef PLAIT_THREAD_POOL_H
#define PLAIT_THREAD_POOL_H

#include <plait/plait.h>

#define PLAIT_THREAD_POOL_MAX_THREADS 256
#define PLAIT_THREAD_POOL_SLOTS 64

typedef struct plait_thread_pool plait_thread_pool;

/* A pool of thread_count workers in all, the caller included: it starts thread_count - 1
 * threads. thread_count is 1..PLAIT_THREAD_POOL_MAX_THREADS. With 1 no thread is started,
 * attach leaves the hooks NULL, and the pool's enqueue runs a task inline (worker_index 0) and
 * returns NULL. Returns NULL on a bad count or when threads or memory cannot be had. */
plait_thread_pool *plait_thread_pool_create(int thread_count);

/* Waits for the work in flight, stops and joins the threads, frees the pool. NULL is a no-op. */
void plait_thread_pool_destroy(plait_thread_pool *pool);

/* thread_count as created (the caller included). */
int plait_thread_pool_worker_count(const plait_thread_pool *pool);

/* Sets def->enqueue_task, finish_task, task_context (the pool) and worker_count. With a pool of
 * one worker (or pool NULL) the hooks are set NULL and worker_count 1. The pool must outlive the
 * worlds created from def. */
void plait_thread_pool_attach(plait_thread_pool *pool, plait_world_def *def);

/* The hooks themselves, for callers that drive the pool directly; user_context is the pool. */
void *plait_thread_pool_enqueue(plait_task_fn *task, int item_count, int min_range, void *task_context,
                                void *user_context);
void plait_thread_pool_finish(void *user_task, void *user_context);

/* Online processors (sysconf(_SC_NPROCESSORS_ONLN)), clamped to 1..PLAIT_THREAD_POOL_MAX_THREADS. */
int plait_thread_pool_default_count(void);

#endif
