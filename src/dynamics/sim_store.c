#include "dynamics/sim_store.h"

#include "dynamics/colouring.h"
#include "dynamics/constraints.h"
#include "dynamics/wave.h"

#include <string.h>

/* Replaces *array (count_used elements of element_size) with a larger copy of new_capacity. */
static bool grow_array(const plait_allocator *allocator, void **array, size_t element_size, int count_used,
                       int new_capacity)
{
	void *bigger = plait_alloc_grow(allocator, *array, element_size, count_used, new_capacity);
	if (bigger == NULL) {
		return false;
	}
	*array = bigger;
	return true;
}

static int next_capacity(int capacity, int needed)
{
	int grown = capacity < 16 ? 16 : capacity + capacity / 2;
	return grown > needed ? grown : needed;
}

void plait_sim_init(plait_sim *sim, const plait_allocator *allocator)
{
	memset(sim, 0, sizeof *sim);
	sim->allocator = *allocator;
	sim->schedule_dirty = true;
	sim->fold_closing_passes = true;
	sim->close_on_columns = true;
	sim->wave_frames = true;
}

#define FREE_FIELD(object, field) plait_free(&sim->allocator, (object).field)

static void free_particles(plait_sim *sim)
{
	plait_particles *p = &sim->particles;
	void *fields[] = {p->point,
	                  p->x_prev,
	                  p->v,
	                  p->mass,
	                  p->radius,
	                  p->material,
	                  p->flags,
	                  p->pin_start,
	                  p->pin_end,
	                  p->x_start,
	                  p->contact_normal,
	                  p->contact_velocity,
	                  p->contact_bounce,
	                  p->contact_stickiness,
	                  p->contact_push,
	                  p->contact_rub,
	                  p->drag_matrix,
	                  p->air_force,
	                  p->lift_force,
	                  p->point_frame,
	                  p->v_frame};
	for (size_t k = 0; k < sizeof fields / sizeof fields[0]; ++k) {
		plait_free(&sim->allocator, fields[k]);
	}
}

static void free_distance(plait_sim *sim, plait_distance_block *b)
{
	FREE_FIELD(*b, pair);
	FREE_FIELD(*b, point_offset);
	FREE_FIELD(*b, rest);
	FREE_FIELD(*b, compliance_tension);
	FREE_FIELD(*b, compliance_compression);
	FREE_FIELD(*b, lambda);
	plait_colouring_clear(&b->colouring, &sim->allocator);
}

void plait_sim_destroy(plait_sim *sim)
{
	free_particles(sim);
	free_distance(sim, &sim->stretch);
	free_distance(sim, &sim->shear);
	free_distance(sim, &sim->bend_distance);
	FREE_FIELD(sim->bend, quad);
	FREE_FIELD(sim->bend, rest_angle);
	FREE_FIELD(sim->bend, compliance);
	FREE_FIELD(sim->bend, lambda);
	plait_colouring_clear(&sim->bend.colouring, &sim->allocator);
	FREE_FIELD(sim->rod_bend, triple);
	FREE_FIELD(sim->rod_bend, rest);
	FREE_FIELD(sim->rod_bend, compliance);
	FREE_FIELD(sim->rod_bend, lambda);
	FREE_FIELD(sim->tether, pair);
	FREE_FIELD(sim->tether, length);
	FREE_FIELD(sim->tether, stiffness);
	plait_tether_lanes_destroy(&sim->tether, &sim->allocator);
	FREE_FIELD(sim->aero, triangle);
	FREE_FIELD(sim->aero, weight);
	FREE_FIELD(sim->aero, material);
	plait_free(&sim->allocator, sim->materials);
	plait_free(&sim->allocator, sim->colliders);
	plait_free(&sim->allocator, sim->surfaces); /* their shapes are released by the world */
	plait_free(&sim->allocator, sim->chains);
	plait_free(&sim->allocator, sim->pair_contacts);
	plait_free(&sim->allocator, sim->pair_list);
	plait_free(&sim->allocator, sim->contact_particles);
	plait_free(&sim->allocator, sim->pair_lower);
	plait_free(&sim->allocator, sim->pair_upper);
	plait_free(&sim->allocator, sim->column_x);
	if (sim->wave_plan != NULL) {
		plait_wave_plan_destroy(sim->wave_plan, &sim->allocator);
		plait_free(&sim->allocator, sim->wave_plan);
	}
	plait_schedule_destroy(&sim->schedule, &sim->allocator);
	/* The particle hash is owned by the contact stage and freed there. */
}

