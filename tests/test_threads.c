/* The tool's thread pool (tools/plait/thread_pool.h) behind the world's task hooks: every item
 * of an enqueue runs exactly once; tasks that spin-wait for each other (the solver's pattern)
 * all run at once; results do not depend on the worker count; `plait run --threads`; and the
 * hang-128 example scene loads. */
#include "cli.h"
#include "core/parallel.h"
#include "collide_scenes.h"
#include "scene.h"
#include "test_cli.h"
#include "test_support.h"
#include "thread_pool.h"
#include "dynamics/wave.h"
#include "world/world.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* ---- Every item exactly once ---------------------------------------------------------------- */

#define MAX_ITEMS 1000

typedef struct count_context {
	atomic_int hits[MAX_ITEMS];
	atomic_int ranges;
	atomic_int smallest_range;
	atomic_int bad_worker; /* worker_index out of range */
	atomic_int on_caller;  /* ranges run on the calling thread */
	atomic_int bad_range;  /* start/end outside [0, item_count) or empty */
	pthread_t caller;
	int thread_count;
	int item_count;
} count_context;

static void count_task(int start, int end, int worker_index, void *task_context)
{
	count_context *c = task_context;
	if (start < 0 || end > c->item_count || start >= end)
		atomic_fetch_add(&c->bad_range, 1);
	int expected_low = c->thread_count > 1 ? 1 : 0;
	int expected_high = c->thread_count > 1 ? c->thread_count - 1 : 0;
	if (worker_index < expected_low || worker_index > expected_high)
		atomic_fetch_add(&c->bad_worker, 1);
	if (pthread_equal(pthread_self(), c->caller))
		atomic_fetch_add(&c->on_caller, 1);
	atomic_fetch_add(&c->ranges, 1);
	int size = end - start, smallest = atomic_load(&c->smallest_range);
	while (size < smallest && !atomic_compare_exchange_weak(&c->smallest_range, &smallest, size)) {
	}
	for (int i = start; i < end && i >= 0 && i < MAX_ITEMS; ++i)
		atomic_fetch_add(&c->hits[i], 1);
}

static void count_context_init(count_context *c, int thread_count, int item_count)
{
	memset(c, 0, sizeof *c);
	for (int i = 0; i < MAX_ITEMS; ++i)
		atomic_init(&c->hits[i], 0);
	atomic_init(&c->ranges, 0);
	atomic_init(&c->smallest_range, MAX_ITEMS + 1);
	atomic_init(&c->bad_worker, 0);
	atomic_init(&c->on_caller, 0);
	atomic_init(&c->bad_range, 0);
	c->caller = pthread_self();
	c->thread_count = thread_count;
	c->item_count = item_count;
}

static void check_every_item_once(int thread_count, int item_count, int min_range)
{
	plait_thread_pool *pool = plait_thread_pool_create(thread_count);
	cr_assert_not_null(pool);
	cr_expect_eq(plait_thread_pool_worker_count(pool), thread_count);
	count_context *c = malloc(sizeof *c);
	for (int repeat = 0; repeat < 20; ++repeat) {
		count_context_init(c, thread_count, item_count);
		void *handle = plait_thread_pool_enqueue(count_task, item_count, min_range, c, pool);
		if (thread_count == 1)
			cr_expect_null(handle, "a pool without threads runs the task inline and returns NULL");
		plait_thread_pool_finish(handle, pool);
		for (int i = 0; i < item_count; ++i)
			cr_assert_eq(atomic_load(&c->hits[i]), 1, "threads %d, items %d: item %d ran %d times",
			             thread_count, item_count, i, atomic_load(&c->hits[i]));
		for (int i = item_count; i < MAX_ITEMS; ++i)
			cr_assert_eq(atomic_load(&c->hits[i]), 0);
		cr_expect_eq(atomic_load(&c->bad_range), 0);
		cr_expect_eq(atomic_load(&c->bad_worker), 0, "threads %d: worker_index out of range", thread_count);
		int ranges = atomic_load(&c->ranges);
		if (thread_count > 1) {
			cr_expect_eq(atomic_load(&c->on_caller), 0, "threads %d: a range ran on the calling thread",
			             thread_count);
			cr_expect(ranges <= thread_count - 1, "threads %d: %d ranges", thread_count, ranges);
			if (item_count >= min_range)
				cr_expect(atomic_load(&c->smallest_range) >= min_range, "threads %d: a range of %d < %d",
				          thread_count, atomic_load(&c->smallest_range), min_range);
		} else {
			cr_expect_eq(ranges, 1);
		}
	}
	free(c);
	plait_thread_pool_destroy(pool);
}

Test(threads, every_item_runs_once_single_item)
{
	check_every_item_once(1, 1, 1);
	check_every_item_once(2, 1, 1);
	check_every_item_once(8, 1, 1);
}

Test(threads, every_item_runs_once_1000_items_min_range_7)
{
	check_every_item_once(1, 1000, 7);
	check_every_item_once(2, 1000, 7);
	check_every_item_once(8, 1000, 7);
	check_every_item_once(3, 10, 7); /* fewer items than min_range per thread: one range */
}

// More enqueues in flight than the pool has slots: enqueue blocks until one completes.
Test(threads, more_enqueues_than_slots)
{
	enum { enqueues = 3 * PLAIT_THREAD_POOL_SLOTS + 5 };
	plait_thread_pool *pool = plait_thread_pool_create(3);
	cr_assert_not_null(pool);
	count_context *contexts = malloc(sizeof *contexts * enqueues);
	void *handles[enqueues];
	for (int e = 0; e < enqueues; ++e) {
		count_context_init(&contexts[e], 3, 50);
		handles[e] = plait_thread_pool_enqueue(count_task, 50, 4, &contexts[e], pool);
		cr_assert_not_null(handles[e]);
	}
	for (int e = enqueues - 1; e >= 0; --e) /* in any order */
		plait_thread_pool_finish(handles[e], pool);
	for (int e = 0; e < enqueues; ++e)
		for (int i = 0; i < 50; ++i)
			cr_assert_eq(atomic_load(&contexts[e].hits[i]), 1, "enqueue %d item %d", e, i);
	free(contexts);
	plait_thread_pool_destroy(pool);
}

/* ---- A worker that starts late joins the loop under way ------------------------------------- */

/* A task system whose worker thread starts only when told (late_start.go): the first loop of a
 * frame is then posted before the worker runs. */
typedef struct late_start {
	pthread_t thread;
	plait_task_fn *task;
	void *task_context;
	atomic_int go;
	atomic_int worker_ran; /* a chunk ran on the worker */
	pthread_t caller;
} late_start;

static void *late_thread(void *argument)
{
	late_start *late = argument;
	while (!atomic_load(&late->go)) {
		sched_yield();
	}
	late->task(0, 1, 1, late->task_context);
	return NULL;
}

static void *late_enqueue(plait_task_fn *task, int item_count, int min_range, void *task_context,
                          void *user_context)
{
	(void)item_count;
	(void)min_range;
	late_start *late = user_context;
	late->task = task;
	late->task_context = task_context;
	return pthread_create(&late->thread, NULL, late_thread, late) == 0 ? late : NULL;
}

