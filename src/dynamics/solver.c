#include "dynamics/solver.h"

#include <math.h>
#include <string.h>

#include "core/clock.h"
#include "core/error.h"
#include "core/float_mode.h"
#include "core/stream_copy.h"
#include "dynamics/air.h"
#include "dynamics/colouring.h"
#include "dynamics/constraints.h"
#include "dynamics/contact.h"
#include "dynamics/mesh_contact.h"
#include "dynamics/particle_step.h"
#include "dynamics/wave.h"

const char *const plait_kind_names[PLAIT_KIND_COUNT] = {"stretch", "shear",     "bend",
                                                        "tether",  "collision", "contact"};

/* Order of each kind within a position: stretch first, collisions last (paper §6, Fig. 10).
 * Tethers come after the deformation kinds so that, collisions aside, their limit holds at
 * the end of every substep. (Contact passes take collision slots: below.) */
static const int kind_order[PLAIT_KIND_COUNT] = {10, 20, 30, 50, 100, 100};

/* The most collision iterations and contact passes together in a substep that contact passes
 * ask for (a rigid cloth's derived 1,000 stretch iterations would otherwise ask for 500). */
#define CONTACT_PASSES_PER_SUBSTEP 8

/* Contact passes (contact.h) fill collision slots: the collisions run as often as the contact
 * pass interval asks (one per `interval` stretch iterations, at most CONTACT_PASSES_PER_SUBSTEP
 * a substep), and in each substep as many of those slots as max_collision_iterations gives it,
 * spread evenly and the last among them, stay collision iterations; the others become contact
 * passes. So a substep still ends with a collision iteration, and the iterations that would run
 * without contact passes still run, each at about the same place. */
static int collision_slots(const plait_sim *sim)
{
	int iterations = sim->settings.max_collision_iterations, interval = sim->settings.contact_pass_interval;
	if (interval <= 0 || !sim->kind_active[PLAIT_KIND_STRETCH]) {
		return iterations;
	}
	int wanted = (sim->kind_importance[PLAIT_KIND_STRETCH] + interval - 1) / interval;
	int most = CONTACT_PASSES_PER_SUBSTEP * sim->settings.substeps;
	wanted = wanted < most ? wanted : most;
	return wanted > iterations ? wanted : iterations;
}

static void make_contact_passes(plait_sim *sim, int collision, int contact)
{
	plait_schedule *schedule = &sim->schedule;
	int substeps = sim->settings.substeps;
	for (int s = 0; s < substeps; ++s) {
		int first = schedule->substep_start[s], last = schedule->substep_start[s + 1];
		int slots = 0;
		for (int e = first; e < last; ++e) {
			slots += schedule->events[e] == collision;
		}
		int kept = plait_schedule_substep_iterations(sim->settings.max_collision_iterations, substeps, s);
		for (int e = first, j = 0; e < last; ++e) {
			if (schedule->events[e] != collision) {
				continue;
			}
			/* Slot j stays a collision iteration where the kept ones' even spread steps. */
			if ((long long)(j + 1) * kept / slots == (long long)j * kept / slots) {
				schedule->events[e] = contact;
				sim->contact_passes = true;
			}
			++j;
		}
	}
}

plait_result plait_sim_update_schedule(plait_sim *sim, plait_error *error)
{
	if (!sim->schedule_dirty) {
		return PLAIT_OK;
	}
	plait_kind_desc kinds[PLAIT_KIND_COUNT];
	int count = 0, collision = -1;
	for (int k = 0; k < PLAIT_KIND_COUNT; ++k) {
		if (!sim->kind_active[k] || k == PLAIT_KIND_CONTACT) {
			continue;
		}
		int importance = k == PLAIT_KIND_COLLISION ? collision_slots(sim) : sim->kind_importance[k];
		kinds[count] = (plait_kind_desc){plait_kind_names[k], kind_order[k], importance};
		sim->schedule_kinds[count] = k;
		collision = k == PLAIT_KIND_COLLISION ? count : collision;
		++count;
	}
	plait_schedule_destroy(&sim->schedule, &sim->allocator);
	plait_result result =
	    plait_schedule_build(&sim->schedule, &sim->allocator, sim->settings.substeps, kinds, count, error);
	sim->contact_passes = false;
	sim->contact_particle_count = 0;
	if (result == PLAIT_OK) {
		if (collision >= 0) {
			sim->schedule_kinds[count] = PLAIT_KIND_CONTACT;
			make_contact_passes(sim, collision, count);
		}
		sim->schedule_dirty = false;
	}
	return result;
}

static void clear_floats(float *values, int count)
{
	if (count > 0) {
		memset(values, 0, sizeof(float) * (size_t)count);
	}
}

/* A rigid distance block (no compliance) never reads its multipliers: left alone. */
static void reset_distance_multipliers(plait_distance_block *block)
{
	if (block->compliant_count > 0) {
		clear_floats(block->lambda, block->count);
	}
}

