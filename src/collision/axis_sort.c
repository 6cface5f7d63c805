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

bool plait_axis_orders_make(plait_axis_orders *orders, const plait_allocator *allocator, const vec3 *centre,
                            int count)
{
	size_t n = (size_t)(count > 0 ? count : 1);
	*orders = (plait_axis_orders){{NULL, NULL, NULL}, NULL, NULL};
	for (int axis = 0; axis < 3; ++axis) {
		orders->by_axis[axis] = plait_alloc(allocator, sizeof(int) * n);
	}
	orders->scratch = plait_alloc(allocator, sizeof(int) * n);
	orders->in_left = plait_alloc_zero(allocator, n, sizeof(uint8_t));
	if (orders->by_axis[0] == NULL || orders->by_axis[1] == NULL || orders->by_axis[2] == NULL ||
	    orders->scratch == NULL || orders->in_left == NULL) {
		plait_axis_orders_free(orders, allocator);
		return false;
	}
	for (int axis = 0; axis < 3; ++axis) {
		for (int k = 0; k < count; ++k) {
			orders->by_axis[axis][k] = k;
		}
		plait_sort_by_axis(orders->by_axis[axis], count, centre, axis, orders->scratch);
	}
	return true;
}

void plait_axis_orders_free(plait_axis_orders *orders, const plait_allocator *allocator)
{
	for (int axis = 0; axis < 3; ++axis) {
		plait_free(allocator, orders->by_axis[axis]);
		orders->by_axis[axis] = NULL;
	}
	plait_free(allocator, orders->scratch);
	plait_free(allocator, orders->in_left);
	orders->scratch = NULL;
	orders->in_left = NULL;
}

void plait_axis_orders_bounds(const plait_axis_orders *orders, const vec3 *centre, int first, int count,
                              vec3 *lower, vec3 *upper)
{
	int last = first + count - 1;
	*lower = v3(centre[orders->by_axis[0][first]].x, centre[orders->by_axis[1][first]].y,
	            centre[orders->by_axis[2][first]].z);
	*upper = v3(centre[orders->by_axis[0][last]].x, centre[orders->by_axis[1][last]].y,
	            centre[orders->by_axis[2][last]].z);
}

void plait_axis_orders_split(plait_axis_orders *orders, int first, int count, int axis, int half)
{
	const int *along = orders->by_axis[axis];
	for (int k = first; k < first + half; ++k) {
		orders->in_left[along[k]] = 1;
	}
	for (int other = 0; other < 3; ++other) {
		if (other == axis) {
			continue;
		}
		int *order = orders->by_axis[other];
		int left = first, right = 0;
		for (int k = first; k < first + count; ++k) {
			if (orders->in_left[order[k]]) {
				order[left++] = order[k];
			} else {
				orders->scratch[right++] = order[k];
			}
		}
		memcpy(order + left, orders->scratch, sizeof(int) * (size_t)right);
	}
	for (int k = first; k < first + half; ++k) {
		orders->in_left[along[k]] = 0;
	}
}
