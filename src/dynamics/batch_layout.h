/* Where the points of a SIMD batch of distance constraints lie: the vector kernels
 * (distance_avx2.c, distance_avx512.c) move a batch whose points lie in runs of consecutive
 * points with full-width loads and stores, and gather the others point by point. In a grid
 * cloth most batches can lie in runs, in one of four layouts (a = the first constraint's
 * first point, b = its second, b1 = the second constraint's first, k = the constraint's lane):
 *   RUNS:  constraint k joins a + k and b + k (edges across rows, bend and shear along them);
 *   PAIRS: constraint k joins a + 2k and a + 2k + 1 (every other edge along a row);
 *   SHEAR: constraint 2m joins a + 2m and b1 + 2m + 1, constraint 2m + 1 joins b1 + 2m and
 *          a + 2m + 1 (the two diagonals of a row of quads, alternating).
 *   SKIP:  constraint 2m joins a + 4m and a + 4m + 2, constraint 2m + 1 joins a + 4m + 1 and
 *          a + 4m + 3 (skip-one edges along a row, two on and two off).
 *
 * Which layout a batch has depends on its constraints alone, so it is found once, when the
 * block is coloured, and kept in the colouring (plait_colouring.batch_layout): a byte per
 * position, whose bits 0-2 give the layout of the 16 constraints from there (AVX-512) and
 * bits 3-5 that of the 8 (AVX2). Finding it at each projection took 6% of the kernel's time. */
#ifndef PLAIT_DYNAMICS_BATCH_LAYOUT_H
#define PLAIT_DYNAMICS_BATCH_LAYOUT_H

#include <stdint.h>

#include "dynamics/sim.h"

typedef enum plait_batch_layout {
	PLAIT_LAYOUT_GATHER, /* anything else: points loaded one by one */
	PLAIT_LAYOUT_RUNS,
	PLAIT_LAYOUT_PAIRS,
	PLAIT_LAYOUT_SHEAR,
	PLAIT_LAYOUT_SKIP,
	/* Segments only: SHEAR with a taken from the first constraint's second point. */
	PLAIT_LAYOUT_SHEAR_FLIPPED,
} plait_batch_layout;

/* The layouts kept for a position: 16 lanes from it, and 8. */
static inline plait_batch_layout plait_layout16(unsigned char kept)
{
	return (plait_batch_layout)(kept & 7u);
}

static inline plait_batch_layout plait_layout8(unsigned char kept)
{
	return (plait_batch_layout)((kept >> 3) & 7u);
}

/* The layout of the `lanes` constraints (8 or 16) whose point offset pairs start at offset
 * (plait_distance_block.point_offset[c]: constraint k's at offset[2 k] and offset[2 k + 1]). */
plait_batch_layout plait_batch_layout_of(const uint32_t *offset, int lanes);

/* layout[c] for every position of block's coloured runs (block->colouring): the layout of each
 * batch of 16 that starts a multiple of 16 after its run's start and ends inside it, and the
 * same for 8; zero (gather) elsewhere. layout holds plait_colouring_end(&block->colouring)
 * bytes. */
void plait_find_batch_layouts(const plait_distance_block *block, unsigned char *layout);

/* Segments: the same layouts, for the column kernel (distance_columns_avx512.c), which needs
 * no batch to start at a multiple of 16 and masks a short one at no cost, and whose constraints
 * may join their points either way round. Each coloured run is cut, from its start, into the
 * longest prefixes of at most 16 constraints that lie in one layout; a constraint that begins
 * none (of two or more) is a segment of one, projected alone. A segment keeps its base points,
 * so the kernel reads neither the constraints' points nor their offsets: at hang-512 those are
 * 12.5 MB a sweep, the segments under 2 MB. */
typedef struct plait_segment {
	int start;            /* its first constraint */
	uint32_t a, b;        /* base points (byte offsets): plait_segment_bases, or a lone pair's ends */
	unsigned char layout; /* plait_batch_layout; PLAIT_LAYOUT_GATHER: a constraint alone */
	unsigned char length; /* 1 to 16 */
} plait_segment;

/* The base points (byte offsets) of a segment in `layout` whose first constraint is
 * offset[0], offset[1]: a and b of RUNS (constraint k joins a + k and b + k); a of PAIRS and
 * SKIP (the lower point); a and b1 of SHEAR (constraint 2m joins a + 2m and b1 + 2m + 1,
 * constraint 2m + 1 joins b1 + 2m and a + 2m + 1), a the first point, or the second when
 * FLIPPED. */
static inline void plait_segment_bases(const uint32_t *offset, plait_batch_layout layout, uint32_t *a,
                                       uint32_t *b)
{
	uint32_t step = (uint32_t)sizeof(plait_point), lower = offset[0] < offset[1] ? offset[0] : offset[1];
	switch (layout) {
	case PLAIT_LAYOUT_PAIRS:
	case PLAIT_LAYOUT_SKIP:
		*a = lower;
		*b = lower;
		break;
	case PLAIT_LAYOUT_SHEAR:
		*a = offset[0];
		*b = offset[1] - step;
		break;
	case PLAIT_LAYOUT_SHEAR_FLIPPED:
		*a = offset[1];
		*b = offset[0] - step;
		break;
	default:
		*a = offset[0];
		*b = offset[1];
		break;
	}
}

/* The segments of block's coloured runs, in order, into segments[] (NULL: only counted);
 * returns how many. */
int plait_find_segments(const plait_distance_block *block, plait_segment *segments);

#endif
