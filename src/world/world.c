/* World lifetime, settings, stepping, statistics and the schedule's public view. */
#include "world/world.h"

#include <stdio.h>
#include <string.h>

#include "collision/mesh_shape.h"
#include "core/error.h"
#include "dynamics/contact.h"
#include "dynamics/bend_kernel.h"
#include "dynamics/distance_kernel.h"
#include "dynamics/mesh_contact.h"
#include "dynamics/sim_store.h"
#include "dynamics/solver.h"

#define PLAIT_DEF_MAGIC 0x504c4154

plait_world_def plait_default_world_def(void)
{
	plait_world_def def;
	memset(&def, 0, sizeof def);
	def.fps = 24.0f;
	def.substeps = 3;
	def.max_collision_iterations = 4;
	def.contact_pass_interval = 1;
	def.gravity = (plait_vec3){0.0f, -9.81f, 0.0f};
	def.air_density = 1.0f;
	def.wind.direction = (plait_vec3){1.0f, 0.0f, 0.0f};
	def.space_scale = 1.0f;
	def.time_scale = 1.0f;
	def.cloth_contacts = true;
	def.untangle = true;
	def.worker_count = 1;
	def.internal_value = PLAIT_DEF_MAGIC;
	return def;
}

static bool finite3(plait_vec3 v)
{
	return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

static plait_result validate_world_def(const plait_world_def *def, bool check_hooks, plait_error *error)
{
	if (def == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "world def is NULL");
	}
	if (def->internal_value != PLAIT_DEF_MAGIC) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "world def was not initialised with plait_default_world_def()");
	}
	if (!(def->fps > 0.0f) || !isfinite(def->fps)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "fps must be > 0, got %g",
		                       (double)def->fps);
	}
	if (def->substeps < 1 || def->substeps > 1000) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "substeps must be in 1..1000, got %d",
		                       def->substeps);
	}
	if (def->max_collision_iterations < 0 || def->max_collision_iterations > PLAIT_MAX_IMPORTANCE) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "max_collision_iterations must be in 0..%d, got %d", PLAIT_MAX_IMPORTANCE,
		                       def->max_collision_iterations);
	}
	if (def->contact_pass_interval < 0 || def->contact_pass_interval > PLAIT_MAX_IMPORTANCE) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "contact_pass_interval must be in 0..%d, got %d", PLAIT_MAX_IMPORTANCE,
		                       def->contact_pass_interval);
	}
	if (!finite3(def->gravity)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "gravity must be finite");
	}
	if (!(def->air_density >= 0.0f) || !isfinite(def->air_density)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "air_density must be >= 0, got %g",
		                       (double)def->air_density);
	}
	if (!(def->wind.speed >= 0.0f) || !isfinite(def->wind.speed) || !finite3(def->wind.direction)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "wind speed must be >= 0 and direction finite");
	}
	if (!(def->wind.noise >= 0.0f && def->wind.noise <= 10.0f)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "wind noise must be in 0..10, got %g",
		                       (double)def->wind.noise);
	}
	if (!(def->space_scale > 0.0f) || !isfinite(def->space_scale)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "space_scale must be > 0, got %g",
		                       (double)def->space_scale);
	}
	if (!(def->time_scale > 0.0f) || !isfinite(def->time_scale)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "time_scale must be > 0, got %g",
		                       (double)def->time_scale);
	}
	if (check_hooks && (def->alloc == NULL) != (def->free == NULL)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "alloc and free hooks must be set together");
	}
	if (check_hooks && (def->enqueue_task == NULL) != (def->finish_task == NULL)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "enqueue_task and finish_task hooks must be set together");
	}
	if (check_hooks && (def->worker_count < 1 || def->worker_count > PLAIT_MAX_WORKERS)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "worker_count must be in 1..%d, got %d",
		                       PLAIT_MAX_WORKERS, def->worker_count);
	}
	if (check_hooks && (def->simd < PLAIT_SIMD_AUTO || def->simd > PLAIT_SIMD_AVX512)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "simd must be a plait_simd value, got %d",
		                       (int)def->simd);
	}
	if (check_hooks && !plait_simd_supported(def->simd)) {
		static const char *const names[] = {"auto", "scalar", "AVX2", "AVX-512"};
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "simd %s was asked for, but this processor does not run it", names[def->simd]);
	}
	return PLAIT_OK;
}