static void late_finish(void *handle, void *user_context)
{
	(void)user_context;
	late_start *late = handle;
	atomic_store(&late->go, 1);
	pthread_join(late->thread, NULL);
}

/* Chunk 0 (the caller's) lets the worker start and waits up to 5 s for it to take chunk 1. */
static void late_chunk(void *context, int begin, int end)
{
	(void)end;
	late_start *late = context;
	if (!pthread_equal(pthread_self(), late->caller)) {
		atomic_store(&late->worker_ran, 1);
		return;
	}
	if (begin == 0) {
		atomic_store(&late->go, 1);
		time_t give_up = time(NULL) + 5;
		while (!atomic_load(&late->worker_ran) && time(NULL) < give_up) {
			sched_yield();
		}
	}
}

Test(threads, a_worker_that_starts_late_joins_the_first_loop_of_the_frame)
{
	late_start late;
	memset(&late, 0, sizeof late);
	atomic_init(&late.go, 0);
	atomic_init(&late.worker_ran, 0);
	late.caller = pthread_self();
	plait_parallel parallel;
	plait_parallel_init(&parallel, late_enqueue, late_finish, &late, 2);
	/* A loop of an earlier frame, so that the first loop of this one is not the first ever. */
	plait_parallel_for(&parallel, late_chunk, &late, 2, 4, 1);
	plait_parallel_begin(&parallel);
	plait_parallel_for(&parallel, late_chunk, &late, 0, 2, 1);
	plait_parallel_end(&parallel);
	cr_expect(atomic_load(&late.worker_ran), "the worker took no chunk of the loop posted before it started");
}

Test(threads, create_attach_and_counts)
{
	cr_expect_null(plait_thread_pool_create(0));
	cr_expect_null(plait_thread_pool_create(PLAIT_THREAD_POOL_MAX_THREADS + 1));
	int cpus = plait_thread_pool_default_count();
	cr_expect(cpus >= 1 && cpus <= PLAIT_THREAD_POOL_MAX_THREADS, "default count %d", cpus);

	plait_world_def def = plait_default_world_def();
	plait_thread_pool *one = plait_thread_pool_create(1);
	cr_assert_not_null(one);
	plait_thread_pool_attach(one, &def);
	cr_expect_null(def.enqueue_task);
	cr_expect_null(def.finish_task);
	cr_expect_eq(def.worker_count, 1);
	plait_thread_pool_destroy(one);

	plait_thread_pool *four = plait_thread_pool_create(4);
	cr_assert_not_null(four);
	plait_thread_pool_attach(four, &def);
	cr_expect(def.enqueue_task == plait_thread_pool_enqueue);
	cr_expect(def.finish_task == plait_thread_pool_finish);
	cr_expect(def.task_context == four);
	cr_expect_eq(def.worker_count, 4);
	plait_thread_pool_attach(NULL, &def);
	cr_expect_null(def.enqueue_task);
	cr_expect_eq(def.worker_count, 1);
	plait_thread_pool_destroy(four);
	plait_thread_pool_destroy(NULL);
}

/* ---- The solver's pattern: one task per worker, all spinning until all have started ---------- */

typedef struct barrier_context {
	atomic_int started;
	atomic_uint_least64_t workers_seen; /* bit per worker_index */
	int worker_count;
} barrier_context;

static void spin_until_all_started(barrier_context *b)
{
	atomic_fetch_add(&b->started, 1);
	while (atomic_load(&b->started) < b->worker_count)
		sched_yield(); /* 8 workers on 2 cores: let the others in */
}

static void barrier_task(int start, int end, int worker_index, void *task_context)
{
	barrier_context *b = task_context;
	atomic_fetch_or(&b->workers_seen, (uint_least64_t)1 << worker_index);
	spin_until_all_started(b);
}

static void check_spinning_workers(int worker_count, int frames)
{
	plait_thread_pool *pool = plait_thread_pool_create(worker_count);
	cr_assert_not_null(pool);
	plait_world_def def = plait_default_world_def();
	plait_thread_pool_attach(pool, &def);
	cr_assert_eq(def.worker_count, worker_count);
	void *handles[8];
	for (int frame = 0; frame < frames; ++frame) {
		barrier_context b;
		atomic_init(&b.started, 0);
		atomic_init(&b.workers_seen, 0);
		b.worker_count = def.worker_count;
		for (int w = 1; w < def.worker_count; ++w) {
			handles[w] = def.enqueue_task(barrier_task, 1, 1, &b, def.task_context);
			cr_assert_not_null(handles[w]);
		}
		spin_until_all_started(&b); /* worker 0, on this thread */
		for (int w = 1; w < def.worker_count; ++w)
			def.finish_task(handles[w], def.task_context);
		uint_least64_t all = (((uint_least64_t)1 << worker_count) - 1) & ~(uint_least64_t)1;
		cr_assert_eq(atomic_load(&b.workers_seen), all,
		             "frame %d: the tasks did not run on distinct pool threads 1..%d", frame,
		             worker_count - 1);
	}
	plait_thread_pool_destroy(pool);
}

Test(threads, spinning_workers_two, .timeout = 120)
{
	check_spinning_workers(2, 500);
}

Test(threads, spinning_workers_eight, .timeout = 120)
{
	check_spinning_workers(8, 200);
}

/* ---- Results do not depend on the worker count ---------------------------------------------- */

/* A 40 x 40 cloth with self-collision falling on a sphere, and 64 particles dropped on it;
 * positions of both objects after 30 frames. */
/* A world run by a pool of worker_count threads (none for 1), with substeps (0: default). */
static plait_world_id pooled_world(int worker_count, int substeps, plait_thread_pool **pool)
{
	*pool = NULL;
	if (worker_count > 1) {
		*pool = plait_thread_pool_create(worker_count);
		cr_assert_not_null(*pool);
	}
	plait_world_def wdef = plait_default_world_def();
	if (substeps > 0) {
		wdef.substeps = substeps;
	}
	plait_thread_pool_attach(*pool, &wdef);
	cr_assert_eq(wdef.worker_count, worker_count);
	plait_error error = {0};
	plait_world_id world = plait_create_world(&wdef, &error);
	cr_assert(!plait_world_id_is_null(world), "%s", error.message);
	return world;
}

/* A self-colliding cloth with 64 particles dropped on it, over a sphere and the ground; with
 * `bouncy`, the cloth and particles bounce and stick to each other (mesh contacts' restitution,
 * a pass after the velocities). */
