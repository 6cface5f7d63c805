/* The order a long contact list is kept and projected in, so that the workers can share it.
 *
 * Each collision iteration projects the listed pairs one after another (Gauss-Seidel): a pair
 * sees what the pairs before it did to its vertices. The order the gather lists them in runs
 * through space, each pair touching one just before it (the pile's 466,000 pairs form 35,000
 * such steps), so it cannot be shared out. A long list is put in another order, made from where
 * its pairs lie: their space is cut into PLAN_SLABS slabs across its longest extent, with about
 * as many pairs each (as many slabs as are four times wider than the pairs reach), and every
 * vertex that can move belongs to the slab it lies in. First come
 * the pairs whose moving vertices all lie in one slab, slab after slab; then those across the
 * border between slabs s and s + 1, for even s, then for odd s; then the rest (across three
 * slabs or more), each group in the list's order (the gather's, or the last plan's with a
 * mending's pairs after it). The groups of one stage share no moving
 * vertex, so the workers take them side by side with the same result as one after another: the
 * order, and so every bit of the result, does not depend on the number of threads. Vertices
 * that never move (inverse mass 0: pins, a collider's vertices) tie no pairs together;
 * failsafe-only pairs (no contact distance) move nothing and go with slab 0.
 *
 * The list is stored in that order (each pair moved once, at the plan), so the projection and
 * the failsafe's sweeps read it straight through. A mending keeps the order of the pairs it
 * keeps and adds its own at the end (plait_mesh_contacts_relist_around): those are projected
 * after the groups, one by one, until the next plan. A plan is made at the first projection of
 * a long list after a gather, after a mending of a list that had none, and once a mending's
 * pairs are more than an eighth of the list; a frame's start drops the plan if a vertex was
 * pinned or unpinned since (inverse masses change only between frames, through the pin calls:
 * within a frame the groups stay apart). Shorter lists keep the
 * gather's order, projected on the calling thread: sharing them would cost more than it saves. */
#include "dynamics/mesh_contact_internal.h"

#include <math.h>
#include <string.h>

#define PLAN_CHUNK 8192

void plait_mesh_contacts_free_plan(plait_mesh_contacts *mc, const plait_allocator *a)
{
	plait_free(a, mc->pair_group);
	plait_free(a, mc->spare_group);
	plait_free(a, mc->spare_pairs);
	plait_free(a, mc->plan_counts);
	plait_free(a, mc->vertex_slab);
	plait_free(a, mc->vertex_moves);
	mc->pair_group = mc->spare_group = NULL;
	mc->spare_pairs = NULL;
	mc->plan_counts = NULL;
	mc->vertex_slab = NULL;
	mc->vertex_moves = NULL;
	mc->plan_pair_capacity = 0;
	mc->plan_particle_capacity = 0;
	mc->planned = 0;
	mc->plan_list = -1;
	mc->plan_kept_list = -1;
}

/* Room for the list's pairs (with their groups, kept when the room grows) and the particles. */
static bool reserve_plan(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_allocator *a = &sim->allocator;
	int particles = sim->particles.count;
	if (mc->plan_particle_capacity < particles) {
		plait_free(a, mc->vertex_slab);
		plait_free(a, mc->vertex_moves);
		mc->vertex_slab = plait_alloc(a, (size_t)particles * sizeof *mc->vertex_slab);
		mc->vertex_moves = plait_alloc_zero(a, (size_t)particles, sizeof *mc->vertex_moves);
		mc->plan_particle_capacity = particles;
		mc->planned = 0; /* no vertex has its slab yet */
		if (mc->vertex_slab == NULL || mc->vertex_moves == NULL) {
			plait_mesh_contacts_free_plan(mc, a);
			return false;
		}
	}
	if (mc->plan_pair_capacity != mc->pair_capacity) {
		/* The spare list as long as the list: the two are swapped at each plan. */
		int pairs = mc->pair_capacity;
		int chunks = (pairs + PLAN_CHUNK - 1) / PLAN_CHUNK;
		int keep = mc->plan_pair_capacity < pairs ? mc->plan_pair_capacity : pairs;
		int8_t *group = plait_alloc_grow(a, mc->pair_group, sizeof *group, keep, pairs);
		if (group != NULL) {
			mc->pair_group = group;
		}
		plait_free(a, mc->spare_group);
		plait_free(a, mc->spare_pairs);
		plait_free(a, mc->plan_counts);
		mc->spare_group = plait_alloc(a, (size_t)pairs * sizeof *mc->spare_group);
		mc->spare_pairs = plait_alloc(a, (size_t)pairs * sizeof *mc->spare_pairs);
		mc->plan_counts = plait_alloc(a, (size_t)chunks * sizeof *mc->plan_counts);
		if (group == NULL || mc->spare_group == NULL || mc->spare_pairs == NULL || mc->plan_counts == NULL) {
			plait_mesh_contacts_free_plan(mc, a);
			return false;
		}
		mc->plan_pair_capacity = pairs;
	}
	return true;
}

