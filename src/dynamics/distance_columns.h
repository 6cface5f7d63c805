/* Plain C pieces of the column kernel (distance_columns_avx512.c), kept apart from its vector
 * code: a constraint projected alone on columns, with the portable kernel's arithmetic, and
 * finding the segment a range starts in. */
#ifndef PLAIT_DYNAMICS_DISTANCE_COLUMNS_H
#define PLAIT_DYNAMICS_DISTANCE_COLUMNS_H

#include <math.h>
#include <stdbool.h>

#include "dynamics/batch_layout.h"
#include "dynamics/distance_kernel.h"

/* The point index of a byte offset (plait_point_offset). */
static inline uint32_t index_of(uint32_t offset)
{
	return offset / (uint32_t)sizeof(plait_point);
}

/* One constraint, as distance_scalar.c. */
static inline __attribute__((always_inline)) void project_alone(plait_distance_block *block,
                                                                const plait_columns *columns, int c,
                                                                uint32_t i, uint32_t j,
                                                                float inverse_h_squared, bool rigid)
{
	float *x = columns->x, *y = columns->y, *z = columns->z;
	float wi = columns->w[i], wj = columns->w[j];
	float dx = x[j] - x[i], dy = y[j] - y[i], dz = z[j] - z[i];
	float s = plait_distance_step(block, c, dx, dy, dz, wi, wj, inverse_h_squared, rigid);
	float si = wi * s, sj = wj * s;
	float ex = x[i] - x[j], ey = y[i] - y[j], ez = z[i] - z[j];
	x[i] = x[i] - si * dx;
	y[i] = y[i] - si * dy;
	z[i] = z[i] - si * dz;
	x[j] = x[j] - sj * ex;
	y[j] = y[j] - sj * ey;
	z[j] = z[j] - sj * ez;
}

/* The last segment starting at or before constraint c (the block has segments, c coloured). */
static inline int segment_at(const plait_colouring *colouring, int c)
{
	int low = 0, high = colouring->segment_count - 1;
	while (low < high) {
		int middle = (low + high + 1) / 2;
		if (colouring->segments[middle].start <= c) {
			low = middle;
		} else {
			high = middle - 1;
		}
	}
	return low;
}

#endif
