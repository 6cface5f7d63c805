/* Reading and writing object state, pins, collider transforms, and destroying objects. */
#include <string.h>

#include "core/error.h"
#include "collision/mesh_shape.h"
#include "dynamics/mesh_contact.h"
#include "dynamics/sim_store.h"
#include "world/world.h"

void plait_collider_release(plait_world *world, plait_collider *collider)
{
	if (collider->shape.mesh != NULL) {
		plait_mesh_shape_destroy(collider->shape.mesh, &world->allocator);
		plait_free(&world->allocator, collider->shape.mesh);
		collider->shape.mesh = NULL;
	}
	plait_free(&world->allocator, collider->mesh_start);
	plait_free(&world->allocator, collider->mesh_end);
	collider->mesh_start = NULL;
	collider->mesh_end = NULL;
	plait_free(&world->allocator, collider->clear_at);
	plait_free(&world->allocator, collider->clearance);
	plait_free(&world->allocator, collider->clear_drift);
	collider->clear_at = NULL;
	collider->clearance = NULL;
	collider->clear_drift = NULL;
	collider->clear_capacity = 0;
}

void plait_destroy_object(plait_object_id id)
{
	plait_object *object = plait_world_resolve(id, NULL);
	if (object == NULL) {
		return;
	}
	plait_world *world = id.world;
	plait_sim *sim = &world->sim;
	if (object->particle_count > 0) {
		bool *keep = plait_alloc_zero(&world->allocator, (size_t)sim->particles.count, sizeof(bool));
		if (keep == NULL) {
			return; /* Out of memory: the object stays rather than half-leaving. */
		}
		for (int i = 0; i < sim->particles.count; ++i) {
			keep[i] = i < object->first_particle || i >= object->first_particle + object->particle_count;
		}
		bool compacted = plait_sim_compact(sim, keep);
		plait_free(&world->allocator, keep);
		if (!compacted) {
			return; /* Out of memory before anything changed: the object stays. */
		}
		for (int o = 0; o < world->object_count; ++o) {
			plait_object *other = &world->objects[o];
			if (other->alive && other->first_particle > object->first_particle) {
				other->first_particle -= object->particle_count;
			}
		}
	}
	/* A curve's chain goes with it; the others follow their particles. */
	for (int k = 0; k < sim->chain_count;) {
		plait_chain *chain = &sim->chains[k];
		if (chain->object == id.index1 - 1) {
			memmove(chain, chain + 1, sizeof *chain * (size_t)(sim->chain_count - k - 1));
			sim->chain_count -= 1;
			continue;
		}
		chain->first = world->objects[chain->object].first_particle;
		++k;
	}
	/* The cloth's surface goes with it; the others keep pointing at their particles. */
	for (int k = 0; k < sim->surface_count;) {
		plait_surface *surface = &sim->surfaces[k];
		if (surface->object == id.index1 - 1) {
			plait_mesh_shape_destroy(surface->shape, &world->allocator);
			plait_free(&world->allocator, surface->shape);
			memmove(surface, surface + 1, sizeof *surface * (size_t)(sim->surface_count - k - 1));
			sim->surface_count -= 1;
			continue;
		}
		surface->first = world->objects[surface->object].first_particle;
		++k;
	}
	/* The colliders' vertices (their particles) follow too. */
	for (int k = 0; k < sim->collider_count; ++k) {
		if (sim->colliders[k].count > 0) {
			sim->colliders[k].first = world->objects[sim->colliders[k].object].first_particle;
		}
	}
	if (object->collider >= 0) {
		int k = object->collider;
		plait_collider_release(world, &sim->colliders[k]);
		memmove(&sim->colliders[k], &sim->colliders[k + 1],
		        sizeof *sim->colliders * (size_t)(sim->collider_count - k - 1));
		sim->collider_count -= 1;
		for (int o = 0; o < world->object_count; ++o) {
			if (world->objects[o].collider > k) {
				world->objects[o].collider -= 1;
			}
		}
	}
	if (object->material >= 0) {
		/* The material slot stays (particles index materials), but takes no part any more. */
		sim->materials[object->material].collide = false;
		sim->materials[object->material].retired = true;
		sim->materials[object->material].drag = 0.0f;
		sim->materials[object->material].tangential_drag = 0.0f;
		sim->materials[object->material].lift = 0.0f;
		sim->materials[object->material].point_drag = 0.0f;
	}
	plait_topology_destroy(&object->topology, &world->allocator);
	object->alive = false;
	object->generation += 1;
	object->particle_count = 0;
	memset(object->importance, 0, sizeof object->importance);
	plait_world_update_kinds(world);
}