static float along(vec3 x, int axis)
{
	return axis == 0 ? x.x : axis == 1 ? x.y : x.z;
}

static int bin_of(const plan_slabs *s, vec3 x)
{
	float at = (along(x, s->axis) - s->low) * s->per_bin;
	return at >= (float)(SLAB_BINS - 1) ? SLAB_BINS - 1 : at > 0.0f ? (int)at : 0; /* NaN: bin 0 */
}

/* The slabs: along the longest extent of the projected pairs' first vertices, each of SLAB_BINS
 * bins to its slab, with about as many pairs in each slab; as many slabs as fit four times the
 * pairs' mean reach along that extent (most pairs then lie in one slab), PLAN_SLABS at most. */
static void cut_slabs(const plait_sim *sim, const plait_mesh_contacts *mc, plan_slabs *s)
{
	const plait_point *point = sim->particles.point;
	vec3 lower = v3(INFINITY, INFINITY, INFINITY), upper = v3(-INFINITY, -INFINITY, -INFINITY);
	for (int k = 0; k < mc->pair_count; ++k) {
		if (mc->pairs[k].distance > 0.0f) {
			vec3 x = point[mc->pairs[k].v[0]].x;
			lower = v3_min(lower, x);
			upper = v3_max(upper, x);
		}
	}
	vec3 extent = v3_sub(upper, lower);
	s->axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
	float width = along(extent, s->axis);
	s->low = along(lower, s->axis);
	s->per_bin = width > 0.0f && isfinite(width) ? (float)SLAB_BINS / width : 0.0f;
	int in_bin[SLAB_BINS] = {0}, projected = 0;
	double reach = 0.0;
	for (int k = 0; k < mc->pair_count; ++k) {
		const contact_pair *pair = &mc->pairs[k];
		if (pair->distance > 0.0f) {
			float first = along(point[pair->v[0]].x, s->axis), least = first, most = first;
			for (int m = 1; m < pair_size[pair->type]; ++m) {
				float at = along(point[pair->v[m]].x, s->axis);
				least = plait_minf(least, at);
				most = plait_maxf(most, at);
			}
			reach += (double)(most - least);
			in_bin[bin_of(s, point[pair->v[0]].x)] += 1;
			projected += 1;
		}
	}
	double fits = projected > 0 && reach > 0.0 ? (double)width / (4.0 * reach / projected) : 1.0;
	s->count = fits >= PLAN_SLABS ? PLAN_SLABS : fits > 1.0 ? (int)fits : 1;
	for (int b = 0, before = 0; b < SLAB_BINS; ++b) {
		s->bin_slab[b] = (uint8_t)((long)before * s->count / (projected > 0 ? projected : 1));
		before += in_bin[b];
	}
}

/* A pair's group, from the slabs of its moving vertices. */
static int group_of(const plait_sim *sim, const plait_mesh_contacts *mc, const contact_pair *pair)
{
	if (!(pair->distance > 0.0f)) {
		return 0;
	}
	const plait_point *point = sim->particles.point;
	int low = PLAN_SLABS, high = -1;
	for (int m = 0; m < pair_size[pair->type]; ++m) {
		int i = pair->v[m];
		if (point[i].w != 0.0f) {
			int slab = mc->vertex_slab[i];
			low = slab < low ? slab : low;
			high = slab > high ? slab : high;
		}
	}
	if (high < 0 || high == low) {
		return high < 0 ? 0 : low; /* one that moves nothing goes anywhere */
	}
	if (high == low + 1) {
		return low % 2 == 0 ? PLAN_FIRST_EVEN + low / 2 : PLAN_FIRST_ODD + low / 2;
	}
	return PLAN_WIDE_GROUP;
}

