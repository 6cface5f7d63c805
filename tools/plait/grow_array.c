#include "grow_array.h"

#include <limits.h>
#include <stdlib.h>

bool plait_grow_array(void **array, int *capacity, long long needed, size_t item_size)
{
	if (needed <= *capacity)
		return true;
	if (needed > INT_MAX)
		return false;
	long long next = *capacity > 0 ? *capacity : 64;
	while (next < needed)
		next *= 2;
	if (next > INT_MAX)
		next = INT_MAX;
	void *grown = realloc(*array, (size_t)next * item_size);
	if (grown == NULL)
		return false;
	*array = grown;
	*capacity = (int)next;
	return true;
}