static void reset_multipliers(plait_sim *sim)
{
	reset_distance_multipliers(&sim->stretch);
	reset_distance_multipliers(&sim->shear);
	reset_distance_multipliers(&sim->bend_distance);
	clear_floats(sim->bend.lambda, sim->bend.count);
	clear_floats(sim->rod_bend.lambda, sim->rod_bend.count);
}

/* The per-particle stages of a substep; particles are independent there, so they run as
 * parallel loops. */
typedef struct particle_job {
	plait_sim *sim;
	float h, t_end;
	bool air;
	float resting_speed; /* of the substep ending, for the velocity update */
} particle_job;

#define PARTICLE_GRAIN 2048

static plait_particle_step step_of(const particle_job *job)
{
	vec3 gravity = job->sim->settings.gravity;
	return (plait_particle_step){job->h,
	                             1.0f / job->h,
	                             job->t_end,
	                             job->resting_speed,
	                             gravity,
	                             v3_scale(gravity, 0.5f * job->h),
	                             job->air,
	                             job->sim->materials,
	                             job->sim->damp_shared,
	                             job->sim->shared_damp_factor};
}

/* The end of a substep (`ending`: the velocity update) and the start of the next (`beginning`:
 * gravity, damping, prediction) for particles [begin, end), one or both. Both in one pass when
 * nothing runs between them that reads or writes the particles (no air, no particle-pair
 * restitution): the same operations per particle, in the same order, with its data read once.
 * Air's own velocity integration comes first in a start and keeps the portable loop. */
static inline void step_particles(const particle_job *job, int begin, int end, bool ending, bool beginning)
{
	if (beginning && job->air) {
		plait_integrate_velocities(job->sim, job->h, true, begin, end);
	}
	plait_particle_step k = step_of(job);
	plait_particles *p = &job->sim->particles;
#if PLAIT_X86_KERNELS
	if (job->sim->simd != PLAIT_SIMD_SCALAR && !(beginning && job->air)) {
		if (job->sim->simd == PLAIT_SIMD_AVX512) {
			plait_step_particles_avx512(&k, p, begin, end, ending, beginning);
		} else {
			plait_step_particles_avx2(&k, p, begin, end, ending, beginning);
		}
		return;
	}
#endif
	for (int i = begin; i < end; ++i) {
		if (ending) {
			plait_end_particle(&k, p, i);
		}
		if (beginning) {
			plait_begin_particle(&k, p, i);
		}
	}
}

static void begin_substep_range(void *context, int begin, int end)
{
	step_particles(context, begin, end, false, true);
}

static void end_substep_range(void *context, int begin, int end)
{
	step_particles(context, begin, end, true, false);
}

static void end_and_begin_range(void *context, int begin, int end)
{
	step_particles(context, begin, end, true, true);
}

/* Columns. Where the distance blocks' segments hold 8 constraints or more on average
 * (colouring.c, choose_columns), the points are copied into columns (x, y, z, w arrays) before
 * the first distance event of a substep and back before anything else reads them: the column
 * kernel (distance_columns_avx512.c) projects about 1.6 times as fast as the point kernel
 * (hang-128). A folded close whose tethers are all rows of two and whose colliders are all
 * bounded runs on the columns too (folded_range_on_columns: column versions of the tether rows,
 * the collider cull and the particle pass; a particle that may reach a collider goes through
 * its own entry of the point array and back), and the points stay there for the next substep:
 * a frame then copies them once each way instead of once each way a substep. That was 10% of
 * hang-512's frame (4 MB each way a substep, from memory), 4% of hang-128's. Everything else
 * keeps the point array. The copies are exact and the column kernels give the point kernels'
 * bits, so results do not change (test_threads, a_close_on_columns_gives_the_point_arrays_bits). */
static plait_columns columns_of(const plait_sim *sim)
{
	return (plait_columns){sim->column_x, sim->column_y, sim->column_z, sim->column_w,
	                       sim->column_ops.project};
}

static void to_columns_range(void *context, int begin, int end)
{
	plait_sim *sim = context;
	plait_columns columns = columns_of(sim);
	sim->column_ops.to_columns(sim->particles.point, &columns, begin, end);
}

static void from_columns_range(void *context, int begin, int end)
{
	plait_sim *sim = context;
	plait_columns columns = columns_of(sim);
	sim->column_ops.from_columns(sim->particles.point, &columns, begin, end);
}

/* The columns to project on (into *columns), copied there if they are not yet; NULL: the
 * point array. */
static const plait_columns *enter_columns(plait_sim *sim, plait_columns *columns)
{
	if (!sim->use_columns || sim->columns_capacity < sim->particles.count) {
		return NULL;
	}
	if (!sim->in_columns) {
		plait_parallel_for(&sim->parallel, to_columns_range, sim, 0, sim->particles.count, PARTICLE_GRAIN);
		sim->in_columns = true;
	}
	*columns = columns_of(sim);
	return columns;
}

