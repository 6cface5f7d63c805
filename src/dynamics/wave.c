#include "dynamics/wave.h"

#include <string.h>

#include "core/clock.h"

#include "dynamics/colouring.h"

bool plait_wave_takes(const plait_distance_block *block, int regions, int particle_count)
{
	const plait_colouring *colouring = &block->colouring;
	return block->compliant_count == 0 && colouring->boundary_cut_start != NULL &&
	       colouring->region_count == regions && colouring->particle_count == particle_count &&
	       plait_colouring_end(colouring) == block->count;
}

static void run_cut(plait_wave *wave, int o, int cut, bool head)
{
	const plait_wave_slot *slot = &wave->slots[o];
	bool backward = head ? slot->sweep == PLAIT_SWEEP_BACKWARD : slot->sweep == PLAIT_SWEEP_SYMMETRIC;
	plait_distance_sweep_cut(slot->block, wave->columns, cut, wave->inverse_h_squared, backward);
}

/* Slot o's part of region q itself: its sweep, or its close (and after the last slot, leaving
 * columns). */
static void run_region(plait_wave *wave, int o, int q)
{
	const plait_wave_slot *slot = &wave->slots[o];
	if (slot->block != NULL) {
		plait_distance_sweep_region(slot->block, wave->columns, q, wave->inverse_h_squared, slot->sweep);
		return;
	}
	int begin = plait_region_first(q, wave->regions, wave->particle_count),
	    end = plait_region_first(q + 1, wave->regions, wave->particle_count);
	wave->close(wave->context, slot->substep, begin, end);
	if (o == wave->slot_count - 1) {
		wave->leave(wave->context, begin, end);
	}
}

/* A slot's shape: its sweep, or -1 for a close. The one rule for both the wave on one thread and
 * the plan of its pieces: a sweep other than forward has a head (a boundary swept before the
 * regions), one other than backward a tail (after them). */
static int slot_shape(const plait_wave *wave, int o)
{
	return wave->slots[o].block == NULL ? -1 : (int)wave->slots[o].sweep;
}
static bool shape_has_head(int shape)
{
	return shape >= 0 && shape != PLAIT_SWEEP_FORWARD;
}
static bool shape_has_tail(int shape)
{
	return shape >= 0 && shape != PLAIT_SWEEP_BACKWARD;
}

void plait_wave_run(plait_wave *wave)
{
	int regions = wave->regions, slots = wave->slot_count;
	for (int t = 0; t < regions + slots; ++t) {
		if (t < regions) {
			wave->enter(wave->context, plait_region_first(t, regions, wave->particle_count),
			            plait_region_first(t + 1, regions, wave->particle_count));
		}
		for (int o = 0; o < slots; ++o) {
			int q = t - 1 - o;
			if (q < 0) {
				break;
			}
			if (q >= regions) {
				continue;
			}
			if (shape_has_head(slot_shape(wave, o)) && q + 1 < regions) {
				run_cut(wave, o, q, true);
			}
			run_region(wave, o, q);
			if (shape_has_tail(slot_shape(wave, o)) && q > 0) {
				run_cut(wave, o, q - 1, false);
			}
		}
	}
}

/* Pieces (wave.h). */

bool plait_wave_plan_reserve(plait_wave_plan *plan, const plait_allocator *allocator, int regions,
                             int participants)
{
	plait_wave_plan_destroy(plan, allocator);
	participants = participants < 1 ? 1 : participants > PLAIT_MAX_WORKERS ? PLAIT_MAX_WORKERS : participants;
	size_t tasks = (size_t)PLAIT_WAVE_MAX_SLOTS * 3 * (size_t)(regions > 0 ? regions : 1);
	plan->tasks = plait_alloc(allocator, sizeof(plait_wave_task) * tasks);
	plan->waits = plait_alloc(allocator, sizeof(int[3]) * tasks);
	plan->done = plait_alloc(allocator, sizeof(_Atomic uint32_t) * tasks);
	plan->in_order = plait_alloc(allocator, sizeof(plait_wave_task) * tasks);
	plan->before = plait_alloc(allocator, sizeof(int[3]) * tasks);
	plan->owner = plait_alloc(allocator, sizeof(int) * (tasks + 3 * (size_t)regions));
	plan->position = plait_alloc(allocator, sizeof(int) * tasks);
	plan->list_start = plait_alloc(
	    allocator,
	    sizeof(int) * ((size_t)(PLAIT_WAVE_MAX_SLOTS / PLAIT_WAVE_LEAST_ROW) * (size_t)participants + 1));
	if (plan->tasks == NULL || plan->waits == NULL || plan->done == NULL || plan->in_order == NULL ||
	    plan->before == NULL || plan->owner == NULL || plan->position == NULL || plan->list_start == NULL) {
		plait_wave_plan_destroy(plan, allocator);
		return false;
	}
	for (size_t n = 0; n < tasks; ++n) {
		atomic_init(&plan->done[n], 0);
	}
	plan->task_capacity = (int)tasks;
	plan->region_capacity = regions;
	plan->participant_capacity = participants;
	return true;
}

