#include "core/alloc.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PLAIT_ALIGNMENT 64

void *plait_alloc(const plait_allocator *allocator, size_t size)
{
	if (size == 0) {
		return NULL;
	}
	if (allocator->alloc != NULL) {
		return allocator->alloc(size, PLAIT_ALIGNMENT, allocator->context);
	}
	size_t rounded = (size + PLAIT_ALIGNMENT - 1) / PLAIT_ALIGNMENT * PLAIT_ALIGNMENT;
	return aligned_alloc(PLAIT_ALIGNMENT, rounded);
}

void *plait_alloc_zero(const plait_allocator *allocator, size_t count, size_t element_size)
{
	if (count == 0 || element_size == 0 || count > SIZE_MAX / element_size) {
		return NULL;
	}
	void *memory = plait_alloc(allocator, count * element_size);
	if (memory != NULL) {
		memset(memory, 0, count * element_size);
	}
	return memory;
}

void *plait_alloc_grow(const plait_allocator *allocator, void *array, size_t element_size, int count_used,
                       int new_capacity)
{
	void *bigger = plait_alloc_zero(allocator, (size_t)new_capacity, element_size);
	if (bigger == NULL) {
		return NULL;
	}
	if (array != NULL && count_used > 0) {
		memcpy(bigger, array, (size_t)count_used * element_size);
	}
	plait_free(allocator, array);
	return bigger;
}

void plait_free(const plait_allocator *allocator, void *memory)
{
	if (memory == NULL) {
		return;
	}
	if (allocator->free != NULL) {
		allocator->free(memory, allocator->context);
	} else {
		free(memory);
	}
}