/* The points back in the point array. */
static void leave_columns(plait_sim *sim)
{
	if (sim->in_columns) {
		plait_parallel_for(&sim->parallel, from_columns_range, sim, 0, sim->particles.count, PARTICLE_GRAIN);
		sim->in_columns = false;
	}
}

/* A substep that closes with tethers and then collisions, each once, where every particle's
 * tethers and collisions touch that particle alone (anchors pinned, colliders only, without
 * vertices of their own: plait_tethers_by_particle, plait_collider_pass_begin), runs them in its
 * last pass over the particles, chunk by chunk: tethers, colliders, the velocity update and the
 * next substep's start. Each particle goes through the same operations in the same order as
 * with a pass for each, so the bits are the same; the points are read once instead of three
 * times, with two hand-overs to the workers less (hang-512 moves about 55 MB a substep in
 * these passes, more than the last-level cache holds). */
typedef struct folded_job {
	particle_job step;
	bool beginning;
	bool on_columns; /* the points are in columns and stay there (below, "Columns") */
	plait_collider_pass *colliders;
	_Atomic long long collide_ns; /* time in the colliders, summed over the workers */
} folded_job;

/* folded_range on the points as columns: the same operations on the same values. */
static void folded_range_on_columns(folded_job *job, int begin, int end)
{
#if PLAIT_X86_KERNELS
	plait_sim *sim = job->step.sim;
	plait_columns columns = columns_of(sim);
	plait_solve_tethers_of_particles_on_columns(&sim->tether, &columns, begin, end);
	double start = plait_seconds();
	plait_collider_pass_range_on_columns(job->colliders, &columns, begin, end);
	atomic_fetch_add_explicit(&job->collide_ns, (long long)((plait_seconds() - start) * 1e9),
	                          memory_order_relaxed);
	plait_particle_step k = step_of(&job->step);
	plait_step_columns_avx512(&k, &sim->particles, &columns, begin, end, job->beginning);
#else
	(void)job;
	(void)begin;
	(void)end;
#endif
}

static void folded_range(void *context, int begin, int end)
{
	folded_job *job = context;
	plait_sim *sim = job->step.sim;
	if (job->on_columns) {
		folded_range_on_columns(job, begin, end);
		return;
	}
	plait_solve_tethers_of_particles(&sim->tether, sim->particles.point, sim->simd, begin, end);
	double start = plait_seconds();
	plait_collider_pass_range(job->colliders, begin, end);
	atomic_fetch_add_explicit(&job->collide_ns, (long long)((plait_seconds() - start) * 1e9),
	                          memory_order_relaxed);
	step_particles(&job->step, begin, end, true, job->beginning);
}

/* The substep's closing tethers and collisions with its velocity update, and the next
 * substep's start when `beginning` (t_next: where that start's pins go). */
static void run_folded_close(plait_sim *sim, const particle_job *job, plait_collider_pass *colliders,
                             bool beginning, float t_next)
{
	sim->folded_substeps += 1;
	/* On columns when every part of the close has a column kernel; the points then stay there
	 * for the next substep, or go back once at the frame's end. */
	bool on_columns = sim->in_columns && sim->close_on_columns && sim->simd == PLAIT_SIMD_AVX512 &&
	                  plait_tethers_on_columns(&sim->tether) && plait_collider_pass_on_columns(colliders);
	if (!on_columns) {
		leave_columns(sim);
	}
	folded_job folded = {*job, beginning, on_columns, colliders, 0};
	folded.step.t_end = t_next;
	plait_parallel_for(&sim->parallel, folded_range, &folded, 0, sim->particles.count, PARTICLE_GRAIN);
	if (on_columns) {
		sim->closed_on_columns += 1;
		if (!beginning) {
			leave_columns(sim);
		}
	}
	plait_collider_pass_end(sim, colliders);
	sim->constraint_solves += sim->tether.count;
	/* Per worker, roughly: the workers ran the colliders side by side. */
	sim->collision_seconds += 1e-9 * (double)atomic_load_explicit(&folded.collide_ns, memory_order_relaxed) /
	                          (double)sim->parallel.worker_count;
	if (beginning) {
		/* Only transforms move: these colliders have no vertices (pins) of their own. */
		plait_colliders_begin_substep(sim, job->t_end, t_next);
	} else {
		plait_contacts_end_substep(sim);
	}
}

/* Whether substep events [first, last) close with one tether event and then one collision
 * event that can be folded into the particle pass (above). */