static plait_vec3 *drape_positions(int worker_count, bool bouncy, int *count)
{
	plait_thread_pool *pool;
	plait_world_id world = pooled_world(worker_count, 0, &pool);
	plait_error error = {0};

	test_grid grid = test_grid_make(40, 40, 1.6f, 1.6f);
	for (int i = 0; i < grid.vertex_count; ++i)
		grid.positions[i].y = 1.2f;
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(&grid);
	cloth.self_collide = true;
	cloth.surface.friction = 0.3f;
	cloth.surface.bounce = bouncy ? 0.6f : 0.0f;
	cloth.surface.stickiness = bouncy ? 0.3f : 0.0f;
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
	cr_assert(!plait_object_id_is_null(cloth_id), "%s", error.message);

	plait_vec3 drops[64];
	for (int i = 0; i < 64; ++i)
		drops[i] = (plait_vec3){-0.35f + 0.1f * (float)(i % 8), 1.6f, -0.35f + 0.1f * (float)(i / 8)};
	plait_particles_def particles = plait_default_particles_def();
	particles.positions = drops;
	particles.count = 64;
	particles.radius = 0.03f;
	particles.surface.bounce = bouncy ? 0.9f : 0.0f;
	plait_object_id particles_id = plait_create_particles(world, &particles, &error);
	cr_assert(!plait_object_id_is_null(particles_id), "%s", error.message);

	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.0f, 0.5f, 0.0f};
	sphere.radius = 0.5f;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &sphere, &error)), "%s", error.message);
	plait_collider_def ground = plait_default_collider_def();
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &ground, &error)), "%s", error.message);

	cr_assert(test_step_frames(world, 30));
	*count = grid.vertex_count + 64;
	plait_vec3 *x = malloc(sizeof *x * (size_t)*count);
	cr_assert_eq(plait_object_get_positions(cloth_id, 0, grid.vertex_count, x, &error), PLAIT_OK, "%s",
	             error.message);
	cr_assert_eq(plait_object_get_positions(particles_id, 0, 64, x + grid.vertex_count, &error), PLAIT_OK,
	             "%s", error.message);
	plait_destroy_world(world);
	test_grid_free(&grid);
	plait_thread_pool_destroy(pool);
	return x;
}

Test(threads, same_positions_with_1_2_and_8_workers, .timeout = 600)
{
	int count1, count2, count8;
	plait_vec3 *x1 = drape_positions(1, false, &count1);
	plait_vec3 *x2 = drape_positions(2, false, &count2);
	plait_vec3 *x8 = drape_positions(8, false, &count8);
	cr_assert_eq(count1, count2);
	cr_assert_eq(count1, count8);
	cr_expect(memcmp(x1, x2, sizeof *x1 * (size_t)count1) == 0, "2 workers give other positions than 1");
	cr_expect(memcmp(x1, x8, sizeof *x1 * (size_t)count1) == 0, "8 workers give other positions than 1");
	free(x1);
	free(x2);
	free(x8);
}

Test(threads, bouncing_and_sticking_contacts_give_the_same_positions_with_1_and_2_workers, .timeout = 600)
{
	int count1, count2;
	plait_vec3 *x1 = drape_positions(1, true, &count1);
	plait_vec3 *x2 = drape_positions(2, true, &count2);
	cr_assert_eq(count1, count2);
	cr_expect(memcmp(x1, x2, sizeof *x1 * (size_t)count1) == 0, "2 workers give other positions than 1");
	free(x1);
	free(x2);
}

/* A cloth tethered to three pins (rows of three tethers per vertex, solved exactly, which
 * straddle the workers' ranges of 2048 tethers) and hung over a sphere: tethers are split
 * between workers by particle rows, never inside one. */
static plait_vec3 *tethered_positions(int worker_count, int *count)
{
	plait_thread_pool *pool;
	plait_world_id world = pooled_world(worker_count, 4, &pool);
	plait_error error = {0};
	int n = 90;
	test_grid grid = test_grid_make(n, n, 2.0f, 2.0f);
	int pins[3] = {0, n, (n / 2) * (n + 1)};
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(&grid);
	cloth.stretch_resistance = cloth.compression_resistance = 10000.0f;
	cloth.tethers = PLAIT_TETHER_EUCLIDEAN;
	cloth.pins = pins;
	cloth.pin_count = 3;
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
	cr_assert(!plait_object_id_is_null(cloth_id), "%s", error.message);
	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.2f, -0.6f, 0.3f};
	sphere.radius = 0.5f;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &sphere, &error)), "%s", error.message);
	cr_assert(test_step_frames(world, 20));
	*count = grid.vertex_count;
	plait_vec3 *x = malloc(sizeof *x * (size_t)*count);
	cr_assert_eq(plait_object_get_positions(cloth_id, 0, *count, x, &error), PLAIT_OK, "%s", error.message);
	plait_destroy_world(world);
	test_grid_free(&grid);
	plait_thread_pool_destroy(pool);
	return x;
}

/* A bouncy, sticky sphere and a capsule under a 2 m cloth hung at y = 0. */
static void add_round_colliders(plait_world_id world)
{
	plait_error error = {0};
	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.2f, -0.6f, 0.3f};
	sphere.radius = 0.5f;
	sphere.surface.bounce = 0.4f;
	sphere.surface.stickiness = 0.3f;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &sphere, &error)), "%s", error.message);
	plait_collider_def capsule = plait_default_collider_def();
	capsule.shape = PLAIT_SHAPE_CAPSULE;
	capsule.a = (plait_vec3){-0.8f, -0.9f, -0.2f};
	capsule.b = (plait_vec3){0.6f, -0.7f, 0.4f};
	capsule.radius = 0.2f;
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &capsule, &error)), "%s", error.message);
}

/* A cloth tethered to three pins (rows of two and of three tethers), meeting a sticky, bouncy
 * sphere, a capsule and a floor with its vertices (colliders met forward and back), stepped
 * with the substeps' closing tethers and collisions folded into the last particle pass
 * (solver.c) or not. */
static plait_vec3 *closing_pass_positions(int worker_count, bool fold, bool moving_pin, int *count)
{
	plait_thread_pool *pool = worker_count > 1 ? plait_thread_pool_create(worker_count) : NULL;
	plait_world_def wdef = plait_default_world_def();
	wdef.substeps = 4;
	wdef.air_density = 0.0f; /* air comes between the passes: nothing folds */
	plait_thread_pool_attach(pool, &wdef);
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	world.world->sim.fold_closing_passes = fold;
	plait_error error = {0};
	int n = 100; /* 10,201 particles: five chunks of the folded pass, side by side */
	test_grid grid = test_grid_make(n, n, 2.0f, 2.0f);
	int pins[3] = {0, n, (n / 2) * (n + 1)};
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(&grid);
	cloth.stretch_resistance = cloth.compression_resistance = 10000.0f;
	cloth.bend_model = PLAIT_BEND_DISTANCE;
	cloth.tethers = PLAIT_TETHER_EUCLIDEAN;
	cloth.damp = 0.3f;
	cloth.collision_flag = PLAIT_COLLIDE_VERTEX; /* triangles pushed out of round colliders do not fold */
	cloth.pins = pins;
	cloth.pin_count = 3;
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
	cr_assert(!plait_object_id_is_null(cloth_id), "%s", error.message);
	add_round_colliders(world);
	plait_collider_def floor = plait_default_collider_def();
	floor.shape = PLAIT_SHAPE_PLANE;
	floor.point = (plait_vec3){0.0f, -1.2f, 0.0f};
	floor.normal = (plait_vec3){0.0f, 1.0f, 0.0f};
	cr_assert(!plait_object_id_is_null(plait_create_collider(world, &floor, &error)), "%s", error.message);
	for (int frame = 0; frame < 15; ++frame) {
		if (moving_pin) {
			/* A moving anchor: chunks must not read it while another moves it on. */
			plait_vec3 target = grid.positions[n];
			target.y += 0.01f * (float)(frame + 1);
			cr_assert_eq(plait_object_set_pin_target(cloth_id, n, target, &error), PLAIT_OK, "%s",
			             error.message);
		}
		cr_assert(test_step_frames(world, 1));
	}
	cr_assert_eq(world.world->sim.folded_substeps > 0, fold && !moving_pin, "substeps folded: %lld",
	             world.world->sim.folded_substeps);
	*count = grid.vertex_count;
	plait_vec3 *x = malloc(sizeof *x * (size_t)*count);
	cr_assert_eq(plait_object_get_positions(cloth_id, 0, *count, x, &error), PLAIT_OK, "%s", error.message);
	plait_destroy_world(world);
	test_grid_free(&grid);
	plait_thread_pool_destroy(pool);
	return x;
}

