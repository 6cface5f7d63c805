#include "collision/particle_hash.h"

#include <string.h>

void plait_particle_hash_destroy(plait_particle_hash *hash, const plait_allocator *allocator)
{
	plait_free(allocator, hash->bucket_start);
	plait_free(allocator, hash->entry_particle);
	plait_free(allocator, hash->entry_cell);
	plait_free(allocator, hash->particle_cell);
	memset(hash, 0, sizeof *hash);
}

plait_hash_cell plait_particle_hash_cell_of(const plait_particle_hash *hash, vec3 p)
{
	float inverse = 1.0f / hash->cell_size;
	plait_hash_cell c = {(int)floorf(p.x * inverse), (int)floorf(p.y * inverse), (int)floorf(p.z * inverse)};
	return c;
}

int plait_particle_hash_bucket(const plait_particle_hash *hash, plait_hash_cell c)
{
	uint32_t h = (uint32_t)c.x * 73856093u ^ (uint32_t)c.y * 19349663u ^ (uint32_t)c.z * 83492791u;
	h ^= h >> 13;
	h *= 0x5bd1e995u;
	h ^= h >> 15;
	return (int)(h & (uint32_t)(hash->table_size - 1));
}

bool plait_particle_hash_build(plait_particle_hash *hash, const plait_allocator *allocator, const vec3 *positions,
                               const int *particles, int count, float cell_size)
{
	int table_size = 64;
	while (table_size < 2 * count) {
		table_size *= 2;
	}
	if (table_size != hash->table_size) {
		plait_free(allocator, hash->bucket_start);
		hash->bucket_start = plait_alloc_zero(allocator, (size_t)table_size + 1, sizeof(int));
		if (hash->bucket_start == NULL) {
			hash->table_size = 0;
			return false;
		}
		hash->table_size = table_size;
	}
	if (count > hash->entry_capacity) {
		plait_free(allocator, hash->entry_particle);
		plait_free(allocator, hash->entry_cell);
		plait_free(allocator, hash->particle_cell);
		hash->entry_particle = plait_alloc_zero(allocator, (size_t)count, sizeof(int));
		hash->entry_cell = plait_alloc_zero(allocator, (size_t)count, sizeof(plait_hash_cell));
		hash->particle_cell = plait_alloc_zero(allocator, (size_t)count, sizeof(plait_hash_cell));
		if (!hash->entry_particle || !hash->entry_cell || !hash->particle_cell) {
			hash->entry_capacity = 0;
			return false;
		}
		hash->entry_capacity = count;
	}
	hash->cell_size = cell_size;
	hash->entry_count = count;
	memset(hash->bucket_start, 0, sizeof(int) * ((size_t)table_size + 1));
	for (int k = 0; k < count; ++k) {
		plait_hash_cell c = plait_particle_hash_cell_of(hash, positions[particles[k]]);
		hash->particle_cell[k] = c;
		hash->bucket_start[plait_particle_hash_bucket(hash, c) + 1] += 1;
	}
	for (int b = 0; b < table_size; ++b) {
		hash->bucket_start[b + 1] += hash->bucket_start[b];
	}
	/* Fill in input order within each bucket (deterministic), using bucket_start as cursors
	 * shifted by one and restored afterwards. */
	for (int k = 0; k < count; ++k) {
		int b = plait_particle_hash_bucket(hash, hash->particle_cell[k]);
		int slot = hash->bucket_start[b]++;
		hash->entry_particle[slot] = particles[k];
		hash->entry_cell[slot] = hash->particle_cell[k];
	}
	for (int b = table_size; b > 0; --b) {
		hash->bucket_start[b] = hash->bucket_start[b - 1];
	}
	hash->bucket_start[0] = 0;
	return true;
}