static bool closes_foldably(const plait_sim *sim, const int *in_substep, int first, int last, bool air)
{
	const plait_schedule *schedule = &sim->schedule;
	if (!sim->fold_closing_passes || air || last - first < 2) {
		return false;
	}
	int tether = schedule->events[last - 2], collision = schedule->events[last - 1];
	return sim->schedule_kinds[tether] == PLAIT_KIND_TETHER &&
	       sim->schedule_kinds[collision] == PLAIT_KIND_COLLISION && in_substep[tether] == 1 &&
	       in_substep[collision] == 1 && plait_tethers_by_particle(&sim->tether);
}

/* Whether any of count floats is an infinity or a NaN (all exponent bits set), in a loop
 * without branches that the compiler vectorises: it runs over every position and velocity once
 * a frame. */
static bool any_nonfinite(const float *values, size_t count)
{
	uint32_t bad = 0;
	for (size_t k = 0; k < count; ++k) {
		uint32_t bits;
		memcpy(&bits, &values[k], sizeof bits);
		bad |= (uint32_t)((bits & 0x7f800000u) == 0x7f800000u);
	}
	return bad != 0;
}

/* The frame's own passes over every particle, split over the workers like the substeps' (on
 * one thread they were a few percent of a two-thread frame at hang-128): keeping the frame's
 * start and the largest radius, checking the end is finite, moving the pins' start. */
typedef struct frame_job {
	plait_sim *sim;
	_Atomic uint32_t largest_radius_bits; /* a non-negative float's bits order as it does */
	_Atomic int nonfinite;
	bool checked; /* nonfinite is known: a wave checked each region as it left columns */
} frame_job;

/* Whether positions or velocities of particles [begin, end) are not finite (below). */
static void frame_check_range(void *context, int begin, int end);

/* Waves. Where a frame is only distance sweeps of rigid blocks and folded closes on columns, its
 * colliders still, it runs as one wave down the regions (wave.h): each region meets every pass of
 * the frame a step after the pass before, while its points, velocities and constraints are in
 * cache (one thread: hang-512 10-13% faster, hang-128 about 3%). On several threads the wave runs
 * in pieces that move a region a slot (wave.h, "Pieces"), in rows of slots where the frame is
 * taller than the cloth has regions for (two threads, pieces over passes: hang-512 0.89-0.97,
 * hang-128 0.88-1.04 and hang-256 0.92-1.05 depending on the minute). The same operations on the
 * same values in an order that keeps every particle's, so the bits are the same (test_threads,
 * a_wave_gives_the_passes_bits and a_wave_in_pieces_gives_the_passes_bits). */

/* The distance block an event of `kind` projects, or NULL: another kind, or bend with
 * dihedral or rod bends (not distance constraints). */
static plait_distance_block *distance_block_of(plait_sim *sim, int kind)
{
	switch (kind) {
	case PLAIT_KIND_STRETCH:
		return &sim->stretch;
	case PLAIT_KIND_SHEAR:
		return &sim->shear;
	case PLAIT_KIND_BEND:
		return sim->bend.count == 0 && sim->rod_bend.count == 0 ? &sim->bend_distance : NULL;
	default:
		return NULL;
	}
}

/* Colliders that stay put over the frame, in the shapes whose pass reads nothing of the substep:
 * closes of different substeps run at once. */
static bool colliders_keep_still(const plait_sim *sim)
{
	for (int k = 0; k < sim->collider_count; ++k) {
		const plait_collider *c = &sim->colliders[k];
		if (c->collide && (c->shape.type == PLAIT_SHAPE_MESH || c->mesh_end != NULL ||
		                   memcmp(&c->transform_start, &c->transform_end, sizeof c->transform_start) != 0)) {
			return false;
		}
	}
	return true;
}

/* The frame's slots into *wave when it can run as a wave, after substep 0's start (its collider
 * pass in *colliders, folded: fold). */