bool plait_sim_reserve_particles(plait_sim *sim, int count)
{
	plait_particles *p = &sim->particles;
	if (count > PLAIT_MAX_PARTICLES - p->count) {
		return false;
	}
	int needed = p->count + count;
	if (needed <= p->capacity) {
		return true;
	}
	int capacity = next_capacity(p->capacity, needed);
	const plait_allocator *a = &sim->allocator;
	int n = p->count;
	bool ok = grow_array(a, (void **)&p->point, sizeof(plait_point), n, capacity) &&
	          grow_array(a, (void **)&p->x_prev, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->v, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->mass, sizeof(float), n, capacity) &&
	          grow_array(a, (void **)&p->radius, sizeof(float), n, capacity) &&
	          grow_array(a, (void **)&p->material, sizeof(int), n, capacity) &&
	          grow_array(a, (void **)&p->flags, sizeof(uint8_t), n, capacity) &&
	          grow_array(a, (void **)&p->pin_start, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->pin_end, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->x_start, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->contact_normal, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->contact_velocity, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->contact_bounce, sizeof(float), n, capacity) &&
	          grow_array(a, (void **)&p->contact_stickiness, sizeof(float), n, capacity) &&
	          grow_array(a, (void **)&p->contact_push, sizeof(float), n, capacity) &&
	          grow_array(a, (void **)&p->contact_rub, sizeof(float), n, capacity) &&
	          grow_array(a, (void **)&p->drag_matrix, 6 * sizeof(float), n, capacity) &&
	          grow_array(a, (void **)&p->air_force, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->lift_force, sizeof(vec3), n, capacity) &&
	          grow_array(a, (void **)&p->point_frame, sizeof(plait_point), n, capacity) &&
	          grow_array(a, (void **)&p->v_frame, sizeof(vec3), n, capacity);
	if (ok) {
		p->capacity = capacity;
	}
	return ok;
}

bool plait_sim_reserve_distance(plait_sim *sim, plait_distance_block *b, int count)
{
	int needed = b->count + count;
	if (needed <= b->capacity) {
		return true;
	}
	int capacity = next_capacity(b->capacity, needed);
	const plait_allocator *a = &sim->allocator;
	bool ok = grow_array(a, (void **)&b->pair, sizeof *b->pair, b->count, capacity) &&
	          grow_array(a, (void **)&b->point_offset, sizeof *b->point_offset, b->count, capacity) &&
	          grow_array(a, (void **)&b->rest, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->compliance_tension, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->compliance_compression, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->lambda, sizeof(float), b->count, capacity);
	if (ok) {
		b->capacity = capacity;
	}
	return ok;
}

bool plait_sim_reserve_bend(plait_sim *sim, int count)
{
	plait_bend_block *b = &sim->bend;
	int needed = b->count + count;
	if (needed <= b->capacity) {
		return true;
	}
	int capacity = next_capacity(b->capacity, needed);
	const plait_allocator *a = &sim->allocator;
	bool ok = grow_array(a, (void **)&b->quad, sizeof *b->quad, b->count, capacity) &&
	          grow_array(a, (void **)&b->rest_angle, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->compliance, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->lambda, sizeof(float), b->count, capacity);
	if (ok) {
		b->capacity = capacity;
	}
	return ok;
}

bool plait_sim_reserve_rod_bend(plait_sim *sim, int count)
{
	plait_rod_bend_block *b = &sim->rod_bend;
	int needed = b->count + count;
	if (needed <= b->capacity) {
		return true;
	}
	int capacity = next_capacity(b->capacity, needed);
	const plait_allocator *a = &sim->allocator;
	bool ok = grow_array(a, (void **)&b->triple, sizeof *b->triple, b->count, capacity) &&
	          grow_array(a, (void **)&b->rest, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->compliance, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->lambda, sizeof(float), b->count, capacity);
	if (ok) {
		b->capacity = capacity;
	}
	return ok;
}

bool plait_sim_reserve_tethers(plait_sim *sim, int count)
{
	plait_tether_block *b = &sim->tether;
	int needed = b->count + count;
	if (needed <= b->capacity) {
		return true;
	}
	int capacity = next_capacity(b->capacity, needed);
	const plait_allocator *a = &sim->allocator;
	bool ok = grow_array(a, (void **)&b->pair, sizeof *b->pair, b->count, capacity) &&
	          grow_array(a, (void **)&b->length, sizeof(float), b->count, capacity) &&
	          grow_array(a, (void **)&b->stiffness, sizeof(float), b->count, capacity);
	if (ok) {
		b->capacity = capacity;
	}
	return ok;
}