void plait_wave_plan_destroy(plait_wave_plan *plan, const plait_allocator *allocator)
{
	plait_free(allocator, plan->tasks);
	plait_free(allocator, plan->waits);
	plait_free(allocator, (void *)plan->done);
	plait_free(allocator, plan->in_order);
	plait_free(allocator, plan->before);
	plait_free(allocator, plan->owner);
	plait_free(allocator, plan->position);
	plait_free(allocator, plan->list_start);
	memset(plan, 0, sizeof *plan);
}

/* The thread that runs region q at slot o: thread k from region line[k] + o on. */
static int owner_of(const plait_wave_plan *plan, int o, int q)
{
	int k = 0;
	while (k + 1 < plan->participants && q >= plan->line[k + 1] + o) {
		k += 1;
	}
	return k;
}

/* The thread of a task: a region's; a cut's head that of the region after it (the head comes
 * before both regions, so the later thread runs it and the earlier waits), a tail that of the
 * region before it (after both: the earlier thread runs it and waits). */
static int task_owner(const plait_wave_plan *plan, plait_wave_task task, int row_slot)
{
	return owner_of(plan, row_slot, task.kind == PLAIT_WAVE_HEAD ? task.index + 1 : task.index);
}

/* The particle sets a task touches: region q's own (3q), the cut q's in region q (3q + 1) and in
 * region q + 1 (3q + 2). */
static int touched_sets(const plait_wave_plan *plan, plait_wave_task task, int sets[3])
{
	int q = task.index;
	if (task.kind != PLAIT_WAVE_REGION) {
		sets[0] = 3 * q + 1;
		sets[1] = 3 * q + 2;
		return 2;
	}
	int count = 0;
	sets[count++] = 3 * q;
	if (q + 1 < plan->regions) {
		sets[count++] = 3 * q + 1;
	}
	if (q > 0) {
		sets[count++] = 3 * (q - 1) + 2;
	}
	return count;
}

/* Row `row`'s tasks in the wave's order (plait_wave_run's over the row's slots), from the plan's
 * slot shapes; their slots are the frame's. */
static int tasks_in_order(const plait_wave_plan *plan, int row, plait_wave_task *out)
{
	int regions = plan->regions, slots = plan->slot_count, first = row * slots, count = 0;
	for (int t = 0; t < regions + slots; ++t) {
		for (int o = 0; o < slots; ++o) {
			int q = t - 1 - o, shape = plan->slot_shape[first + o];
			int16_t slot = (int16_t)(first + o);
			if (q < 0) {
				break;
			}
			if (q >= regions) {
				continue;
			}
			if (shape_has_head(shape) && q + 1 < regions) {
				out[count++] = (plait_wave_task){slot, PLAIT_WAVE_HEAD, q};
			}
			out[count++] = (plait_wave_task){slot, PLAIT_WAVE_REGION, q};
			if (shape_has_tail(shape) && q > 0) {
				out[count++] = (plait_wave_task){slot, PLAIT_WAVE_TAIL, q - 1};
			}
		}
	}
	return count;
}

/* Whether every thread has regions at every slot: each line within the cloth through the frame. */
static bool lines_fit(const plait_wave_plan *plan)
{
	for (int k = 1; k < plan->participants; ++k) {
		int low = k > 1 ? plan->line[k - 1] + 1 : 1;
		if (plan->line[k] < low || plan->line[k] + plan->slot_count - 1 > plan->regions - 1) {
			return false;
		}
	}
	return true;
}

/* Each row's list of tasks for each thread (list row * participants + k), in the wave's order,
 * and what each task waits for: the task before it in its row on each of its particle sets when
 * another thread runs that one (rows end in a barrier). */
