#include "collision/particle_hash.h"

#include <string.h>

const plait_hash_cell plait_hash_forward_neighbours[13] = {
    {1, 0, 0},  {-1, 1, 0}, {0, 1, 0}, {1, 1, 0},  {-1, -1, 1}, {0, -1, 1}, {1, -1, 1},
    {-1, 0, 1}, {0, 0, 1},  {1, 0, 1}, {-1, 1, 1}, {0, 1, 1},   {1, 1, 1},
};

void plait_particle_hash_destroy(plait_particle_hash *hash, const plait_allocator *allocator)
{
	plait_free(allocator, hash->bucket_start);
	plait_free(allocator, hash->entries);
	plait_free(allocator, hash->scratch);
	memset(hash, 0, sizeof *hash);
}

int plait_particle_hash_bucket(const plait_particle_hash *hash, plait_hash_cell c)
{
	uint32_t h = (uint32_t)c.x * 73856093u ^ (uint32_t)c.y * 19349663u ^ (uint32_t)c.z * 83492791u;
	h ^= h >> 13;
	h *= 0x5bd1e995u;
	h ^= h >> 15;
	return (int)(h & (uint32_t)(hash->table_size - 1));
}

static int cell_coordinate(float value, float inverse)
{
	float c = floorf(value * inverse);
	/* Far-away particles share the outermost cells instead of overflowing an int; a NaN
	 * (a frame going non-finite, caught at its end) lands in one of them too. */
	if (!(c >= -1e9f)) {
		c = -1e9f;
	} else if (c > 1e9f) {
		c = 1e9f;
	}
	return (int)c;
}

static bool reserve(void **array, int *capacity, int needed, size_t size, const plait_allocator *allocator)
{
	if (needed <= *capacity) {
		return true;
	}
	int grown = needed + needed / 2;
	void *bigger = plait_alloc_zero(allocator, (size_t)grown, size);
	if (bigger == NULL) {
		return false;
	}
	plait_free(allocator, *array);
	*array = bigger;
	*capacity = grown;
	return true;
}

bool plait_particle_hash_build(plait_particle_hash *hash, const plait_allocator *allocator,
                               const int *particles, const vec3 *lower, const vec3 *upper, int count,
                               float cell_size)
{
	hash->cell_size = cell_size;
	float inverse = 1.0f / cell_size;
	int table_size = 64;
	while (table_size < 2 * count) {
		table_size *= 2;
	}
	if (table_size != hash->table_size) {
		plait_free(allocator, hash->bucket_start);
		hash->bucket_start = plait_alloc_zero(allocator, (size_t)table_size + 1, sizeof(int));
		hash->table_size = hash->bucket_start != NULL ? table_size : 0;
		if (hash->bucket_start == NULL) {
			return false;
		}
	}
	if (!reserve((void **)&hash->entries, &hash->entry_capacity, count, sizeof *hash->entries, allocator) ||
	    !reserve((void **)&hash->scratch, &hash->scratch_capacity, count, sizeof *hash->scratch, allocator)) {
		return false;
	}
	hash->entry_count = count;
	memset(hash->bucket_start, 0, sizeof(int) * ((size_t)table_size + 1));
	for (int k = 0; k < count; ++k) {
		vec3 centre = v3_scale(v3_add(lower[k], upper[k]), 0.5f);
		plait_hash_entry *entry = &hash->scratch[k];
		entry->cell =
		    (plait_hash_cell){cell_coordinate(centre.x, inverse), cell_coordinate(centre.y, inverse),
		                      cell_coordinate(centre.z, inverse)};
		entry->particle = particles[k];
		entry->slot = k;
		hash->bucket_start[plait_particle_hash_bucket(hash, entry->cell) + 1] += 1;
	}
	for (int b = 0; b < table_size; ++b) {
		hash->bucket_start[b + 1] += hash->bucket_start[b];
	}
	/* Counting sort into buckets, keeping input order inside each bucket (deterministic). */
	for (int k = 0; k < count; ++k) {
		int b = plait_particle_hash_bucket(hash, hash->scratch[k].cell);
		hash->entries[hash->bucket_start[b]++] = hash->scratch[k];
	}
	for (int b = table_size; b > 0; --b) {
		hash->bucket_start[b] = hash->bucket_start[b - 1];
	}
	hash->bucket_start[0] = 0;
	return true;
}