static void apply_settings(plait_world *world)
{
	const plait_world_def *def = &world->def;
	plait_settings *s = &world->sim.settings;
	float inverse_scale = 1.0f / def->space_scale;
	s->fps = def->fps;
	s->time_scale = def->time_scale;
	s->space_scale = def->space_scale;
	s->substeps = def->substeps;
	s->max_collision_iterations = def->max_collision_iterations;
	s->contact_pass_interval = def->contact_pass_interval;
	s->gravity = (vec3){def->gravity.x * inverse_scale, def->gravity.y * inverse_scale,
	                    def->gravity.z * inverse_scale};
	s->air_density = def->air_density;
	vec3 direction = v3_normalize(def->wind.direction);
	s->wind_velocity = v3_scale(direction, def->wind.speed * inverse_scale);
	s->wind_noise = def->wind.noise;
	s->seed = def->seed;
	s->cloth_contacts = def->cloth_contacts;
	s->untangle = def->untangle;
	world->sim.schedule_dirty = true;
}

plait_world_id plait_create_world(const plait_world_def *def, plait_error *error)
{
	plait_world_id id = {NULL};
	plait_error_clear(error);
	if (validate_world_def(def, true, error) != PLAIT_OK) {
		return id;
	}
	plait_allocator allocator = {def->alloc, def->free, def->allocator_context};
	plait_world *world = plait_alloc_zero(&allocator, 1, sizeof *world);
	if (world == NULL) {
		plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory creating a world");
		return id;
	}
	world->allocator = allocator;
	world->def = *def;
	plait_sim_init(&world->sim, &allocator);
	world->sim.simd = def->simd == PLAIT_SIMD_AUTO ? plait_simd_best() : def->simd;
	world->sim.distance_kernel = plait_distance_kernel_for(world->sim.simd);
	world->sim.column_ops = plait_column_ops_for(world->sim.simd);
	world->sim.bend_kernel = plait_bend_kernel_for(world->sim.simd);
	plait_parallel_init(&world->sim.parallel, def->enqueue_task, def->finish_task, def->task_context,
	                    def->worker_count);
	apply_settings(world);
	id.world = world;
	return id;
}

static plait_world *resolve_world(plait_world_id id)
{
	return id.world;
}

void plait_destroy_world(plait_world_id id)
{
	plait_world *world = resolve_world(id);
	if (world == NULL) {
		return;
	}
	for (int k = 0; k < world->object_count; ++k) {
		plait_topology_destroy(&world->objects[k].topology, &world->allocator);
	}
	for (int k = 0; k < world->sim.collider_count; ++k) {
		plait_collider_release(world, &world->sim.colliders[k]);
	}
	for (int k = 0; k < world->sim.surface_count; ++k) {
		plait_mesh_shape_destroy(world->sim.surfaces[k].shape, &world->allocator);
		plait_free(&world->allocator, world->sim.surfaces[k].shape);
	}
	plait_free(&world->allocator, world->objects);
	plait_contacts_destroy(&world->sim);
	plait_sim_destroy(&world->sim);
	plait_allocator allocator = world->allocator;
	plait_free(&allocator, world);
}

plait_simd plait_world_get_simd(plait_world_id id)
{
	plait_world *world = resolve_world(id);
	return world != NULL ? world->sim.simd : PLAIT_SIMD_SCALAR;
}

bool plait_simd_is_supported(plait_simd simd)
{
	return simd >= PLAIT_SIMD_AUTO && simd <= PLAIT_SIMD_AVX512 && plait_simd_supported(simd);
}

bool plait_world_is_valid(plait_world_id id)
{
	return id.world != NULL;
}