/* A plan is made on the workers: the vertices' slabs, then each chunk of PLAN_CHUNK pairs counts
 * its pairs by group and moves them to their places (a counting sort, stable: within a group
 * the gather's order, whoever runs which chunk). */
typedef struct plan_job {
	const plait_sim *sim;
	plait_mesh_contacts *mc;
	int (*counts)[PLAN_GROUPS]; /* per chunk; then where its pairs of each group go */
} plan_job;

static void slab_vertices(void *context, int begin, int end)
{
	const plan_job *job = context;
	const plait_point *point = job->sim->particles.point;
	plait_mesh_contacts *mc = job->mc;
	for (int i = begin; i < end; ++i) {
		mc->vertex_slab[i] = (int8_t)mc->slabs.bin_slab[bin_of(&mc->slabs, point[i].x)];
		mc->vertex_moves[i] = point[i].w != 0.0f;
	}
}

static int chunk_end(const plait_mesh_contacts *mc, int chunk)
{
	return (chunk + 1) * PLAN_CHUNK < mc->pair_count ? (chunk + 1) * PLAN_CHUNK : mc->pair_count;
}

static void count_groups(void *context, int begin, int end)
{
	const plan_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	for (int c = begin; c < end; ++c) {
		int *counts = job->counts[c];
		memset(counts, 0, sizeof job->counts[c]);
		for (int k = c * PLAN_CHUNK; k < chunk_end(mc, c); ++k) {
			int group = group_of(job->sim, mc, &mc->pairs[k]);
			mc->pair_group[k] = (int8_t)group;
			counts[group] += 1;
		}
	}
}

static void place_groups(void *context, int begin, int end)
{
	const plan_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	for (int c = begin; c < end; ++c) {
		int *at = job->counts[c];
		for (int k = c * PLAN_CHUNK; k < chunk_end(mc, c); ++k) {
			int to = at[mc->pair_group[k]]++;
			mc->spare_pairs[to] = mc->pairs[k];
			mc->spare_group[to] = mc->pair_group[k];
		}
	}
}

/* Whether a vertex was pinned or unpinned since the last plan. */
static bool moves_changed(const plait_sim *sim, const plait_mesh_contacts *mc)
{
	const plait_point *point = sim->particles.point;
	for (int i = 0; i < sim->particles.count; ++i) {
		if (mc->vertex_moves[i] != (point[i].w != 0.0f)) {
			return true;
		}
	}
	return false;
}

void plait_mesh_contacts_check_plan(const plait_sim *sim, plait_mesh_contacts *mc)
{
	if (mc->planned > 0 && (mc->plan_particle_capacity < sim->particles.count || moves_changed(sim, mc))) {
		mc->plan_list = -1;
		mc->plan_kept_list = -1;
		mc->planned = 0;
	}
}

bool plait_mesh_contacts_plan(plait_sim *sim, plait_mesh_contacts *mc)
{
	if (mc->plan_list == mc->list_changes) {
		return true;
	}
	if (mc->plan_failed_list == mc->list_changes) {
		return false; /* out of memory for this list's plan: tried once */
	}
	if (!reserve_plan(sim, mc)) {
		mc->plan_failed_list = mc->list_changes;
		return false;
	}
	/* Pairs a mending added are projected one by one after the groups: once they are more than
	 * an eighth of the list, it is planned anew. */
	if (mc->plan_kept_list == mc->list_changes && mc->planned > 0 &&
	    mc->pair_count - mc->planned <= mc->pair_count / 8) {
		/* A mending kept the first `planned` pairs in their groups' order: count them again. */
		int counts[PLAN_GROUPS] = {0};
		for (int k = 0; k < mc->planned; ++k) {
			counts[mc->pair_group[k]] += 1;
		}
		for (int g = 0, at = 0; g < PLAN_GROUPS; ++g) {
			mc->group_start[g] = at;
			at += counts[g];
		}
		mc->group_start[PLAN_GROUPS] = mc->planned;
		mc->plan_list = mc->list_changes;
		return true;
	}
	if (mc->plan_listing != mc->listings) {
		cut_slabs(sim, mc, &mc->slabs);
		mc->plan_listing = mc->listings;
	}
	int chunks = (mc->pair_count + PLAN_CHUNK - 1) / PLAN_CHUNK;
	plan_job job = {sim, mc, mc->plan_counts};
	plait_parallel_for(&sim->parallel, slab_vertices, &job, 0, sim->particles.count, PLAN_CHUNK);
	plait_parallel_for(&sim->parallel, count_groups, &job, 0, chunks, 1);
	int at = 0;
	for (int g = 0; g < PLAN_GROUPS; ++g) {
		mc->group_start[g] = at;
		for (int c = 0; c < chunks; ++c) {
			int count = job.counts[c][g];
			job.counts[c][g] = at;
			at += count;
		}
	}
	mc->group_start[PLAN_GROUPS] = at;
	plait_parallel_for(&sim->parallel, place_groups, &job, 0, chunks, 1);
	contact_pair *pairs = mc->pairs;
	int8_t *groups = mc->pair_group;
	mc->pairs = mc->spare_pairs;
	mc->pair_group = mc->spare_group;
	mc->spare_pairs = pairs;
	mc->spare_group = groups;
	mc->planned = mc->pair_count;
	mc->plan_list = mc->list_changes;
	return true;
}

