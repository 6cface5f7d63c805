#include "collision/axis_sort.h"

#include <string.h>

static float axis_value(vec3 v, int axis)
{
	return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

/* Bottom-up merge sort: qsort needs global state for the axis, and is not stable. */
void plait_sort_by_axis(int *order, int count, const vec3 *centre, int axis, int *scratch)
{
	for (int width = 1; width < count; width *= 2) {
		for (int start = 0; start < count; start += 2 * width) {
			int middle = start + width < count ? start + width : count;
			int end = start + 2 * width < count ? start + 2 * width : count;
			int i = start, j = middle, k = start;
			while (i < middle && j < end) {
				float a = axis_value(centre[order[i]], axis), b = axis_value(centre[order[j]], axis);
				scratch[k++] = (b < a || (b == a && order[j] < order[i])) ? order[j++] : order[i++];
			}
			while (i < middle) {
				scratch[k++] = order[i++];
			}
			while (j < end) {
				scratch[k++] = order[j++];
			}
		}
		memcpy(order, scratch, sizeof(int) * (size_t)count);
	}
}