plait_result plait_world_set_def(plait_world_id id, const plait_world_def *def, plait_error *error)
{
	plait_world *world = resolve_world(id);
	if (world == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ID, "null world id");
	}
	plait_result result = validate_world_def(def, false, error);
	if (result != PLAIT_OK) {
		return result;
	}
	/* Hooks are fixed at creation: memory already handed out must go back to the same place. */
	plait_world_def kept = *def;
	kept.alloc = world->def.alloc;
	kept.free = world->def.free;
	kept.allocator_context = world->def.allocator_context;
	kept.enqueue_task = world->def.enqueue_task;
	kept.finish_task = world->def.finish_task;
	kept.task_context = world->def.task_context;
	kept.worker_count = world->def.worker_count;
	kept.simd = world->def.simd;
	world->def = kept;
	apply_settings(world);
	/* Settings decide which objects meet (cloth_contacts) and the substep the listed paths are
	 * measured in: a list made under the old ones is not kept. */
	plait_mesh_contacts_forget_list(&world->sim);
	return PLAIT_OK;
}

plait_world_def plait_world_get_def(plait_world_id id)
{
	plait_world *world = resolve_world(id);
	return world != NULL ? world->def : plait_default_world_def();
}

/* After a frame a deforming mesh starts the next one where it ended; after a failed frame,
 * which leaves everything at its start, it goes back to where the frame began. */
static void finish_deforming_colliders(plait_sim *sim, bool advanced)
{
	for (int k = 0; k < sim->collider_count; ++k) {
		plait_collider *c = &sim->colliders[k];
		if (c->mesh_end == NULL) {
			continue;
		}
		if (advanced) {
			memcpy(c->mesh_start, c->mesh_end, sizeof(vec3) * (size_t)c->shape.mesh->vertex_count);
		} else {
			/* Back in time: what the failed frame measured against it no longer bounds. */
			plait_mesh_shape_deform(c->shape.mesh, c->mesh_start, c->mesh_end, 0.0f, 0.0f);
			plait_collider_forget_clearances(c);
		}
	}
}

plait_result plait_world_step(plait_world_id id, plait_error *error)
{
	plait_world *world = resolve_world(id);
	if (world == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ID, "null world id");
	}
	plait_result result = plait_sim_step(&world->sim, error);
	finish_deforming_colliders(&world->sim, result == PLAIT_OK);
	/* Counters of the frame; the measures of the state are taken when someone asks. */
	world->stats.contacts = world->sim.contacts;
	world->stats.ccd_hits = world->sim.ccd_hits;
	world->stats.failsafe = world->sim.failsafe;
	world->stats.tangles = world->sim.tangles;
	world->stats.collision_ms = 1e3 * world->sim.collision_seconds;
	world->stats.constraint_solves = world->sim.constraint_solves;
	return result;
}

int plait_world_get_frame(plait_world_id id)
{
	plait_world *world = resolve_world(id);
	return world != NULL ? world->sim.frame : 0;
}

double plait_world_get_time(plait_world_id id)
{
	plait_world *world = resolve_world(id);
	return world != NULL ? world->sim.time : 0.0;
}

plait_frame_stats plait_world_get_stats(plait_world_id id)
{
	plait_world *world = resolve_world(id);
	plait_frame_stats empty = {0};
	if (world == NULL) {
		return empty;
	}
	plait_sim_stats measured = plait_sim_measure(&world->sim);
	plait_frame_stats stats = world->stats;
	stats.frame = world->sim.frame;
	stats.kinetic_energy = measured.kinetic_energy;
	stats.max_strain = measured.max_strain;
	stats.penetrations = measured.penetrations;
	stats.nonfinite = measured.nonfinite;
	return stats;
}

int plait_world_get_substep_count(plait_world_id id)
{
	plait_world *world = resolve_world(id);
	return world != NULL ? world->def.substeps : 0;
}

int plait_world_get_schedule(plait_world_id id, int substep, const char **names, int capacity)
{
	plait_world *world = resolve_world(id);
	if (world == NULL || substep < 0 || substep >= world->def.substeps) {
		return 0;
	}
	if (plait_sim_update_schedule(&world->sim, NULL) != PLAIT_OK) {
		return 0;
	}
	const plait_schedule *schedule = &world->sim.schedule;
	int first = schedule->substep_start[substep], count = schedule->substep_start[substep + 1] - first;
	for (int e = 0; e < count && e < capacity && names != NULL; ++e) {
		names[e] = plait_kind_names[world->sim.schedule_kinds[schedule->events[first + e]]];
	}
	return count;
}

