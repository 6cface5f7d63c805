/* Spatial hash for loose particles (paper §7: a hash table for unstructured complexes, where
 * building a tree's topology would cost too much). Cells are cubes; each cell maps to a bucket
 * of a power-of-two table; entries are stored bucket by bucket (a counting sort), so building
 * is O(n) and the order of everything is deterministic. */
#ifndef PLAIT_COLLISION_PARTICLE_HASH_H
#define PLAIT_COLLISION_PARTICLE_HASH_H

#include "core/alloc.h"
#include "core/math.h"

typedef struct plait_hash_cell {
	int x, y, z;
} plait_hash_cell;

typedef struct plait_particle_hash {
	float cell_size;
	int table_size; /* power of two */
	int entry_count, entry_capacity;
	int *bucket_start; /* table_size + 1 */
	int *entry_particle;
	plait_hash_cell *entry_cell;
	plait_hash_cell *particle_cell; /* per input slot */
	int particle_capacity;
} plait_particle_hash;

void plait_particle_hash_destroy(plait_particle_hash *hash, const plait_allocator *allocator);

/* Inserts particles[0..count) (indices into positions). False when out of memory. */
bool plait_particle_hash_build(plait_particle_hash *hash, const plait_allocator *allocator, const vec3 *positions,
                               const int *particles, int count, float cell_size);

plait_hash_cell plait_particle_hash_cell_of(const plait_particle_hash *hash, vec3 p);
int plait_particle_hash_bucket(const plait_particle_hash *hash, plait_hash_cell cell);

#endif
