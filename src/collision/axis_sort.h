/* The sorts the hierarchies are built with: indices by a point's coordinate along one axis, ties
 * by index, so a tree never depends on a library sort's tie-breaking.
 *
 * A median-split tree sorts each node's elements along the node's axis and cuts them in half.
 * Sorting every node from scratch costs n log^2 n; plait_axis_orders keeps the elements sorted
 * along all three axes at once and splits the three orders in step (each half keeps its order),
 * which costs n log n and gives every node the same elements in the same order. */
#ifndef PLAIT_COLLISION_AXIS_SORT_H
#define PLAIT_COLLISION_AXIS_SORT_H

#include <stdint.h>

#include "core/alloc.h"
#include "core/math.h"

/* Sorts order[0, count) by centre[order[k]] along axis (0, 1, 2); scratch holds count ints. */
void plait_sort_by_axis(int *order, int count, const vec3 *centre, int axis, int *scratch);

typedef struct plait_axis_orders {
	int *by_axis[3]; /* the elements sorted along x, y and z (each range of a node: its elements) */
	int *scratch;
	uint8_t *in_left; /* per element, scratch of a split */
} plait_axis_orders;

/* The three orders of elements 0..count-1; false when out of memory (nothing to free then). */
bool plait_axis_orders_make(plait_axis_orders *orders, const plait_allocator *allocator, const vec3 *centre,
                            int count);
void plait_axis_orders_free(plait_axis_orders *orders, const plait_allocator *allocator);

/* The bounds of the centres of the elements in [first, first + count) (a node's range). */
void plait_axis_orders_bounds(const plait_axis_orders *orders, const vec3 *centre, int first, int count,
                              vec3 *lower, vec3 *upper);

/* Splits the range [first, first + count) at `half` along axis: the first half of its order
 * along that axis goes first in all three orders, each keeping its order. */
void plait_axis_orders_split(plait_axis_orders *orders, int first, int count, int axis, int half);

#endif