static void plan_lists(plait_wave_plan *plan)
{
	int participants = plan->participants, lists = plan->rows * participants, count = 0;
	int *last = plan->owner + plan->task_capacity;
	int *start = plan->list_start;
	memset(start, 0, sizeof(int) * (size_t)(lists + 1));
	for (int row = 0; row < plan->rows; ++row) {
		for (int k = 0; k < 3 * plan->regions; ++k) {
			last[k] = -1;
		}
		int end = count + tasks_in_order(plan, row, plan->in_order + count);
		for (int n = count; n < end; ++n) {
			plait_wave_task task = plan->in_order[n];
			int sets[3], set_count = touched_sets(plan, task, sets);
			int owner = task_owner(plan, task, task.slot - row * plan->slot_count);
			plan->owner[n] = row * participants + owner;
			start[plan->owner[n] + 1] += 1;
			for (int k = 0; k < 3; ++k) {
				plan->before[n][k] = k < set_count ? last[sets[k]] : -1;
			}
			for (int k = 0; k < set_count; ++k) {
				last[sets[k]] = n;
			}
		}
		count = end;
	}
	for (int l = 0; l < lists; ++l) {
		start[l + 1] += start[l];
	}
	for (int n = 0; n < count; ++n) {
		plan->position[n] = start[plan->owner[n]]++;
		plan->tasks[plan->position[n]] = plan->in_order[n];
	}
	for (int l = lists; l > 0; --l) {
		start[l] = start[l - 1];
	}
	start[0] = 0;
	for (int n = 0; n < count; ++n) {
		int *waits = plan->waits[plan->position[n]];
		for (int k = 0; k < 3; ++k) {
			int before = plan->before[n][k];
			waits[k] = before >= 0 && plan->owner[before] != plan->owner[n] ? plan->position[before] : -1;
		}
	}
}

/* Lines that give each thread an equal share of a row's region tasks (the first k threads hold
 * sum over o of (line[k] + o) of them, clipped to the cloth); whether they fit. */
static bool place_lines(plait_wave_plan *plan)
{
	int regions = plan->regions, slots = plan->slot_count, participants = plan->participants;
	for (int k = 1; k < participants; ++k) {
		int64_t goal = (int64_t)regions * slots * k / participants, best_miss = -1;
		for (int x = -slots; x <= regions; ++x) {
			int64_t held = 0;
			for (int o = 0; o < slots; ++o) {
				int width = x + o;
				held += width < 0 ? 0 : width > regions ? regions : width;
			}
			int64_t miss = held > goal ? held - goal : goal - held;
			if (best_miss < 0 || miss < best_miss) {
				best_miss = miss;
				plan->line[k] = x;
			}
		}
	}
	return lines_fit(plan);
}

/* The frame's slots in `rows` rows of one height (at least PLAIT_WAVE_LEAST_ROW), lines placed;
 * whether they fit. */
static bool try_rows(plait_wave_plan *plan, int rows)
{
	int slots = plan->frame_slots;
	if (slots % rows != 0 || slots / rows < PLAIT_WAVE_LEAST_ROW) {
		return false;
	}
	plan->rows = rows;
	plan->slot_count = slots / rows;
	return place_lines(plan);
}

bool plait_wave_plan_make(plait_wave_plan *plan, const plait_wave *wave, int participants)
{
	int slots = wave->slot_count, regions = wave->regions;
	if (plan->tasks == NULL || participants < 2 || participants > plan->participant_capacity || slots < 1 ||
	    slots > PLAIT_WAVE_MAX_SLOTS || regions < 2 || regions > plan->region_capacity) {
		return false;
	}
	int8_t shape[PLAIT_WAVE_MAX_SLOTS];
	for (int o = 0; o < slots; ++o) {
		shape[o] = (int8_t)slot_shape(wave, o);
	}
	if (plan->regions == regions && plan->frame_slots == slots && plan->participants == participants &&
	    memcmp(plan->slot_shape, shape, (size_t)slots) == 0) {
		return plan->made;
	}
	plan->regions = regions;
	plan->frame_slots = slots;
	plan->participants = participants;
	memcpy(plan->slot_shape, shape, (size_t)slots);
	memset(plan->lean, 0, sizeof plan->lean);
	plan->made = false;
	/* Rows of one height, at least PLAIT_WAVE_LEAST_ROW slots (a row ends in a barrier, as a pass
	 * does), and preferably no taller than a quarter of the regions: measured on two threads,
	 * hang-128 (16 regions) ran 0.92-0.93 ms a frame in rows of 4 slots, 0.95-1.04 in rows of 8
	 * and 1.04-1.08 in rows of 12, where hang-512 (64 regions) was the same in rows of 24, 12 or
	 * 8 and slower in rows of 4. The shortest such rows that the lines fit first, then taller. */
	int tallest = regions / 4 > PLAIT_WAVE_LEAST_ROW ? regions / 4 : PLAIT_WAVE_LEAST_ROW;
	int fewest = (slots + tallest - 1) / tallest;
	for (int rows = fewest; rows <= slots && !plan->made; ++rows) {
		plan->made = try_rows(plan, rows);
	}
	for (int rows = fewest - 1; rows >= 1 && !plan->made; --rows) {
		plan->made = try_rows(plan, rows);
	}
	if (plan->made) {
		plan_lists(plan);
	}
	return plan->made;
}