/* Several runs with workers: a tether reading an anchor that another chunk is moving shows
 * as positions that change from run to run. */
Test(threads, closing_passes_give_the_same_bits_folded_or_not, .timeout = 600)
{
	for (int moving = 0; moving <= 1; ++moving) {
		int count_apart;
		plait_vec3 *apart = closing_pass_positions(1, false, moving, &count_apart);
		int workers[] = {1, 2, 2, 8};
		for (size_t k = 0; k < sizeof workers / sizeof workers[0]; ++k) {
			int count_folded;
			plait_vec3 *folded = closing_pass_positions(workers[k], true, moving, &count_folded);
			cr_expect(memcmp(folded, apart, sizeof *folded * (size_t)count_apart) == 0,
			          "folded closing passes change the positions (%d workers, moving pin %d)", workers[k],
			          moving);
			free(folded);
		}
		free(apart);
	}
}

/* A cloth's positions, then its velocities (the closes on columns write velocities from positions
 * read there). */
static plait_vec3 *positions_and_velocities(plait_object_id cloth_id, int count)
{
	plait_error error = {0};
	plait_vec3 *both = malloc(sizeof *both * 2 * (size_t)count);
	cr_assert_eq(plait_object_get_positions(cloth_id, 0, count, both, &error), PLAIT_OK, "%s", error.message);
	cr_assert_eq(plait_object_get_velocities(cloth_id, 0, count, both + count, &error), PLAIT_OK, "%s",
	             error.message);
	return both;
}

/* A stiff cloth on `grid` hung from two pins by tethers, meeting colliders with its vertices
 * (stretch and compression rigid, distance bends). */
static plait_cloth_def hung_cloth_def(const test_grid *grid, const int *pins)
{
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.mesh = test_grid_mesh(grid);
	cloth.stretch_resistance = cloth.compression_resistance = 10000.0f;
	cloth.bend_model = PLAIT_BEND_DISTANCE;
	cloth.tethers = PLAIT_TETHER_EUCLIDEAN;
	cloth.damp = 0.3f;
	cloth.collision_flag = PLAIT_COLLIDE_VERTEX;
	cloth.pins = pins;
	cloth.pin_count = 2;
	return cloth;
}

/* A cloth hung from two pins (its tethers all rows of two), dropped onto a bouncy, sticky
 * sphere and a capsule (colliders met forward and back), with its substeps' closes on the
 * points as columns (solver.c, "Columns") or on the point array. 10,201 particles: chunks of
 * the close that are not a multiple of 16 at the end. *closed: substeps closed on columns. */
static plait_vec3 *column_close_positions(int worker_count, bool on_columns, long long *closed,
                                          bool *columns_used, int *count)
{
	plait_thread_pool *pool = worker_count > 1 ? plait_thread_pool_create(worker_count) : NULL;
	plait_world_def wdef = plait_default_world_def();
	wdef.substeps = 5;
	wdef.air_density = 0.0f;
	plait_thread_pool_attach(pool, &wdef);
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	world.world->sim.close_on_columns = on_columns;
	plait_error error = {0};
	int n = 100;
	test_grid grid = test_grid_make(n, n, 2.0f, 2.0f);
	int pins[2] = {0, n};
	plait_cloth_def cloth = hung_cloth_def(&grid, pins);
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
	cr_assert(!plait_object_id_is_null(cloth_id), "%s", error.message);
	add_round_colliders(world);
	cr_assert(test_step_frames(world, 20));
	*closed = world.world->sim.closed_on_columns;
	*columns_used = world.world->sim.use_columns && world.world->sim.simd == PLAIT_SIMD_AVX512;
	*count = grid.vertex_count;
	plait_vec3 *both = positions_and_velocities(cloth_id, *count);
	plait_destroy_world(world);
	test_grid_free(&grid);
	plait_thread_pool_destroy(pool);
	return both;
}

Test(threads, a_close_on_columns_gives_the_point_arrays_bits, .timeout = 600)
{
	long long closed = 0;
	bool columns = false;
	int count_points;
	plait_vec3 *points = column_close_positions(1, false, &closed, &columns, &count_points);
	cr_assert_eq(closed, 0);
	int workers[] = {1, 2, 8};
	for (size_t k = 0; k < sizeof workers / sizeof workers[0]; ++k) {
		int count;
		plait_vec3 *on_columns = column_close_positions(workers[k], true, &closed, &columns, &count);
		/* Columns need the AVX-512 kernels; elsewhere both runs take the point array. */
		cr_expect_eq(closed > 0, columns, "substeps closed on columns: %lld", closed);
		cr_expect(memcmp(on_columns, points, sizeof *points * 2 * (size_t)count_points) == 0,
		          "the close on columns changes positions or velocities (%d workers)", workers[k]);
		free(on_columns);
	}
	free(points);
}

/* A rigid cloth (every kind at the maximum resistance, distance bends) hung from two pins by
 * tethers onto a bouncy, sticky sphere and a capsule (pins: 0 the first row's corners, 1 the last
 * row's, 2 opposite corners; anchors in the last region are read by the first regions' closes
 * before their own region goes into columns): stretch swept twice a substep (forward, then
 * symmetric), shear and bend once (forward and backward in turn). 10,201 particles in 16 regions
 * a block. With one worker the frame runs as one wave down the regions (dynamics/wave.h) unless
 * `wave` is off; with more it never does. */
/* A task system that never starts a task (a NULL handle): the world's worker never runs. */
static void *absent_enqueue(plait_task_fn *task, int item_count, int min_range, void *task_context,
                            void *user_context)
{
	(void)task;
	(void)item_count;
	(void)min_range;
	(void)task_context;
	(void)user_context;
	return NULL;
}