static bool plan_wave(plait_sim *sim, plait_wave *wave, const plait_collider_pass *colliders, bool fold,
                      bool air)
{
	int n = sim->particles.count, substeps = sim->settings.substeps;
	if (!sim->wave_frames || !fold || air || sim->particle_pairs_active || sim->mesh_contacts_active ||
	    sim->pair_contact_count != 0 || !sim->bands_agree || sim->simd != PLAIT_SIMD_AVX512 ||
	    !sim->close_on_columns || !sim->use_columns || sim->columns_capacity < n ||
	    !plait_tethers_on_columns(&sim->tether) || !sim->tether.anchors_keep_bits ||
	    !plait_collider_pass_on_columns(colliders) || !colliders_keep_still(sim)) {
		return false;
	}
	const plait_schedule *schedule = &sim->schedule;
	int regions = 0, count = 0;
	for (int s = 0; s < substeps; ++s) {
		int first = schedule->substep_start[s], last = schedule->substep_start[s + 1];
		int in_substep[PLAIT_KIND_COUNT] = {0}, seen[PLAIT_KIND_COUNT] = {0};
		for (int e = first; e < last; ++e) {
			in_substep[schedule->events[e]] += 1;
		}
		if (!closes_foldably(sim, in_substep, first, last, air)) {
			return false;
		}
		for (int e = first; e < last - 2; ++e) {
			int k = schedule->events[e], kind = sim->schedule_kinds[k];
			plait_distance_block *block = distance_block_of(sim, kind);
			if (block == NULL || count == PLAIT_WAVE_MAX_SLOTS) {
				return false;
			}
			plait_sweep sweep = plait_sweep_for(seen[k]++, in_substep[k], s, kind == PLAIT_KIND_STRETCH);
			if (block->count == 0) {
				continue;
			}
			regions = regions == 0 ? block->colouring.region_count : regions;
			if (!plait_wave_takes(block, regions, n)) {
				return false;
			}
			wave->slots[count++] = (plait_wave_slot){block, sweep, s};
		}
		if (count == PLAIT_WAVE_MAX_SLOTS) {
			return false;
		}
		wave->slots[count++] = (plait_wave_slot){NULL, PLAIT_SWEEP_FORWARD, s};
	}
	wave->slot_count = count;
	wave->regions = regions;
	wave->particle_count = n;
	if (regions < 2) {
		return false;
	}
	int workers = sim->parallel.worker_count;
	/* In pieces the threads wait for each other: only with every worker running. A task system
	 * that has not started one within 10 ms (or gave a NULL handle) leaves this frame to the
	 * passes, which give the same bits. */
	return workers == 1 || (sim->wave_plan != NULL && plait_wave_plan_make(sim->wave_plan, wave, workers) &&
	                        plait_parallel_all_running(&sim->parallel, 0.01));
}

typedef struct wave_frame {
	plait_sim *sim;
	frame_job *frame;                        /* the frame's check, made as each region leaves columns */
	folded_job closes[PLAIT_WAVE_MAX_SLOTS]; /* one a substep */
} wave_frame;

static void wave_enter(void *context, int begin, int end)
{
	wave_frame *frame = context;
	to_columns_range(frame->sim, begin, end);
}

static void wave_close(void *context, int substep, int begin, int end)
{
	wave_frame *frame = context;
	folded_range_on_columns(&frame->closes[substep], begin, end);
}

static void wave_leave(void *context, int begin, int end)
{
	wave_frame *frame = context;
	from_columns_range(frame->sim, begin, end);
	frame_check_range(frame->frame, begin, end);
}

/* The frame as the wave planned (plan_wave), substep 0 begun: what run_substeps does for every
 * substep, with the passes run by plait_wave_run. */
static plait_result run_wave_frame(plait_sim *sim, plait_wave *wave, const particle_job *job,
                                   plait_collider_pass *colliders, float inverse_h_squared, frame_job *check,
                                   plait_error *error)
{
	int substeps = sim->settings.substeps;
	/* The later substeps' contact set-up: with no particle pairs and no mesh contacts it reads
	 * nothing the substeps change. */
	double contacts_start = plait_seconds();
	for (int s = 1; s < substeps; ++s) {
		sim->substep = s;
		if (!plait_contacts_begin_substep(sim)) {
			return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY,
			                       "out of memory in the collision stage; the frame was not advanced");
		}
	}
	sim->collision_seconds += plait_seconds() - contacts_start;
	wave_frame storage, *frame = &storage;
	frame->sim = sim;
	frame->frame = check;
	for (int s = 0; s < substeps; ++s) {
		bool beginning = s + 1 < substeps;
		folded_job *close = &frame->closes[s];
		*close = (folded_job){*job, beginning, true, colliders, 0};
		close->step.t_end = beginning ? (float)(s + 2) / (float)substeps : (float)(s + 1) / (float)substeps;
	}
	plait_columns columns = columns_of(sim);
	wave->columns = &columns;
	wave->inverse_h_squared = inverse_h_squared;
	wave->enter = wave_enter;
	wave->close = wave_close;
	wave->leave = wave_leave;
	wave->context = frame;
	/* Every region's close reads the tether anchors from columns, some before their own region
	 * goes there; pinned, they keep their bits through the frame. */
	plait_tether_anchors_to_columns(&sim->tether, &sim->particles, &columns);
	int participants = sim->parallel.worker_count;
	if (participants > 1) {
		plait_wave_run_pieces(wave, sim->wave_plan, &sim->parallel);
		sim->pieced_frames += 1;
	} else {
		plait_wave_run(wave);
	}
	sim->in_columns = false;
	check->checked = true;

	long long collide_ns = 0;
	for (int o = 0; o < wave->slot_count; ++o) {
		const plait_wave_slot *slot = &wave->slots[o];
		if (slot->block != NULL) {
			sim->constraint_solves += (slot->sweep == PLAIT_SWEEP_SYMMETRIC ? 2 : 1) * slot->block->count;
		}
	}
	for (int s = 0; s < substeps; ++s) {
		sim->substep = s;
		sim->folded_substeps += 1;
		sim->closed_on_columns += 1;
		sim->constraint_solves += sim->tether.count;
		collide_ns += atomic_load_explicit(&frame->closes[s].collide_ns, memory_order_relaxed);
		if (s + 1 < substeps) {
			plait_colliders_begin_substep(sim, (float)(s + 1) / (float)substeps,
			                              (float)(s + 2) / (float)substeps);
		} else {
			plait_contacts_end_substep(sim);
		}
	}
	/* One pass served every substep (the colliders stay put): its contacts are the frame's. */
	plait_collider_pass_end(sim, colliders);
	sim->collision_seconds += 1e-9 * (double)collide_ns / participants;
	sim->waved_frames += 1;
	return PLAIT_OK;
}

