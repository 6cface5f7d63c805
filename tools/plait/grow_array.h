/* Growing a malloc'ed array: the tool's readers and checker append items of unknown count. */
#ifndef PLAIT_GROW_ARRAY_H
#define PLAIT_GROW_ARRAY_H

#include <stdbool.h>
#include <stddef.h>

/* Makes *array (of *capacity items of item_size) hold at least `needed` items, doubling from
 * 64. False when out of memory or past INT_MAX items; *array is then unchanged. */
bool plait_grow_array(void **array, int *capacity, long long needed, size_t item_size);

#endif
