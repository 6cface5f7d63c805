/* Spatial hash for loose particles (paper §7: a hash table for unstructured complexes, where
 * building a tree's topology would cost too much). Each particle is entered once, in the cube
 * cell holding the centre of its swept, thickened box; with cells at least as wide as the
 * largest box, two particles whose boxes overlap sit in the same or neighbouring cells. Cells
 * map to buckets of a power-of-two table; entries are stored bucket by bucket (a counting
 * sort), so building is O(n) and the order of everything is deterministic. */
#ifndef PLAIT_COLLISION_PARTICLE_HASH_H
#define PLAIT_COLLISION_PARTICLE_HASH_H

#include "core/alloc.h"
#include "core/math.h"

typedef struct plait_hash_cell {
	int x, y, z;
} plait_hash_cell;

typedef struct plait_hash_entry {
	plait_hash_cell cell;
	int particle;
	int slot; /* index into the boxes given to build */
} plait_hash_entry;

typedef struct plait_particle_hash {
	float cell_size;
	int table_size; /* power of two */
	int entry_count, entry_capacity, scratch_capacity;
	int *bucket_start; /* table_size + 1 */
	plait_hash_entry *entries;
	plait_hash_entry *scratch;
} plait_particle_hash;

void plait_particle_hash_destroy(plait_particle_hash *hash, const plait_allocator *allocator);

/* Enters particles[0..count) at the centres of their boxes [lower[k], upper[k]]. False when out
 * of memory. */
bool plait_particle_hash_build(plait_particle_hash *hash, const plait_allocator *allocator,
                               const int *particles, const vec3 *lower, const vec3 *upper, int count,
                               float cell_size);

int plait_particle_hash_bucket(const plait_particle_hash *hash, plait_hash_cell cell);

/* The 13 neighbour offsets "after" a cell in lexicographic order: visiting the cell itself and
 * these finds every neighbouring pair of cells exactly once. */
extern const plait_hash_cell plait_hash_forward_neighbours[13];

#endif
