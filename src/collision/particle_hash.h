/* Spatial hash for loose particles (paper §7: a hash table for unstructured complexes, where
 * building a tree's topology would cost too much). Space is cut into cubes of cell_size; each
 * particle is entered in every cell its swept, thickened box touches (its path over the substep
 * plus its radius), so fast particles are found too. Cells map to buckets of a power-of-two
 * table; entries are stored bucket by bucket (a counting sort), so building is O(entries) and
 * the order of everything is deterministic. */
#ifndef PLAIT_COLLISION_PARTICLE_HASH_H
#define PLAIT_COLLISION_PARTICLE_HASH_H

#include "core/alloc.h"
#include "core/math.h"

typedef struct plait_hash_cell {
	int x, y, z;
} plait_hash_cell;

/* A particle's cell range: cells lower..upper on each axis (inclusive). */
typedef struct plait_hash_range {
	plait_hash_cell lower, upper;
} plait_hash_range;

typedef struct plait_hash_entry {
	plait_hash_cell cell;
	plait_hash_cell lower; /* first cell of the particle's range (see owns_pair) */
	int particle;
	int slot; /* index into the boxes given to build */
} plait_hash_entry;

typedef struct plait_particle_hash {
	float cell_size;
	int table_size; /* power of two */
	int entry_count, entry_capacity;
	int *bucket_start; /* table_size + 1 */
	plait_hash_entry *entries;
	plait_hash_entry *scratch;
	int scratch_capacity;
	plait_hash_range *ranges; /* per slot */
	int range_capacity;
} plait_particle_hash;

void plait_particle_hash_destroy(plait_particle_hash *hash, const plait_allocator *allocator);

/* Enters particles[0..count) with swept boxes [lower[k], upper[k]] (world units). False when
 * out of memory. */
bool plait_particle_hash_build(plait_particle_hash *hash, const plait_allocator *allocator,
                               const int *particles, const vec3 *lower, const vec3 *upper, int count,
                               float cell_size);

int plait_particle_hash_bucket(const plait_particle_hash *hash, plait_hash_cell cell);

/* True when `cell` (shared by entries a and b) is the first cell, lowest on every axis, of the
 * cells their ranges share: each pair is handled in exactly one of them. */
static inline bool plait_particle_hash_owns_pair(const plait_hash_entry *a, const plait_hash_entry *b)
{
	int x = a->lower.x > b->lower.x ? a->lower.x : b->lower.x;
	int y = a->lower.y > b->lower.y ? a->lower.y : b->lower.y;
	int z = a->lower.z > b->lower.z ? a->lower.z : b->lower.z;
	return a->cell.x == x && a->cell.y == y && a->cell.z == z;
}

#endif