bool plait_sim_reserve_aero(plait_sim *sim, int count)
{
	plait_aero_block *b = &sim->aero;
	int needed = b->count + count;
	if (needed <= b->capacity) {
		return true;
	}
	int capacity = next_capacity(b->capacity, needed);
	const plait_allocator *a = &sim->allocator;
	bool ok = grow_array(a, (void **)&b->triangle, sizeof *b->triangle, b->count, capacity) &&
	          grow_array(a, (void **)&b->weight, sizeof *b->weight, b->count, capacity) &&
	          grow_array(a, (void **)&b->material, sizeof(int), b->count, capacity);
	if (ok) {
		b->capacity = capacity;
	}
	return ok;
}

bool plait_sim_reserve_materials(plait_sim *sim, int count)
{
	int needed = sim->material_count + count;
	if (needed <= sim->material_capacity) {
		return true;
	}
	int capacity = next_capacity(sim->material_capacity, needed);
	if (!grow_array(&sim->allocator, (void **)&sim->materials, sizeof *sim->materials, sim->material_count,
	                capacity)) {
		return false;
	}
	sim->material_capacity = capacity;
	return true;
}

bool plait_sim_reserve_colliders(plait_sim *sim, int count)
{
	int needed = sim->collider_count + count;
	if (needed <= sim->collider_capacity) {
		return true;
	}
	int capacity = next_capacity(sim->collider_capacity, needed);
	if (!grow_array(&sim->allocator, (void **)&sim->colliders, sizeof *sim->colliders, sim->collider_count,
	                capacity)) {
		return false;
	}
	sim->collider_capacity = capacity;
	return true;
}

int plait_sim_add_particle(plait_sim *sim, vec3 position, vec3 velocity, float mass, float radius,
                           int material, uint8_t flags)
{
	plait_particles *p = &sim->particles;
	int i = p->count++;
	p->point[i].x = position;
	p->x_prev[i] = position;
	p->v[i] = velocity;
	p->mass[i] = mass;
	p->point[i].w = (flags & PLAIT_PARTICLE_PINNED) ? 0.0f : 1.0f / mass;
	p->radius[i] = radius;
	p->material[i] = material;
	p->flags[i] = flags;
	p->pin_start[i] = position;
	p->pin_end[i] = position;
	p->x_start[i] = position;
	return i;
}

void plait_sim_add_distance(plait_distance_block *b, int i, int j, float rest, float compliance_tension,
                            float compliance_compression)
{
	int c = b->count++;
	b->pair[c][0] = i;
	b->pair[c][1] = j;
	b->point_offset[c][0] = plait_point_offset(i);
	b->point_offset[c][1] = plait_point_offset(j);
	b->rest[c] = rest;
	b->compliance_tension[c] = compliance_tension;
	b->compliance_compression[c] = compliance_compression;
	b->lambda[c] = 0.0f;
	b->compliant_count += compliance_tension != 0.0f || compliance_compression != 0.0f;
}

static void compact_distance(plait_distance_block *b, const int *remap, const plait_allocator *allocator)
{
	int kept = 0;
	b->compliant_count = 0;
	for (int c = 0; c < b->count; ++c) {
		int i = remap[b->pair[c][0]], j = remap[b->pair[c][1]];
		if (i < 0 || j < 0) {
			continue;
		}
		b->compliant_count += b->compliance_tension[c] != 0.0f || b->compliance_compression[c] != 0.0f;
		b->pair[kept][0] = i;
		b->pair[kept][1] = j;
		b->point_offset[kept][0] = plait_point_offset(i);
		b->point_offset[kept][1] = plait_point_offset(j);
		b->rest[kept] = b->rest[c];
		b->compliance_tension[kept] = b->compliance_tension[c];
		b->compliance_compression[kept] = b->compliance_compression[c];
		b->lambda[kept] = 0.0f;
		++kept;
	}
	b->count = kept;
	plait_colouring_clear(&b->colouring, allocator);
}