plait_object *plait_world_resolve(plait_object_id id, plait_error *error)
{
	plait_world *world = id.world;
	if (world == NULL || id.index1 <= 0 || id.index1 > world->object_count) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ID, "invalid object id");
		return NULL;
	}
	plait_object *object = &world->objects[id.index1 - 1];
	if (!object->alive || object->generation != id.generation) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ID, "stale object id (the object was destroyed)");
		return NULL;
	}
	return object;
}

void plait_world_update_kinds(plait_world *world)
{
	plait_sim *sim = &world->sim;
	for (int k = 0; k < PLAIT_KIND_COUNT; ++k) {
		sim->kind_importance[k] = 0;
	}
	for (int o = 0; o < world->object_count; ++o) {
		const plait_object *object = &world->objects[o];
		if (!object->alive) {
			continue;
		}
		for (int k = 0; k < PLAIT_KIND_COUNT; ++k) {
			if (object->importance[k] > sim->kind_importance[k]) {
				sim->kind_importance[k] = object->importance[k];
			}
		}
	}
	sim->colouring_dirty = true; /* objects came or went: colour the constraints again */
	sim->mesh_contacts_dirty = true;
	sim->kind_active[PLAIT_KIND_STRETCH] = sim->stretch.count > 0;
	sim->kind_active[PLAIT_KIND_SHEAR] = sim->shear.count > 0;
	sim->kind_active[PLAIT_KIND_BEND] = sim->bend.count + sim->bend_distance.count + sim->rod_bend.count > 0;
	sim->kind_active[PLAIT_KIND_TETHER] = sim->tether.count > 0;
	bool any_collider = false;
	int colliding_objects = 0;
	bool self_pairs = false;
	for (int k = 0; k < sim->collider_count; ++k) {
		any_collider = any_collider || sim->colliders[k].collide;
	}
	for (int m = 0; m < sim->material_count; ++m) {
		const plait_material *mat = &sim->materials[m];
		const plait_object *object = &world->objects[mat->object];
		if (!object->alive || !mat->collide || mat->type == PLAIT_OBJECT_COLLIDER) {
			continue;
		}
		++colliding_objects;
		self_pairs =
		    self_pairs ||
		    ((mat->type == PLAIT_OBJECT_PARTICLES || mat->type == PLAIT_OBJECT_CLOTH) && mat->self_collide);
	}
	sim->kind_active[PLAIT_KIND_COLLISION] =
	    (any_collider && colliding_objects > 0) || colliding_objects >= 2 || self_pairs;
	sim->schedule_dirty = true;
}

plait_object *plait_world_new_object(plait_world *world, plait_object_type type, const char *name,
                                     plait_object_id *id)
{
	if (world->object_count == world->object_capacity) {
		int capacity = world->object_capacity < 8 ? 8 : world->object_capacity * 2;
		plait_object *bigger = plait_alloc_grow(&world->allocator, world->objects, sizeof *bigger,
		                                        world->object_count, capacity);
		if (bigger == NULL) {
			return NULL;
		}
		world->objects = bigger;
		world->object_capacity = capacity;
	}
	int slot = world->object_count++;
	plait_object *object = &world->objects[slot];
	memset(object, 0, sizeof *object);
	object->alive = true;
	object->generation = 1;
	object->type = type;
	object->collider = -1;
	object->material = -1;
	const char *defaults[] = {"cloth", "curve", "particles", "collider"};
	if (name == NULL || name[0] == '\0') {
		snprintf(object->name, sizeof object->name, "%s%d", defaults[type], slot + 1);
	} else {
		snprintf(object->name, sizeof object->name, "%s", name);
	}
	id->world = world;
	id->index1 = slot + 1;
	id->generation = object->generation;
	return object;
}