static void run_event(plait_sim *sim, plait_kind kind, float inverse_h_squared, plait_sweep sweep)
{
	int sweeps = sweep == PLAIT_SWEEP_SYMMETRIC ? 2 : 1;
	plait_columns storage;
	const plait_columns *columns = NULL;
	switch (kind) {
	case PLAIT_KIND_STRETCH:
		columns = enter_columns(sim, &storage);
		plait_solve_distance(&sim->stretch, &sim->particles, columns, inverse_h_squared, sweep,
		                     sim->distance_kernel, &sim->parallel);
		sim->constraint_solves += sweeps * sim->stretch.count;
		break;
	case PLAIT_KIND_SHEAR:
		columns = enter_columns(sim, &storage);
		plait_solve_distance(&sim->shear, &sim->particles, columns, inverse_h_squared, sweep,
		                     sim->distance_kernel, &sim->parallel);
		sim->constraint_solves += sweeps * sim->shear.count;
		break;
	case PLAIT_KIND_BEND:
		if (sim->bend.count > 0) {
			leave_columns(sim);
			plait_solve_bend(&sim->bend, &sim->particles, inverse_h_squared, sim->bend_kernel,
			                 &sim->parallel);
		}
		/* (Not into columns for no distance constraint: a dihedral bend's event would copy the
		 * points there and straight back.) */
		columns = sim->bend_distance.count > 0 ? enter_columns(sim, &storage) : NULL;
		plait_solve_distance(&sim->bend_distance, &sim->particles, columns, inverse_h_squared, sweep,
		                     sim->distance_kernel, &sim->parallel);
		if (sim->rod_bend.count > 0) {
			leave_columns(sim);
			plait_solve_rod_bend(&sim->rod_bend, &sim->particles, inverse_h_squared);
		}
		sim->constraint_solves += sim->bend.count + sweeps * sim->bend_distance.count + sim->rod_bend.count;
		break;
	case PLAIT_KIND_TETHER:
		leave_columns(sim);
		plait_solve_tethers(&sim->tether, &sim->particles, sim->simd, &sim->parallel);
		sim->constraint_solves += sim->tether.count;
		break;
	case PLAIT_KIND_COLLISION:
	case PLAIT_KIND_CONTACT: {
		leave_columns(sim);
		double start = plait_seconds();
		if (kind == PLAIT_KIND_COLLISION) {
			plait_collide(sim);
		} else {
			plait_collide_again(sim); /* a contact pass */
		}
		sim->collision_seconds += plait_seconds() - start;
		break;
	}
	case PLAIT_KIND_COUNT:
		break;
	}
}

static void frame_start_range(void *context, int begin, int end)
{
	frame_job *job = context;
	plait_particles *p = &job->sim->particles;
	size_t n = (size_t)(end - begin);
	/* Read back only if the frame fails: kept out of the caches. */
	plait_copy_streaming(p->point_frame + begin, p->point + begin, sizeof(plait_point) * n);
	plait_copy_streaming(p->v_frame + begin, p->v + begin, sizeof(vec3) * n);
	float largest = 0.0f;
	for (int i = begin; i < end; ++i) {
		largest = plait_maxf(largest, p->radius[i]);
	}
	uint32_t bits;
	memcpy(&bits, &largest, sizeof bits);
	uint32_t seen = atomic_load_explicit(&job->largest_radius_bits, memory_order_relaxed);
	while (bits > seen &&
	       !atomic_compare_exchange_weak_explicit(&job->largest_radius_bits, &seen, bits,
	                                              memory_order_relaxed, memory_order_relaxed)) {
	}
}

static void frame_check_range(void *context, int begin, int end)
{
	frame_job *job = context;
	const plait_particles *p = &job->sim->particles;
	/* Positions with their inverse masses (finite too), then velocities. */
	bool bad = any_nonfinite(&p->point[begin].x.x, 4 * (size_t)(end - begin)) ||
	           any_nonfinite(&p->v[begin].x, 3 * (size_t)(end - begin));
	if (bad) {
		atomic_store_explicit(&job->nonfinite, 1, memory_order_relaxed);
	}
}