bool plait_wave_plan_set_lines(plait_wave_plan *plan, const int *lines)
{
	if (!plan->made) {
		return false;
	}
	int kept[PLAIT_MAX_WORKERS];
	memcpy(kept, plan->line, sizeof(int) * (size_t)plan->participants);
	memcpy(plan->line + 1, lines + 1, sizeof(int) * (size_t)(plan->participants - 1));
	if (!lines_fit(plan)) {
		memcpy(plan->line, kept, sizeof(int) * (size_t)plan->participants);
		return false;
	}
	plan_lists(plan);
	return true;
}

typedef struct piece_run {
	plait_wave *wave;
	plait_wave_plan *plan;
	int row;
} piece_run;

/* Thread k's list; it waits only where a task needs another thread's. */
static void run_pieces(void *context, int begin, int end)
{
	piece_run *run = context;
	plait_wave_plan *plan = run->plan;
	uint32_t epoch = plan->epoch;
	for (int k = begin; k < end; ++k) {
		double start = plait_seconds(), waited = 0.0;
		int list = run->row * plan->participants + k;
		for (int n = plan->list_start[list]; n < plan->list_start[list + 1]; ++n) {
			for (int w = 0; w < 3; ++w) {
				int before = plan->waits[n][w];
				if (before < 0 || atomic_load_explicit(&plan->done[before], memory_order_acquire) == epoch) {
					continue;
				}
				double wait_start = plait_seconds();
				int spins = 0;
				while (atomic_load_explicit(&plan->done[before], memory_order_acquire) != epoch) {
					plait_spin_wait(&spins);
				}
				waited += plait_seconds() - wait_start;
			}
			plait_wave_task task = plan->tasks[n];
			if (task.kind == PLAIT_WAVE_REGION) {
				run_region(run->wave, task.slot, task.index);
			} else {
				run_cut(run->wave, task.slot, task.index, task.kind == PLAIT_WAVE_HEAD);
			}
			atomic_store_explicit(&plan->done[n], epoch, memory_order_release);
		}
		plan->busy[k] = plait_seconds() - start - waited;
	}
}

/* The regions into columns, each by the thread that holds it halfway through a row (the pieces'
 * shares of the regions are then about even). */
static void enter_pieces(void *context, int begin, int end)
{
	piece_run *run = context;
	plait_wave *wave = run->wave;
	for (int q = 0; q < wave->regions; ++q) {
		int owner = owner_of(run->plan, run->plan->slot_count / 2, q);
		if (owner >= begin && owner < end) {
			wave->enter(wave->context, plait_region_first(q, wave->regions, wave->particle_count),
			            plait_region_first(q + 1, wave->regions, wave->particle_count));
		}
	}
}

/* Moves each line a region toward balance when the threads before it ran longer (or shorter)
 * than their share by more than a region's tasks, over the last rows (any lines give the same
 * bits). With two threads: toward the thread that ran shorter. */
static void balance(plait_wave_plan *plan)
{
	int participants = plan->participants;
	double total = 0.0;
	for (int k = 0; k < participants; ++k) {
		total += plan->busy[k];
	}
	double column = total / plan->regions; /* one region at every slot */
	int lines[PLAIT_MAX_WORKERS];
	bool moved = false;
	double before = 0.0;
	for (int k = 1; k < participants; ++k) {
		before += plan->busy[k - 1];
		/* Twice the excess: moving the line a region changes it by about two regions' tasks. */
		double lean = 2.0 * (before - total * k / participants);
		plan->lean[k] = 0.75 * plan->lean[k] + 0.25 * lean;
		int step = plan->lean[k] > column ? -1 : plan->lean[k] < -column ? 1 : 0;
		lines[k] = plan->line[k] + step;
		moved = moved || step != 0;
	}
	int kept[PLAIT_MAX_WORKERS];
	memcpy(kept, plan->line, sizeof(int) * (size_t)participants);
	if (moved && plait_wave_plan_set_lines(plan, lines)) {
		for (int k = 1; k < participants; ++k) {
			plan->lean[k] = lines[k] != kept[k] ? 0.0 : plan->lean[k];
		}
	}
}

void plait_wave_run_pieces(plait_wave *wave, plait_wave_plan *plan, plait_parallel *parallel)
{
	int participants = plan->participants;
	piece_run run = {wave, plan, 0};
	plait_parallel_for(parallel, enter_pieces, &run, 0, participants, 1);
	for (int row = 0; row < plan->rows; ++row) {
		run.row = row;
		plan->epoch = plan->epoch == UINT32_MAX ? 1 : plan->epoch + 1;
		plait_parallel_for(parallel, run_pieces, &run, 0, participants, 1);
		balance(plan);
	}
}