bool plait_sim_compact(plait_sim *sim, const bool *keep)
{
	plait_particles *p = &sim->particles;
	int *remap = plait_alloc_zero(&sim->allocator, (size_t)(p->count > 0 ? p->count : 1), sizeof(int));
	if (remap == NULL) {
		return false;
	}
	int kept = 0;
	for (int i = 0; i < p->count; ++i) {
		if (!keep[i]) {
			remap[i] = -1;
			continue;
		}
		remap[i] = kept;
		p->point[kept] = p->point[i];
		p->x_prev[kept] = p->x_prev[i];
		p->v[kept] = p->v[i];
		p->mass[kept] = p->mass[i];
		p->radius[kept] = p->radius[i];
		p->material[kept] = p->material[i];
		p->flags[kept] = p->flags[i];
		p->pin_start[kept] = p->pin_start[i];
		p->pin_end[kept] = p->pin_end[i];
		p->x_start[kept] = p->x_start[i];
		++kept;
	}
	p->count = kept;
	compact_distance(&sim->stretch, remap, &sim->allocator);
	compact_distance(&sim->shear, remap, &sim->allocator);
	compact_distance(&sim->bend_distance, remap, &sim->allocator);
	/* Removing constraints breaks the colours: until the next step colours the blocks again,
	 * every constraint is projected one by one (an empty colouring). */
	sim->colouring_dirty = true;

	plait_bend_block *bend = &sim->bend;
	int bend_kept = 0;
	for (int c = 0; c < bend->count; ++c) {
		int q[4];
		bool alive = true;
		for (int k = 0; k < 4; ++k) {
			q[k] = remap[bend->quad[c][k]];
			alive = alive && q[k] >= 0;
		}
		if (!alive) {
			continue;
		}
		memcpy(bend->quad[bend_kept], q, sizeof q);
		bend->rest_angle[bend_kept] = bend->rest_angle[c];
		bend->compliance[bend_kept] = bend->compliance[c];
		++bend_kept;
	}
	bend->count = bend_kept;
	plait_colouring_clear(&bend->colouring, &sim->allocator);

	plait_rod_bend_block *rod = &sim->rod_bend;
	int rod_kept = 0;
	for (int c = 0; c < rod->count; ++c) {
		int t[3] = {remap[rod->triple[c][0]], remap[rod->triple[c][1]], remap[rod->triple[c][2]]};
		if (t[0] < 0 || t[1] < 0 || t[2] < 0) {
			continue;
		}
		memcpy(rod->triple[rod_kept], t, sizeof t);
		rod->rest[rod_kept] = rod->rest[c];
		rod->compliance[rod_kept] = rod->compliance[c];
		++rod_kept;
	}
	rod->count = rod_kept;

	plait_tether_block *tether = &sim->tether;
	int tether_kept = 0;
	for (int c = 0; c < tether->count; ++c) {
		int i = remap[tether->pair[c][0]], anchor = remap[tether->pair[c][1]];
		if (i < 0 || anchor < 0) {
			continue;
		}
		tether->pair[tether_kept][0] = i;
		tether->pair[tether_kept][1] = anchor;
		tether->length[tether_kept] = tether->length[c];
		tether->stiffness[tether_kept] = tether->stiffness[c];
		++tether_kept;
	}
	tether->count = tether_kept;
	tether->lanes_stale = true;

	plait_aero_block *aero = &sim->aero;
	int aero_kept = 0;
	for (int c = 0; c < aero->count; ++c) {
		int t[3] = {remap[aero->triangle[c][0]], remap[aero->triangle[c][1]], remap[aero->triangle[c][2]]};
		if (t[0] < 0 || t[1] < 0 || t[2] < 0) {
			continue;
		}
		memcpy(aero->triangle[aero_kept], t, sizeof t);
		memcpy(aero->weight[aero_kept], aero->weight[c], sizeof aero->weight[c]);
		aero->material[aero_kept] = aero->material[c];
		++aero_kept;
	}
	aero->count = aero_kept;
	plait_free(&sim->allocator, remap);
	return true;
}

bool plait_sim_reserve_surfaces(plait_sim *sim, int count)
{
	int needed = sim->surface_count + count;
	if (needed <= sim->surface_capacity) {
		return true;
	}
	int capacity = next_capacity(sim->surface_capacity, needed);
	if (!grow_array(&sim->allocator, (void **)&sim->surfaces, sizeof *sim->surfaces, sim->surface_count,
	                capacity)) {
		return false;
	}
	sim->surface_capacity = capacity;
	return true;
}

bool plait_sim_reserve_chains(plait_sim *sim, int count)
{
	int needed = sim->chain_count + count;
	if (needed <= sim->chain_capacity) {
		return true;
	}
	int capacity = next_capacity(sim->chain_capacity, needed);
	if (!grow_array(&sim->allocator, (void **)&sim->chains, sizeof *sim->chains, sim->chain_count,
	                capacity)) {
		return false;
	}
	sim->chain_capacity = capacity;
	return true;
}