static void frame_pins_range(void *context, int begin, int end)
{
	frame_job *job = context;
	plait_particles *p = &job->sim->particles;
	/* Only pinned particles (w = 0) read their pin targets; pinning one sets both (world/
	 * object_access.c). Copying every particle's cost hang-512 3 MB of memory traffic a frame. */
	for (int i = begin; i < end; ++i) {
		if (p->point[i].w == 0.0f) {
			p->pin_start[i] = p->pin_end[i];
		}
	}
}

/* The frame's start back in the point array (the columns are then stale). */
static void restore_frame_start(plait_sim *sim)
{
	plait_particles *p = &sim->particles;
	sim->in_columns = false;
	memcpy(p->point, p->point_frame, sizeof(plait_point) * (size_t)p->count);
	memcpy(p->v, p->v_frame, sizeof(vec3) * (size_t)p->count);
}

/* The substeps of one frame (seed 000 §2.2), with the workers running. */
static plait_result run_substeps(plait_sim *sim, frame_job *frame, plait_error *error)
{
	const plait_settings *settings = &sim->settings;
	int substeps = settings->substeps;
	float frame_time = settings->time_scale / settings->fps;
	float h = frame_time / (float)substeps;
	float inverse_h_squared = 1.0f / (h * h);
	bool air = plait_air_active(sim);
	sim->substep_time = h;
	/* Damping's factor per substep, once per material rather than once per particle. */
	for (int m = 0; m < sim->material_count; ++m) {
		float damp = sim->materials[m].damp;
		sim->materials[m].damp_factor = damp > 0.0f ? expf(-damp * h) : 1.0f;
	}
	/* Colliders' particles are always pinned, and pinned particles are never damped: their
	 * materials (no damping) do not count, nor do destroyed objects'. */
	sim->damp_shared = true;
	sim->shared_damp_factor = 1.0f;
	bool seen = false;
	for (int m = 0; m < sim->material_count; ++m) {
		if (sim->materials[m].type == PLAIT_OBJECT_COLLIDER || sim->materials[m].retired) {
			continue;
		}
		if (!seen) {
			sim->shared_damp_factor = sim->materials[m].damp_factor;
			seen = true;
		}
		sim->damp_shared = sim->damp_shared && sim->materials[m].damp_factor == sim->shared_damp_factor;
	}
	/* Columns never carry over from one frame to the next: a frame ends with the points in the
	 * point array, or fails and is restored there. */
	sim->in_columns = false;
	bool begun = false; /* the particles' part of this substep's start is done */
	for (int s = 0; s < substeps; ++s) {
		float t0 = (float)s / (float)substeps, t1 = (float)(s + 1) / (float)substeps;
		sim->substep = s;
		if (!begun) {
			plait_colliders_begin_substep(sim, t0, t1);
		}
		if (air) {
			plait_air_accumulate(sim, sim->time + (double)(t0 * frame_time));
		}
		particle_job job = {sim, h, t1, air, plait_resting_speed(sim)};
		if (!begun) {
			plait_parallel_for(&sim->parallel, begin_substep_range, &job, 0, sim->particles.count,
			                   PARTICLE_GRAIN);
		}
		reset_multipliers(sim);
		/* Collision time: it builds the collision elements, trees and rest pairs when objects
		 * come or go (the first frame of a self-colliding cloth). */
		double contacts_start = plait_seconds();
		bool contacts_begun = plait_contacts_begin_substep(sim);
		sim->collision_seconds += plait_seconds() - contacts_start;
		if (!contacts_begun) {
			return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY,
			                       "out of memory in the collision stage; the frame was not advanced");
		}

		/* The interleaved events of this substep (paper §6), collisions last. */
		const plait_schedule *schedule = &sim->schedule;
		int first = schedule->substep_start[s], last = schedule->substep_start[s + 1];
		int in_substep[PLAIT_KIND_COUNT] = {0}, done[PLAIT_KIND_COUNT] = {0};
		for (int e = first; e < last; ++e) {
			in_substep[schedule->events[e]] += 1;
		}
		plait_collider_pass colliders;
		bool fold =
		    closes_foldably(sim, in_substep, first, last, air) && plait_collider_pass_begin(sim, &colliders);
		if (s == 0) {
			plait_wave wave;
			if (plan_wave(sim, &wave, &colliders, fold, air)) {
				return run_wave_frame(sim, &wave, &job, &colliders, inverse_h_squared, frame, error);
			}
		}
		for (int e = first; e < last - (fold ? 2 : 0); ++e) {
			int k = schedule->events[e];
			plait_sweep sweep =
			    plait_sweep_for(done[k]++, in_substep[k], s, sim->schedule_kinds[k] == PLAIT_KIND_STRETCH);
			run_event(sim, (plait_kind)sim->schedule_kinds[k], inverse_h_squared, sweep);
		}

		if (!fold) {
			leave_columns(sim); /* (a folded close leaves them itself, or stays there) */
		}
		/* The substep must not end with anything passed through anything. */
		if (sim->mesh_contacts_active) {
			double start = plait_seconds();
			plait_mesh_contacts_failsafe(sim);
			sim->collision_seconds += plait_seconds() - start;
		}
		/* The velocity update; with the next substep's start when nothing comes between. */
		begun =
		    s + 1 < substeps && !air && sim->pair_contact_count == 0 && !plait_mesh_contacts_restitution(sim);
		if (fold) {
			/* The closing tethers and collisions in the same pass (folded_range). */
			run_folded_close(sim, &job, &colliders, begun, begun ? (float)(s + 2) / (float)substeps : t1);
		} else if (begun) {
			/* Colliders first: their vertices' targets for the next substep. */
			plait_colliders_begin_substep(sim, t1, (float)(s + 2) / (float)substeps);
			particle_job both = job;
			both.t_end = (float)(s + 2) / (float)substeps;
			plait_parallel_for(&sim->parallel, end_and_begin_range, &both, 0, sim->particles.count,
			                   PARTICLE_GRAIN);
		} else {
			plait_parallel_for(&sim->parallel, end_substep_range, &job, 0, sim->particles.count,
			                   PARTICLE_GRAIN);
			plait_contacts_end_substep(sim);
		}
	}
	return PLAIT_OK;
}