static void absent_finish(void *user_task, void *user_context)
{
	(void)user_task;
	(void)user_context;
}

static bool absent_workers; /* wave_world_sized: the world's task system starts no task */

static plait_world_id wave_world_sized(plait_thread_pool *pool, bool wave, int pins_at, int n, int substeps,
                                       int iterations, test_grid *grid, plait_object_id *cloth_id)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.substeps = substeps;
	wdef.max_collision_iterations = substeps; /* once a substep: closes fold */
	wdef.contact_pass_interval = 0;           /* (a contact pass is no distance block: no wave) */
	wdef.air_density = 0.0f;
	plait_thread_pool_attach(pool, &wdef);
	if (absent_workers) {
		wdef.enqueue_task = absent_enqueue;
		wdef.finish_task = absent_finish;
		wdef.worker_count = 2;
	}
	plait_world_id world = plait_create_world(&wdef, NULL);
	cr_assert(!plait_world_id_is_null(world));
	world.world->sim.wave_frames = wave;
	plait_error error = {0};
	*grid = test_grid_make(n, n, 2.0f, 2.0f);
	int last = grid->vertex_count - 1;
	int pins[3][2] = {{0, n}, {last - n, last}, {0, last}};
	plait_cloth_def cloth = hung_cloth_def(grid, pins[pins_at]);
	cloth.shear_resistance = cloth.bend_resistance = 10000.0f;
	cloth.iterations = iterations;
	cloth.shear_iterations = cloth.bend_iterations = (iterations + 1) / 2;
	*cloth_id = plait_create_cloth(world, &cloth, &error);
	cr_assert(!plait_object_id_is_null(*cloth_id), "%s", error.message);
	add_round_colliders(world);
	return world;
}

static plait_world_id wave_world(plait_thread_pool *pool, bool wave, int pins_at, test_grid *grid,
                                 plait_object_id *cloth_id)
{
	return wave_world_sized(pool, wave, pins_at, 100, 3, 6, grid, cloth_id);
}

/* That world after `frames` frames: positions, then velocities; *waved: frames run as a wave. */
static plait_vec3 *wave_positions(int worker_count, bool wave, int pins_at, int frames, long long *waved,
                                  int *count)
{
	plait_thread_pool *pool = worker_count > 1 ? plait_thread_pool_create(worker_count) : NULL;
	test_grid grid;
	plait_object_id cloth_id;
	plait_world_id world = wave_world(pool, wave, pins_at, &grid, &cloth_id);
	cr_assert(test_step_frames(world, frames));
	*waved = world.world->sim.waved_frames;
	*count = grid.vertex_count;
	plait_vec3 *both = positions_and_velocities(cloth_id, *count);
	plait_destroy_world(world);
	test_grid_free(&grid);
	plait_thread_pool_destroy(pool);
	return both;
}

Test(threads, a_wave_gives_the_passes_bits, .timeout = 600)
{
	long long waved = 0;
	int count;
	plait_vec3 *passes = wave_positions(1, false, 0, 30, &waved, &count);
	cr_assert_eq(waved, 0);
	plait_vec3 *waves = wave_positions(1, true, 0, 30, &waved, &count);
	/* The wave projects on columns, which need the AVX-512 kernels. */
	bool columns = plait_simd_is_supported(PLAIT_SIMD_AVX512);
	cr_expect_eq(waved > 0, columns, "frames run as a wave: %lld", waved);
	if (columns) {
		cr_expect_eq(waved, 30, "frames run as a wave: %lld of 30", waved);
	}
	cr_expect(memcmp(waves, passes, sizeof *passes * 2 * (size_t)count) == 0,
	          "the wave changes positions or velocities");
	int workers[] = {2, 8};
	for (size_t k = 0; k < sizeof workers / sizeof workers[0]; ++k) {
		plait_vec3 *threaded = wave_positions(workers[k], true, 0, 30, &waved, &count);
		/* Two threads run it in pieces (below); eight do not fit 16 regions: the passes. */
		if (workers[k] == 8) {
			cr_expect_eq(waved, 0, "a wave on %d workers", workers[k]);
		}
		cr_expect(memcmp(threaded, waves, sizeof *waves * 2 * (size_t)count) == 0,
		          "%d workers give other positions or velocities than a wave on one", workers[k]);
		free(threaded);
	}
	free(passes);
	free(waves);
	/* Anchors in the last region, from the first frame (columns never filled before) on. */
	for (int pins_at = 1; pins_at <= 2; ++pins_at) {
		for (int frames = 1; frames <= 5; frames += 4) {
			passes = wave_positions(1, false, pins_at, frames, &waved, &count);
			waves = wave_positions(1, true, pins_at, frames, &waved, &count);
			cr_expect_eq(waved > 0, columns, "pins %d: frames run as a wave: %lld", pins_at, waved);
			cr_expect(memcmp(waves, passes, sizeof *passes * 2 * (size_t)count) == 0,
			          "pins %d, %d frames: the wave changes positions or velocities", pins_at, frames);
			free(passes);
			free(waves);
		}
	}
}

/* A wave world of n x n quads and `substeps` run on `worker_count` workers, the wave in pieces
 * whatever the cloth's size (dynamics/wave.h, "Pieces"); after its first frame the line between
 * the first two threads moves by `line_step` regions a frame, back and forth (any lines give the
 * same bits). Positions, then velocities; *pieced: frames run as a wave in pieces. */
static int piece_rows; /* piece_positions: rows of the last plan */

static plait_vec3 *piece_positions(int worker_count, int pins_at, int n, int substeps, int iterations,
                                   int frames, int line_step, long long *pieced, int *count)
{
	plait_thread_pool *pool = worker_count > 1 ? plait_thread_pool_create(worker_count) : NULL;
	test_grid grid;
	plait_object_id cloth_id;
	plait_world_id world = wave_world_sized(pool, true, pins_at, n, substeps, iterations, &grid, &cloth_id);
	for (int frame = 0; frame < frames; ++frame) {
		cr_assert(test_step_frames(world, 1));
		plait_wave_plan *plan = world.world->sim.wave_plan;
		if (line_step != 0 && plan != NULL && plan->made) {
			int lines[2] = {0, plan->line[1] + (frame % 2 == 0 ? line_step : -line_step / 2)};
			cr_expect(plait_wave_plan_set_lines(plan, lines), "line %d does not fit", lines[1]);
		}
	}
	*pieced = world.world->sim.pieced_frames;
	const plait_wave_plan *plan = world.world->sim.wave_plan;
	piece_rows = plan != NULL && plan->made ? plan->rows : 0;
	*count = grid.vertex_count;
	plait_vec3 *both = positions_and_velocities(cloth_id, *count);
	plait_destroy_world(world);
	test_grid_free(&grid);
	plait_thread_pool_destroy(pool);
	return both;
}