bool plait_object_is_valid(plait_object_id id)
{
	return plait_world_resolve(id, NULL) != NULL;
}

plait_object_type plait_object_get_type(plait_object_id id)
{
	plait_object *object = plait_world_resolve(id, NULL);
	return object != NULL ? object->type : PLAIT_OBJECT_PARTICLES;
}

const char *plait_object_get_name(plait_object_id id)
{
	plait_object *object = plait_world_resolve(id, NULL);
	return object != NULL ? object->name : "";
}

int plait_world_get_object_count(plait_world_id world_id)
{
	plait_world *world = world_id.world;
	int count = 0;
	for (int o = 0; world != NULL && o < world->object_count; ++o) {
		count += world->objects[o].alive;
	}
	return count;
}

plait_object_id plait_world_get_object(plait_world_id world_id, int index)
{
	plait_object_id id = {0};
	plait_world *world = world_id.world;
	for (int o = 0; world != NULL && o < world->object_count; ++o) {
		if (!world->objects[o].alive) {
			continue;
		}
		if (index-- == 0) {
			id.world = world;
			id.index1 = o + 1;
			id.generation = world->objects[o].generation;
			return id;
		}
	}
	return id;
}

/* The vertices an object shows through the API: a collider's particles are the solver's own
 * (plait_collider.first), its geometry is read with plait_collider_get_surface_positions. */
static int shown_vertices(const plait_object *object)
{
	return object->type == PLAIT_OBJECT_COLLIDER ? 0 : object->particle_count;
}

int plait_object_get_vertex_count(plait_object_id id)
{
	plait_object *object = plait_world_resolve(id, NULL);
	return object != NULL ? shown_vertices(object) : 0;
}

int plait_object_get_triangles(plait_object_id id, int *indices, int capacity)
{
	plait_object *object = plait_world_resolve(id, NULL);
	if (object == NULL || object->type != PLAIT_OBJECT_CLOTH) {
		return 0;
	}
	const plait_topology *t = &object->topology;
	for (int k = 0; k < t->triangle_count && k < capacity && indices != NULL; ++k) {
		memcpy(indices + 3 * k, t->triangles[k], sizeof t->triangles[k]);
	}
	return t->triangle_count;
}

int plait_object_get_faces(plait_object_id id, int *face_sizes, int *face_indices, int *index_count)
{
	plait_object *object = plait_world_resolve(id, NULL);
	if (object == NULL || object->type != PLAIT_OBJECT_CLOTH) {
		if (index_count != NULL) {
			*index_count = 0;
		}
		return 0;
	}
	const plait_topology *t = &object->topology;
	if (index_count != NULL) {
		*index_count = t->polygon_index_count;
	}
	if (face_sizes != NULL) {
		memcpy(face_sizes, t->polygon_sizes, sizeof(int) * (size_t)t->polygon_count);
	}
	if (face_indices != NULL) {
		memcpy(face_indices, t->polygon_indices, sizeof(int) * (size_t)t->polygon_index_count);
	}
	return t->polygon_count;
}

