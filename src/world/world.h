/* The world: the public API's state. Owns the simulation (dynamics/sim.h) and maps objects,
 * which users see, onto particle ranges, materials and colliders, which the solver sees. */
#ifndef PLAIT_WORLD_H
#define PLAIT_WORLD_H

#include "dynamics/sim.h"
#include "topology/topology.h"

#define PLAIT_MAX_NAME 64

typedef struct plait_object {
	bool alive;
	uint16_t generation;
	plait_object_type type;
	char name[PLAIT_MAX_NAME];
	int first_particle, particle_count;
	int material;
	int collider;            /* index into sim.colliders, or -1 */
	plait_topology topology; /* cloth only */
	int importance[PLAIT_KIND_COUNT];
} plait_object;

struct plait_world {
	plait_allocator allocator;
	plait_world_def def;
	plait_sim sim;
	plait_object *objects;
	int object_count, object_capacity;
	plait_frame_stats stats;
};

typedef struct plait_world plait_world;

/* Resolves an object id, or NULL (with an error) when it is null, stale or of another world. */
plait_object *plait_world_resolve(plait_object_id id, plait_error *error);

/* Recomputes kind importance and activity from the live objects; marks the schedule dirty. */
void plait_world_update_kinds(plait_world *world);

/* Frees what a collider owns (a mesh shape). */
void plait_collider_release(plait_world *world, plait_collider *collider);

/* A new object slot (alive, next generation); NULL when out of memory. */
plait_object *plait_world_new_object(plait_world *world, plait_object_type type, const char *name,
                                     plait_object_id *id);

#endif