/* A wave world of n x n quads on one thread, the passes one after another, after `frames`. */
static plait_vec3 *passes_positions(int n, int substeps, int iterations, int frames, int *count)
{
	test_grid grid;
	plait_object_id cloth_id;
	plait_world_id world = wave_world_sized(NULL, false, 0, n, substeps, iterations, &grid, &cloth_id);
	cr_assert(test_step_frames(world, frames));
	*count = grid.vertex_count;
	plait_vec3 *both = positions_and_velocities(cloth_id, *count);
	plait_destroy_world(world);
	test_grid_free(&grid);
	return both;
}

/* (Pieces need the AVX-512 kernels, as the wave does: elsewhere both runs take the passes, and
 * the test only shows that. A frame whose workers are not all running within 10 ms takes the
 * passes too, so a loaded machine may run fewer frames in pieces; the bits must not change.) */
Test(threads, a_wave_in_pieces_gives_the_passes_bits, .timeout = 600)
{
	bool columns = plait_simd_is_supported(PLAIT_SIMD_AVX512);
	long long waved = 0, pieced = 0;
	int count;
	/* 16 regions and 15 slots a frame: two threads' line can only be at region 1. Pins in the
	 * first row, the last row and opposite corners (anchors read by both threads' closes). */
	for (int pins_at = 0; pins_at <= 2; ++pins_at) {
		plait_vec3 *passes = wave_positions(1, false, pins_at, 6, &waved, &count);
		plait_vec3 *pieces = piece_positions(2, pins_at, 100, 3, 6, 6, 0, &pieced, &count);
		cr_expect_eq(pieced > 0, columns, "pins %d: frames run in pieces: %lld of 6", pins_at, pieced);
		cr_expect(memcmp(pieces, passes, sizeof *passes * 2 * (size_t)count) == 0,
		          "pins %d: a wave in pieces on two threads changes positions or velocities", pins_at);
		free(passes);
		free(pieces);
	}
	/* 16 regions and 6 substeps of 4 slots (stretch, shear, bend, close): two threads' lines do
	 * not fit the frame's 24 slots, so it runs in rows (of one substep: a quarter of the regions),
	 * each a wave in pieces (the rows' sweeps differ: shear and bend alternate direction; the
	 * regions enter columns before the first row, and leave after the last one's last slot). */
	{
		plait_vec3 *passes6 = passes_positions(100, 6, 6, 4, &count);
		plait_vec3 *pieces6 = piece_positions(2, 0, 100, 6, 6, 4, 0, &pieced, &count);
		cr_expect_eq(pieced > 0, columns, "rows: frames run in pieces: %lld of 4", pieced);
		if (columns) {
			cr_expect_gt(piece_rows, 1, "one row for 24 slots over 16 regions");
		}
		cr_expect(memcmp(pieces6, passes6, sizeof *passes6 * 2 * (size_t)count) == 0,
		          "a wave in rows of pieces changes positions or velocities");
		free(passes6);
		free(pieces6);
	}
	/* 40 regions and 8 slots (two substeps of one sweep of each kind): lines for 2, 3 and 8
	 * threads, and two threads' line moved every frame, 3 regions on and 1 back. */
	plait_vec3 *passes = passes_positions(200, 2, 1, 5, &count);
	int workers[] = {2, 3, 8, 2};
	for (size_t k = 0; k < sizeof workers / sizeof workers[0]; ++k) {
		int step = k == 3 ? 3 : 0;
		plait_vec3 *pieces = piece_positions(workers[k], 0, 200, 2, 1, 5, step, &pieced, &count);
		cr_expect_eq(pieced > 0, columns, "%d workers: frames run in pieces: %lld of 5", workers[k], pieced);
		cr_expect(memcmp(pieces, passes, sizeof *passes * 2 * (size_t)count) == 0,
		          "%d workers (line moved by %d): a wave in pieces changes positions or velocities",
		          workers[k], step);
		free(pieces);
	}
	free(passes);
}

/* In pieces the threads wait for each other, so a frame whose worker never started (a task
 * system that gave a NULL handle) runs the passes, on the calling thread alone, to the same bits. */
Test(threads, a_wave_without_its_worker_runs_the_passes, .timeout = 120)
{
	long long waved = 0;
	int count;
	plait_vec3 *passes = wave_positions(1, false, 0, 3, &waved, &count);
	absent_workers = true;
	long long pieced = 0;
	plait_vec3 *alone = piece_positions(1, 0, 100, 3, 6, 3, 0, &pieced, &count);
	absent_workers = false;
	cr_expect_eq(pieced, 0, "frames run in pieces without a worker: %lld", pieced);
	cr_expect(memcmp(alone, passes, sizeof *passes * 2 * (size_t)count) == 0,
	          "a world whose worker never started gives other positions or velocities");
	free(passes);
	free(alone);
}

/* A wave checks each region as it leaves columns (solver.c): a velocity that overflows in the
 * last region fails the frame, and the frame's start comes back to the bit. */
static void check_wave_rolled_back(int worker_count)
{
	plait_thread_pool *pool = worker_count > 1 ? plait_thread_pool_create(worker_count) : NULL;
	test_grid grid;
	plait_object_id cloth_id;
	plait_world_id world = wave_world(pool, true, 0, &grid, &cloth_id);
	cr_assert(test_step_frames(world, 2));
	int count = grid.vertex_count;
	plait_vec3 *x = malloc(sizeof *x * (size_t)count), *v = malloc(sizeof *v * (size_t)count);
	plait_vec3 *out = malloc(sizeof *out * (size_t)count);
	plait_error error = {0};
	cr_assert_eq(plait_object_get_positions(cloth_id, 0, count, x, &error), PLAIT_OK);
	cr_assert_eq(plait_object_get_velocities(cloth_id, 0, count, v, &error), PLAIT_OK);
	v[count - 3] = (plait_vec3){3e38f, 0.0f, 0.0f};
	cr_assert_eq(plait_object_set_velocities(cloth_id, 0, count, v, &error), PLAIT_OK);
	long long waved = world.world->sim.waved_frames, pieced = world.world->sim.pieced_frames;
	cr_assert_eq(plait_world_step(world, &error), PLAIT_ERROR_NONFINITE);
	if (plait_simd_is_supported(PLAIT_SIMD_AVX512)) {
		cr_expect_eq(world.world->sim.waved_frames, waved + 1, "the failed frame did not run as a wave");
		cr_expect_eq(world.world->sim.pieced_frames, pieced + (worker_count > 1 ? 1 : 0),
		             "the failed frame did not run in pieces on %d workers", worker_count);
	}
	cr_assert_eq(plait_world_get_frame(world), 2);
	cr_assert_eq(plait_object_get_positions(cloth_id, 0, count, out, &error), PLAIT_OK);
	cr_expect(memcmp(out, x, sizeof *x * (size_t)count) == 0, "positions were not restored");
	cr_assert_eq(plait_object_get_velocities(cloth_id, 0, count, out, &error), PLAIT_OK);
	cr_expect(memcmp(out, v, sizeof *v * (size_t)count) == 0, "velocities were not restored");
	free(x);
	free(v);
	free(out);
	plait_destroy_world(world);
	test_grid_free(&grid);
	plait_thread_pool_destroy(pool);
}