static plait_object *resolve_range(plait_object_id id, int first, int count, const void *buffer,
                                   plait_error *error)
{
	plait_object *object = plait_world_resolve(id, error);
	if (object == NULL) {
		return NULL;
	}
	int vertices = shown_vertices(object);
	if (first < 0 || count < 0 || first > vertices || count > vertices - first ||
	    (count > 0 && buffer == NULL)) {
		plait_error_set(
		    error, PLAIT_ERROR_INVALID_ARGUMENT,
		    "'%s': %d vertices from vertex %d are outside its %d vertices (or the buffer is NULL)",
		    object->name, count, first, vertices);
		return NULL;
	}
	return object;
}

plait_result plait_object_get_positions(plait_object_id id, int first, int count, plait_vec3 *out,
                                        plait_error *error)
{
	plait_object *object = resolve_range(id, first, count, out, error);
	if (object == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	const plait_point *points = id.world->sim.particles.point + object->first_particle + first;
	for (int k = 0; k < count; ++k) {
		out[k] = points[k].x;
	}
	return PLAIT_OK;
}

plait_result plait_object_get_velocities(plait_object_id id, int first, int count, plait_vec3 *out,
                                         plait_error *error)
{
	plait_object *object = resolve_range(id, first, count, out, error);
	if (object == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	if (count > 0) {
		memcpy(out, id.world->sim.particles.v + object->first_particle + first,
		       sizeof(plait_vec3) * (size_t)count);
	}
	return PLAIT_OK;
}

static bool all_finite(const plait_vec3 *values, int count)
{
	for (int i = 0; i < count; ++i) {
		if (!v3_is_finite(values[i])) {
			return false;
		}
	}
	return true;
}

plait_result plait_object_set_positions(plait_object_id id, int first, int count, const plait_vec3 *positions,
                                        plait_error *error)
{
	plait_object *object = resolve_range(id, first, count, positions, error);
	if (object == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	if (!all_finite(positions, count)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "'%s': positions must be finite",
		                       object->name);
	}
	plait_particles *p = &id.world->sim.particles;
	for (int k = 0; k < count; ++k) {
		int i = object->first_particle + first + k;
		p->point[i].x = positions[k];
		if (p->flags[i] & PLAIT_PARTICLE_PINNED) {
			p->pin_start[i] = positions[k];
			p->pin_end[i] = positions[k];
		}
	}
	plait_mesh_contacts_positions_set(&id.world->sim); /* they may now cross */
	return PLAIT_OK;
}

plait_result plait_object_set_velocities(plait_object_id id, int first, int count,
                                         const plait_vec3 *velocities, plait_error *error)
{
	plait_object *object = resolve_range(id, first, count, velocities, error);
	if (object == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	if (!all_finite(velocities, count)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "'%s': velocities must be finite",
		                       object->name);
	}
	if (count > 0) {
		memcpy(id.world->sim.particles.v + object->first_particle + first, velocities,
		       sizeof(plait_vec3) * (size_t)count);
	}
	return PLAIT_OK;
}

static plait_object *resolve_vertex(plait_object_id id, int vertex, plait_vec3 target, plait_error *error)
{
	plait_object *object = plait_world_resolve(id, error);
	if (object == NULL) {
		return NULL;
	}
	if (vertex < 0 || vertex >= shown_vertices(object)) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "'%s': vertex %d is outside 0..%d", object->name,
		                vertex, shown_vertices(object) - 1);
		return NULL;
	}
	if (!v3_is_finite(target)) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "'%s': pin target must be finite", object->name);
		return NULL;
	}
	return object;
}

