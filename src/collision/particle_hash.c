#include "collision/particle_hash.h"

#include <string.h>

/* A particle whose path crosses more cells than this per axis is entered in this many only
 * around its end position: such speeds are far outside what a substep resolves anyway. */
#define MAX_CELLS_PER_AXIS 8

void plait_particle_hash_destroy(plait_particle_hash *hash, const plait_allocator *allocator)
{
	plait_free(allocator, hash->bucket_start);
	plait_free(allocator, hash->entries);
	plait_free(allocator, hash->scratch);
	plait_free(allocator, hash->ranges);
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
	/* Far-away particles share the outermost cells instead of overflowing an int. */
	c = c < -1e9f ? -1e9f : c > 1e9f ? 1e9f : c;
	return (int)c;
}

static void clamp_axis(int *lower, int *upper)
{
	if (*upper - *lower >= MAX_CELLS_PER_AXIS) {
		*lower = *upper - (MAX_CELLS_PER_AXIS - 1);
	}
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
	if (!reserve((void **)&hash->ranges, &hash->range_capacity, count, sizeof *hash->ranges, allocator)) {
		return false;
	}
	int entry_count = 0;
	for (int k = 0; k < count; ++k) {
		plait_hash_range *r = &hash->ranges[k];
		r->lower =
		    (plait_hash_cell){cell_coordinate(lower[k].x, inverse), cell_coordinate(lower[k].y, inverse),
		                      cell_coordinate(lower[k].z, inverse)};
		r->upper =
		    (plait_hash_cell){cell_coordinate(upper[k].x, inverse), cell_coordinate(upper[k].y, inverse),
		                      cell_coordinate(upper[k].z, inverse)};
		clamp_axis(&r->lower.x, &r->upper.x);
		clamp_axis(&r->lower.y, &r->upper.y);
		clamp_axis(&r->lower.z, &r->upper.z);
		entry_count +=
		    (r->upper.x - r->lower.x + 1) * (r->upper.y - r->lower.y + 1) * (r->upper.z - r->lower.z + 1);
	}
	int table_size = 64;
	while (table_size < 2 * entry_count) {
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
	if (!reserve((void **)&hash->entries, &hash->entry_capacity, entry_count, sizeof *hash->entries,
	             allocator) ||
	    !reserve((void **)&hash->scratch, &hash->scratch_capacity, entry_count, sizeof *hash->scratch,
	             allocator)) {
		return false;
	}
	hash->entry_count = entry_count;
	memset(hash->bucket_start, 0, sizeof(int) * ((size_t)table_size + 1));
	int e = 0;
	for (int k = 0; k < count; ++k) {
		const plait_hash_range *r = &hash->ranges[k];
		for (int z = r->lower.z; z <= r->upper.z; ++z) {
			for (int y = r->lower.y; y <= r->upper.y; ++y) {
				for (int x = r->lower.x; x <= r->upper.x; ++x) {
					plait_hash_entry *entry = &hash->scratch[e++];
					entry->cell = (plait_hash_cell){x, y, z};
					entry->lower = r->lower;
					entry->particle = particles[k];
					entry->slot = k;
					hash->bucket_start[plait_particle_hash_bucket(hash, entry->cell) + 1] += 1;
				}
			}
		}
	}
	for (int b = 0; b < table_size; ++b) {
		hash->bucket_start[b + 1] += hash->bucket_start[b];
	}
	/* Counting sort into buckets, keeping input order inside each bucket (deterministic). */
	for (int k = 0; k < entry_count; ++k) {
		int b = plait_particle_hash_bucket(hash, hash->scratch[k].cell);
		hash->entries[hash->bucket_start[b]++] = hash->scratch[k];
	}
	for (int b = table_size; b > 0; --b) {
		hash->bucket_start[b] = hash->bucket_start[b - 1];
	}
	hash->bucket_start[0] = 0;
	return true;
}