Test(threads, a_wave_going_non_finite_is_rolled_back_to_the_bit, .timeout = 600)
{
	check_wave_rolled_back(1);
	check_wave_rolled_back(2);
}

Test(threads, tethered_cloth_same_with_1_2_and_8_workers, .timeout = 600)
{
	int count1, count2, count8;
	plait_vec3 *x1 = tethered_positions(1, &count1);
	plait_vec3 *x2 = tethered_positions(2, &count2);
	plait_vec3 *x8 = tethered_positions(8, &count8);
	cr_expect(memcmp(x1, x2, sizeof *x1 * (size_t)count1) == 0, "2 workers give other positions than 1");
	cr_expect(memcmp(x1, x8, sizeof *x1 * (size_t)count1) == 0, "8 workers give other positions than 1");
	free(x1);
	free(x2);
	free(x8);
}

/* ---- plait run --threads -------------------------------------------------------------------- */

Test(threads, run_rejects_bad_thread_counts)
{
	const char *cases[][4] = {
	    {"plait", "run", "--threads", "0"},   {"plait", "run", "--threads", "257"},
	    {"plait", "run", "--threads", "two"}, {"plait", "run", "--threads", "2x"},
	    {"plait", "run", "--threads", "-3"},  {"plait", "run", "--threads", ""},
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
		cli_result r = run_cli(4, cases[i]);
		cr_expect_eq(r.code, PLAIT_EXIT_USAGE, "--threads '%s': exit %d", cases[i][3], r.code);
		cr_expect(strstr(r.err, "--threads expects a whole number from 1 to 256") != NULL, "%s", r.err);
		cr_expect(strstr(r.err, "usage:") != NULL, "%s", r.err);
		free_result(&r);
	}
	const char *missing[] = {"plait", "run", "--threads"};
	cli_result r = run_cli(3, missing);
	cr_expect_eq(r.code, PLAIT_EXIT_USAGE);
	cr_expect(strstr(r.err, "--threads needs a value") != NULL, "%s", r.err);
	free_result(&r);

	const char *help[] = {"plait", "run", "--help"};
	r = run_cli(3, help);
	cr_expect_eq(r.code, PLAIT_EXIT_OK);
	cr_expect(strstr(r.out, "--threads N") != NULL, "%s", r.out);
	free_result(&r);
}

Test(threads, run_writes_the_same_frames_with_any_thread_count, .timeout = 300)
{
	char dir[] = "/tmp/plait_threads_test_XXXXXX";
	cr_assert_not_null(mkdtemp(dir));
	char scene[1100], out1[1100], out3[1100];
	snprintf(scene, sizeof scene, "%s/scene.json", dir);
	snprintf(out1, sizeof out1, "%s/one", dir);
	snprintf(out3, sizeof out3, "%s/three", dir);
	FILE *f = fopen(scene, "w");
	cr_assert_not_null(f);
	fputs("{\"world\": {\"fps\": 24}, \"frames\": 4, \"objects\": [\n"
	      " {\"name\": \"sheet\", \"type\": \"cloth\", \"grid\": {\"size\": [1, 1], \"resolution\": [8, 8],\n"
	      "  \"center\": [0, 1, 0]}, \"pins\": [0, 8]},\n"
	      " {\"name\": \"ball\", \"type\": \"collider\", \"shape\": \"sphere\", \"center\": [0, 0.5, 0], "
	      "\"radius\": 0.3}]}\n",
	      f);
	fclose(f);
	const char *run1[] = {"plait", "run", scene, "--out", out1, "--format", "pc2", "--threads", "1"};
	const char *run3[] = {"plait", "run", scene, "--out", out3, "--format=pc2", "--threads=3"};
	cli_result r1 = run_cli(9, run1);
	cr_expect_eq(r1.code, PLAIT_EXIT_OK, "%s", r1.err);
	cli_result r3 = run_cli(7, run3);
	cr_expect_eq(r3.code, PLAIT_EXIT_OK, "%s", r3.err);
	free_result(&r1);
	free_result(&r3);
	char path1[1200], path3[1200];
	snprintf(path1, sizeof path1, "%s/sheet.pc2", out1);
	snprintf(path3, sizeof path3, "%s/sheet.pc2", out3);
	size_t size1 = 0, size3 = 0;
	char *data1 = read_file(path1, &size1), *data3 = read_file(path3, &size3);
	cr_assert_not_null(data1);
	cr_assert_not_null(data3);
	cr_expect_eq(size1, 32 + 5 * 81 * 12);
	cr_expect(size1 == size3 && memcmp(data1, data3, size1) == 0, "--threads 3 wrote other frames than 1");
	free(data1);
	free(data3);
	remove_tree(dir);
}

/* ---- examples/hang-128.json: the hang-128 benchmark as a scene --------------------------------- */

Test(threads, hang_128_example_scene_loads, .timeout = 300)
{
	plait_scene scene;
	plait_tool_error error = {{0}};
	cr_assert(plait_scene_load(PLAIT_SOURCE_DIR "/examples/hang-128.json", &scene, &error), "%s",
	          error.message);
	cr_expect_eq(scene.warning_count, 0);
	cr_expect_eq(scene.frames, 300);
	cr_expect_float_eq(scene.world.fps, 60.0f, 0.0f);
	cr_expect_float_eq(scene.world.gravity.y, -9.81f, 1e-6f);
	cr_assert_eq(scene.object_count, 2);
	const plait_scene_object *cloth = &scene.objects[0];
	cr_expect_eq(cloth->type, PLAIT_OBJECT_CLOTH);
	cr_assert_eq(cloth->vertex_count, 128 * 128);
	cr_expect_eq(cloth->face_count, 127 * 127);
	cr_assert_eq(cloth->pin_count, 2);
	// The pins are the corners at z = -1, x = -1 and x = +1.
	for (int p = 0; p < 2; ++p) {
		plait_vec3 x = cloth->positions[cloth->pins[p]];
		cr_expect_float_eq(x.z, -1.0f, 1e-6f, "pin %d at z %g", p, (double)x.z);
		cr_expect_float_eq(x.y, 0.0f, 1e-6f);
		cr_expect_float_eq(fabsf(x.x), 1.0f, 1e-6f, "pin %d at x %g", p, (double)x.x);
	}
	cr_expect(cloth->positions[cloth->pins[0]].x != cloth->positions[cloth->pins[1]].x);
	// 1 kg per vertex on average: 16384 kg over 4 m^2.
	cr_expect_float_eq(cloth->cloth.density * 4.0f, 16384.0f, 1e-3f);
	cr_expect_float_eq(cloth->cloth.stretch_resistance, 10000.0f, 0.0f);
	cr_expect_float_eq(cloth->cloth.compression_resistance, 10000.0f, 0.0f);
	// The comparison's constraint set: shear and skip-one bend edges, rigid, once per substep.
	cr_expect_float_eq(cloth->cloth.shear_resistance, 10000.0f, 0.0f);
	cr_expect_float_eq(cloth->cloth.bend_resistance, 10000.0f, 0.0f);
	cr_expect_eq(cloth->cloth.bend_model, PLAIT_BEND_DISTANCE);
	cr_expect_eq(scene.world.substeps, 6);
	cr_expect_eq(cloth->cloth.iterations, 6);
	cr_expect_eq(cloth->cloth.tethers, PLAIT_TETHER_EUCLIDEAN);
	const plait_scene_object *sphere = &scene.objects[1];
	cr_expect_eq(sphere->type, PLAIT_OBJECT_COLLIDER);
	cr_expect_eq(sphere->collider.shape, PLAIT_SHAPE_SPHERE);
	cr_expect_float_eq(sphere->collider.radius, 0.5f, 0.0f);
	cr_expect_float_eq(sphere->collider.center.y, -0.75f, 0.0f);

	// The solver takes it (one frame only: the scene is heavy for a test, above all under ASan).
	plait_thread_pool *pool = plait_thread_pool_create(2);
	cr_assert_not_null(pool);
	plait_thread_pool_attach(pool, &scene.world);
	plait_world_id world;
	cr_assert(plait_scene_create_world(&scene, &world, &error), "%s", error.message);
	cr_expect(plait_scene_apply_frame(&scene, world, 1, &error), "%s", error.message);
	cr_expect(test_step_frames(world, 1));
	plait_destroy_world(world);
	plait_scene_free(&scene);
	plait_thread_pool_destroy(pool);
}