plait_result plait_object_pin_vertex(plait_object_id id, int vertex, plait_vec3 target, plait_error *error)
{
	plait_object *object = resolve_vertex(id, vertex, target, error);
	if (object == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	plait_particles *p = &id.world->sim.particles;
	int i = object->first_particle + vertex;
	p->flags[i] |= PLAIT_PARTICLE_PINNED;
	p->point[i].w = 0.0f;
	p->pin_start[i] = p->point[i].x;
	p->pin_end[i] = target;
	p->v[i] = v3(0.0f, 0.0f, 0.0f);
	return PLAIT_OK;
}

plait_result plait_object_unpin_vertex(plait_object_id id, int vertex, plait_error *error)
{
	plait_object *object = resolve_vertex(id, vertex, v3(0.0f, 0.0f, 0.0f), error);
	if (object == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	plait_particles *p = &id.world->sim.particles;
	int i = object->first_particle + vertex;
	p->flags[i] &= (uint8_t)~PLAIT_PARTICLE_PINNED;
	p->point[i].w = 1.0f / p->mass[i];
	return PLAIT_OK;
}

plait_result plait_object_set_pin_target(plait_object_id id, int vertex, plait_vec3 target,
                                         plait_error *error)
{
	plait_object *object = resolve_vertex(id, vertex, target, error);
	if (object == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	plait_particles *p = &id.world->sim.particles;
	int i = object->first_particle + vertex;
	if (!(p->flags[i] & PLAIT_PARTICLE_PINNED)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "'%s': vertex %d is not pinned",
		                       object->name, vertex);
	}
	p->pin_end[i] = target;
	return PLAIT_OK;
}

static plait_collider *resolve_collider(plait_object_id id, plait_error *error)
{
	plait_object *object = plait_world_resolve(id, error);
	if (object == NULL) {
		return NULL;
	}
	if (object->collider < 0) {
		plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "'%s' is not a collider", object->name);
		return NULL;
	}
	return &id.world->sim.colliders[object->collider];
}

plait_result plait_collider_set_transform(plait_object_id id, plait_transform transform, plait_error *error)
{
	plait_collider *collider = resolve_collider(id, error);
	if (collider == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	if (!v3_is_finite(transform.translate) || !v3_is_finite(transform.rotate_deg) ||
	    !(transform.scale > 0.0f) || !isfinite(transform.scale)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "collider transform needs finite translate and rotate and scale > 0");
	}
	collider->transform_end = transform;
	return PLAIT_OK;
}

plait_result plait_collider_set_mesh_positions(plait_object_id id, const plait_vec3 *positions, int count,
                                               plait_error *error)
{
	plait_collider *collider = resolve_collider(id, error);
	if (collider == NULL) {
		return error != NULL ? error->code : PLAIT_ERROR_INVALID_ARGUMENT;
	}
	const char *name = id.world->objects[id.index1 - 1].name;
	if (collider->mesh_end == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "'%s' is a rigid collider; only a mesh collider created with deforming = true "
		                       "takes mesh positions",
		                       name);
	}
	int vertex_count = collider->shape.mesh->vertex_count;
	if (positions == NULL || count != vertex_count) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "'%s': expected %d mesh positions (one per vertex), got %d%s", name,
		                       vertex_count, count, positions == NULL ? " and no array" : "");
	}
	for (int v = 0; v < count; ++v) {
		if (!v3_is_finite(positions[v])) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
			                       "'%s': mesh position %d is not finite (%g, %g, %g)", name, v,
			                       (double)positions[v].x, (double)positions[v].y, (double)positions[v].z);
		}
	}
	memcpy(collider->mesh_end, positions, sizeof(vec3) * (size_t)count);
	return PLAIT_OK;
}

plait_transform plait_collider_get_transform(plait_object_id id)
{
	plait_collider *collider = resolve_collider(id, NULL);
	return collider != NULL ? collider->transform_end : plait_identity_transform();
}

float plait_collider_signed_distance(plait_object_id id, plait_vec3 point)
{
	plait_collider *collider = resolve_collider(id, NULL);
	if (collider == NULL) {
		return INFINITY;
	}
	plait_rigid r = plait_rigid_from_transform(collider->transform_end);
	vec3 normal;
	return plait_shape_distance(&collider->shape, plait_rigid_apply_inverse(&r, point), &normal) * r.scale;
}
