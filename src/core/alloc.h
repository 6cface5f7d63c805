/* Allocation through the user's hooks (plait_world_def.alloc/free), never malloc directly. */
#ifndef PLAIT_CORE_ALLOC_H
#define PLAIT_CORE_ALLOC_H

#include <stddef.h>

#include <plait/plait.h>

typedef struct plait_allocator {
	plait_alloc_fn *alloc;
	plait_free_fn *free;
	void *context;
} plait_allocator;

/* 64-byte aligned so hot arrays start on a cache line. NULL on failure or size 0. */
void *plait_alloc(const plait_allocator *allocator, size_t size);
/* Zeroed allocation of count elements; guards against size overflow. */
void *plait_alloc_zero(const plait_allocator *allocator, size_t count, size_t element_size);
void plait_free(const plait_allocator *allocator, void *memory);
/* A larger copy of array (its first count_used elements of element_size, the rest zeroed) with
 * room for new_capacity; the old array is freed. NULL when out of memory (array untouched). */
void *plait_alloc_grow(const plait_allocator *allocator, void *array, size_t element_size, int count_used,
                       int new_capacity);

#endif