typedef struct project_job {
	plait_sim *sim;
	plait_mesh_contacts *mc;
	pair_projection how;
	_Atomic int contacts;
	_Atomic int ccd_hits;
} project_job;

/* Whether a projection `how` takes the pair: a contact pass, those that pushed at the last
 * collision iteration; after the colliders, those with a vertex that touched a collider in the
 * substep. */
static bool takes_pair(const plait_sim *sim, const contact_pair *pair, pair_projection how)
{
	if (!(pair->distance > 0.0f)) {
		return false;
	}
	if (how == PROJECT_AGAIN) {
		return pair->pushed_last;
	}
	if (how == PROJECT_AFTER_COLLIDERS) {
		const uint8_t *flags = sim->particles.flags;
		for (int q = 0; q < pair_size[pair->type]; ++q) {
			if (flags[pair->v[q]] & PLAIT_PARTICLE_CONTACT) {
				return true;
			}
		}
		return false;
	}
	return true;
}

static int project_range(plait_sim *sim, plait_mesh_contacts *mc, int begin, int end, pair_projection how,
                         int *ccd_hits)
{
	int contacts = 0;
	for (int k = begin; k < end; ++k) {
		contact_pair *pair = &mc->pairs[k];
		if (!takes_pair(sim, pair, how)) {
			if (how == PROJECT_FULL) {
				pair->pushed_last = 0;
			}
			continue;
		}
		if (how == PROJECT_FULL) {
			pair->pushed_last = 0; /* set again when it pushes or rests (rub_resting) */
		}
		int pushed = plait_mesh_contacts_project_pair(sim, pair, how, ccd_hits);
		if (how != PROJECT_AGAIN && pushed > 0) {
			pair->pushed_last = 1;
		}
		contacts += pushed;
	}
	return contacts;
}

static void project_groups(void *context, int begin, int end)
{
	project_job *job = context;
	int ccd_hits = 0;
	int contacts = project_range(job->sim, job->mc, job->mc->group_start[begin], job->mc->group_start[end],
	                             job->how, &ccd_hits);
	atomic_fetch_add_explicit(&job->contacts, contacts, memory_order_relaxed);
	atomic_fetch_add_explicit(&job->ccd_hits, ccd_hits, memory_order_relaxed);
}

int plait_mesh_contacts_project_list(plait_sim *sim, plait_mesh_contacts *mc, pair_projection how)
{
	bool planned = mc->pair_count >= PLAN_LEAST_PAIRS && plait_mesh_contacts_plan(sim, mc);
	if (!planned) {
		return project_range(sim, mc, 0, mc->pair_count, how, &sim->ccd_hits);
	}
	mc->plan_projections += how == PROJECT_FULL;
	project_job job = {sim, mc, how, 0, 0};
	/* The stages, each after the one before: slabs, even borders, odd borders. Then the wide
	 * pairs and those a mending added, on the calling thread. */
	for (int k = 0; k < PLAN_STAGES; ++k) {
		plait_parallel_for(&sim->parallel, project_groups, &job, plan_stage_start[k], plan_stage_start[k + 1],
		                   1);
	}
	sim->ccd_hits += atomic_load_explicit(&job.ccd_hits, memory_order_relaxed);
	int contacts = atomic_load_explicit(&job.contacts, memory_order_relaxed);
	return contacts +
	       project_range(sim, mc, mc->group_start[PLAN_WIDE_GROUP], mc->pair_count, how, &sim->ccd_hits);
}
