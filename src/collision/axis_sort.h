/* The stable sort the hierarchies are built with: indices by a point's coordinate along one
 * axis, ties by index, so a tree never depends on a library sort's tie-breaking. */
#ifndef PLAIT_COLLISION_AXIS_SORT_H
#define PLAIT_COLLISION_AXIS_SORT_H

#include "core/math.h"

/* Sorts order[0, count) by centre[order[k]] along axis (0, 1, 2); scratch holds count ints. */
void plait_sort_by_axis(int *order, int count, const vec3 *centre, int axis, int *scratch);

#endif