/* A collision scene's cloth positions after `frames` frames with worker_count workers. */
/* A collision scene run on the workers: with options, and (pin_frames > 0) with a row of n
 * vertices across its second cloth (n x n) pinned where they are for pin_frames frames from
 * frame pin_at, then let go. */
typedef struct threads_scene {
	collide_scene_kind kind;
	int n, frames;
	collide_scene_options options;
	int pin_at, pin_frames;
	int contact_pass_interval; /* plait_world_def's */
} threads_scene;

static void pin_row(const collide_scene *scene, int n, bool pin)
{
	plait_object_id sheet = scene->cloths[1];
	plait_error error;
	for (int k = 0; k < n; ++k) {
		int v = n * (n / 2) + k;
		plait_vec3 x;
		cr_assert_eq(plait_object_get_positions(sheet, v, 1, &x, NULL), PLAIT_OK);
		plait_result r =
		    pin ? plait_object_pin_vertex(sheet, v, x, &error) : plait_object_unpin_vertex(sheet, v, &error);
		cr_assert_eq(r, PLAIT_OK, "%s", error.message);
	}
}

static plait_vec3 *collide_scene_positions(const threads_scene *run, int worker_count, int *count)
{
	plait_thread_pool *pool = NULL;
	plait_world_def wdef = plait_default_world_def();
	wdef.contact_pass_interval = run->contact_pass_interval;
	if (worker_count > 1) {
		pool = plait_thread_pool_create(worker_count);
		cr_assert_not_null(pool);
	}
	plait_thread_pool_attach(pool, &wdef);
	collide_scene scene;
	plait_error error = {0};
	cr_assert(collide_scene_create_with(&scene, run->kind, run->n, &wdef, &run->options, &error), "%s",
	          error.message);
	for (int f = 0; f < run->frames; ++f) {
		if (run->pin_frames > 0 && (f == run->pin_at || f == run->pin_at + run->pin_frames)) {
			pin_row(&scene, run->n, f == run->pin_at);
		}
		cr_assert_eq(collide_scene_step(&scene, &error), PLAIT_OK, "%s", error.message);
	}
	*count = 0;
	for (int c = 0; c < scene.cloth_count; ++c) {
		*count += plait_object_get_vertex_count(scene.cloths[c]);
	}
	plait_vec3 *x = malloc(sizeof *x * (size_t)*count);
	int at = 0;
	for (int c = 0; c < scene.cloth_count; ++c) {
		int vertices = plait_object_get_vertex_count(scene.cloths[c]);
		cr_assert_eq(plait_object_get_positions(scene.cloths[c], 0, vertices, x + at, &error), PLAIT_OK, "%s",
		             error.message);
		at += vertices;
	}
	collide_scene_destroy(&scene);
	plait_thread_pool_destroy(pool);
	return x;
}

/* Mesh contacts list pairs and sweep them in the failsafe on the workers (mesh_contact_pieces.c,
 * pieces joined in the traversal's order; crossings joined into impact zones in that order):
 * the thin box (a sheet at 20 m/s onto 1 mm, where the failsafe acts in most frames), the
 * drape of two sheets and a small self-colliding hang (flat patches fitted and checked on the
 * workers, lists mended around strayed vertices on them) give the same bits with 1, 2 and 8
 * workers; so does a pile of four 36 x 36 sheets, whose lists (75,000-91,000 pairs as it
 * settles) are long enough to be projected on the workers, group beside group
 * (mesh_contact_plan.c): with a
 * row across a sheet pinned for two frames (groups side by side then share pinned vertices),
 * and falling onto a coarse sheet (pairs across many slabs, projected after the groups). With
 * contact passes (contact.h) between the collision iterations: the drape, the pile (pairs that
 * pushed projected again in the plan's groups) and the arm (its capsules' pass over the
 * particles that touched them). */
Test(threads, collision_scenes_same_with_1_2_and_8_workers, .timeout = 600)
{
	collide_scene_options plain = collide_scene_default_options(), coarse = plain;
	coarse.coarse_floor = true;
	enum { RUNS = 8 };
	threads_scene runs[RUNS] = {
	    {SCENE_THIN_BOX, 24, 24, plain, 0, 0, 0},  {SCENE_DRAPE, 24, 40, plain, 0, 0, 0},
	    {SCENE_HANG_SELF, 24, 60, plain, 0, 0, 0}, {SCENE_PILE, 36, 36, plain, 30, 2, 0},
	    {SCENE_PILE, 32, 38, coarse, 0, 0, 0},     {SCENE_DRAPE, 24, 40, plain, 0, 0, 1},
	    {SCENE_PILE, 36, 36, plain, 0, 0, 1},      {SCENE_ARM, 16, 60, plain, 0, 0, 1}};
	for (int k = 0; k < RUNS; ++k) {
		int count1, count2, count8;
		plait_vec3 *x1 = collide_scene_positions(&runs[k], 1, &count1);
		plait_vec3 *x2 = collide_scene_positions(&runs[k], 2, &count2);
		plait_vec3 *x8 = collide_scene_positions(&runs[k], 8, &count8);
		cr_assert_eq(count1, count2);
		cr_assert_eq(count1, count8);
		const char *name = collide_scene_names[runs[k].kind];
		cr_expect(memcmp(x1, x2, sizeof *x1 * (size_t)count1) == 0,
		          "%s (%d): 2 workers give other positions than 1", name, k);
		cr_expect(memcmp(x1, x8, sizeof *x1 * (size_t)count1) == 0,
		          "%s (%d): 8 workers give other positions than 1", name, k);
		free(x1);
		free(x2);
		free(x8);
	}
}