plait_result plait_sim_step(plait_sim *sim, plait_error *error)
{
	plait_result result = plait_sim_update_schedule(sim, error);
	if (result != PLAIT_OK) {
		return result;
	}
	/* Out of memory here only costs speed: uncoloured constraints are projected one by one. */
	(void)plait_sim_colour(sim);
	plait_particles *p = &sim->particles;
	sim->contacts = 0;
	sim->constraint_solves = 0;
	sim->ccd_hits = 0;
	sim->failsafe = 0;
	sim->tangles = 0;
	sim->collision_seconds = 0.0;

	plait_tethers_begin_frame(&sim->tether, p, &sim->allocator);
	plait_float_mode saved_mode = plait_float_mode_enter();
	plait_parallel_begin(&sim->parallel);
	frame_job frame = {sim, 0, 0, false};
	plait_parallel_for(&sim->parallel, frame_start_range, &frame, 0, p->count, PARTICLE_GRAIN);
	uint32_t largest_bits = atomic_load_explicit(&frame.largest_radius_bits, memory_order_relaxed);
	memcpy(&sim->largest_radius, &largest_bits, sizeof sim->largest_radius);
	result = run_substeps(sim, &frame, error);
	if (result == PLAIT_OK) {
		if (!frame.checked) {
			plait_parallel_for(&sim->parallel, frame_check_range, &frame, 0, p->count, PARTICLE_GRAIN);
		}
		if (atomic_load_explicit(&frame.nonfinite, memory_order_relaxed) == 0) {
			plait_parallel_for(&sim->parallel, frame_pins_range, &frame, 0, p->count, PARTICLE_GRAIN);
		}
	}
	plait_parallel_end(&sim->parallel);
	plait_float_mode_leave(saved_mode);
	if (result != PLAIT_OK) {
		restore_frame_start(sim);
		return result;
	}
	if (atomic_load_explicit(&frame.nonfinite, memory_order_relaxed) != 0) {
		restore_frame_start(sim);
		return plait_error_set(error, PLAIT_ERROR_NONFINITE,
		                       "frame %d produced a non-finite position or velocity; try more substeps or "
		                       "lower resistances",
		                       sim->frame + 1);
	}
	for (int k = 0; k < sim->collider_count; ++k) {
		sim->colliders[k].transform_start = sim->colliders[k].transform_end;
	}
	sim->frame += 1;
	sim->time += (double)(sim->settings.time_scale / sim->settings.fps);
	return PLAIT_OK;
}

plait_sim_stats plait_sim_measure(const plait_sim *sim)
{
	const plait_particles *p = &sim->particles;
	plait_sim_stats stats = {0};
	double scale = sim->settings.space_scale;
	for (int i = 0; i < p->count; ++i) {
		if (!v3_is_finite(p->point[i].x) || !v3_is_finite(p->v[i])) {
			stats.nonfinite += 1;
			continue;
		}
		if (p->point[i].w > 0.0f) {
			double speed_sq = (double)v3_length_sq(p->v[i]) * scale * scale;
			stats.kinetic_energy += 0.5 * (double)p->mass[i] * speed_sq;
		}
	}
	stats.max_strain = plait_distance_max_strain(&sim->stretch, p);
	stats.penetrations = plait_count_penetrations(sim);
	return stats;
}
