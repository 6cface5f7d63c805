#include "dynamics/batch_layout.h"

#include <stdbool.h>

#define STEP ((uint32_t)sizeof(plait_point)) /* one point on, in bytes */

plait_batch_layout plait_batch_layout_of(const uint32_t *offset, int lanes)
{
	uint32_t a = offset[0], b = offset[1], b1 = offset[2];
	bool runs = true, pairs = true, shear = true, skip = true;
	for (int k = 0; k < lanes; ++k) {
		uint32_t on = STEP * (uint32_t)k;
		runs = runs && offset[2 * k] == a + on && offset[2 * k + 1] == b + on;
		pairs = pairs && offset[2 * k] == a + 2 * on && offset[2 * k + 1] == a + 2 * on + STEP;
		/* Lane 2m + 1 is lane 2m's mirror: first and second points from the other run. */
		uint32_t even = STEP * (uint32_t)(k & ~1);
		uint32_t first = k % 2 == 0 ? a + even : b1 + even, second = k % 2 == 0 ? b1 + even : a + even;
		shear = shear && offset[2 * k] == first && offset[2 * k + 1] == second + STEP;
		uint32_t skipped = a + 2 * even + STEP * (uint32_t)(k % 2);
		skip = skip && offset[2 * k] == skipped && offset[2 * k + 1] == skipped + 2 * STEP;
	}
	return runs    ? PLAIT_LAYOUT_RUNS
	       : pairs ? PLAIT_LAYOUT_PAIRS
	       : shear ? PLAIT_LAYOUT_SHEAR
	       : skip  ? PLAIT_LAYOUT_SKIP
	               : PLAIT_LAYOUT_GATHER;
}

void plait_find_batch_layouts(const plait_distance_block *block, unsigned char *layout)
{
	const plait_colouring *colouring = &block->colouring;
	for (int run = 0; run < colouring->run_count; ++run) {
		int begin = colouring->run_start[run], end = colouring->run_start[run + 1];
		for (int c = begin; c < end; ++c) {
			layout[c] = 0;
		}
		for (int c = begin; c + 8 <= end; c += 8) {
			layout[c] = (unsigned char)(plait_batch_layout_of(block->point_offset[c], 8) << 3);
		}
		for (int c = begin; c + 16 <= end; c += 16) {
			layout[c] |= (unsigned char)plait_batch_layout_of(block->point_offset[c], 16);
		}
	}
}

/* Whether constraint pair (p, q) joins e0 and e1, either way round: a projection moves each end
 * by its own difference to the other (distance_kernel.h), the same bits whichever end is first,
 * so a segment's constraints may be stored either way; only its base points are read from its
 * first constraint. */
static inline bool joins(const uint32_t *pair, uint32_t e0, uint32_t e1)
{
	return (pair[0] == e0 && pair[1] == e1) || (pair[0] == e1 && pair[1] == e0);
}

/* The number of constraints from offset (at most `most`) that lie in segment layout `layout`,
 * its base points taken from the first constraint as the column kernel takes them
 * (plait_segment_bases). */
static int lanes_in_segment(const uint32_t *offset, int most, plait_batch_layout layout)
{
	uint32_t a, b;
	plait_segment_bases(offset, layout, &a, &b);
	int k = 0;
	for (; k < most; ++k) {
		uint32_t on = STEP * (uint32_t)k, even = STEP * (uint32_t)(k & ~1), odd = STEP * (uint32_t)(k % 2);
		const uint32_t *pair = offset + 2 * k;
		bool fits = false;
		switch (layout) {
		case PLAIT_LAYOUT_RUNS:
			fits = joins(pair, a + on, b + on);
			break;
		case PLAIT_LAYOUT_PAIRS:
			fits = joins(pair, a + 2 * on, a + 2 * on + STEP);
			break;
		case PLAIT_LAYOUT_SHEAR:
		case PLAIT_LAYOUT_SHEAR_FLIPPED:
			fits =
			    k % 2 == 0 ? joins(pair, a + even, b + even + STEP) : joins(pair, b + even, a + even + STEP);
			break;
		case PLAIT_LAYOUT_SKIP:
			fits = joins(pair, a + 2 * even + odd, a + 2 * even + odd + 2 * STEP);
			break;
		default:
			break;
		}
		if (!fits) {
			break;
		}
	}
	return k;
}

int plait_find_segments(const plait_distance_block *block, plait_segment *segments)
{
	static const plait_batch_layout layouts[] = {PLAIT_LAYOUT_RUNS, PLAIT_LAYOUT_PAIRS, PLAIT_LAYOUT_SHEAR,
	                                             PLAIT_LAYOUT_SHEAR_FLIPPED, PLAIT_LAYOUT_SKIP};
	const plait_colouring *colouring = &block->colouring;
	int found = 0;
	for (int run = 0; run < colouring->run_count; ++run) {
		int begin = colouring->run_start[run], end = colouring->run_start[run + 1];
		for (int c = begin; c < end; ++found) {
			const uint32_t *offset = block->point_offset[c];
			int most = end - c < 16 ? end - c : 16, length = 1;
			plait_batch_layout best = PLAIT_LAYOUT_GATHER;
			for (int k = 0; k < 5 && most > 1; ++k) {
				int lanes = lanes_in_segment(offset, most, layouts[k]);
				if (lanes > length) {
					length = lanes;
					best = layouts[k];
				}
			}
			if (segments != NULL) {
				plait_segment *segment = &segments[found];
				segment->start = c;
				plait_segment_bases(offset, best, &segment->a, &segment->b);
				segment->layout = (unsigned char)best;
				segment->length = (unsigned char)length;
			}
			c += length;
		}
	}
	return found;
}
