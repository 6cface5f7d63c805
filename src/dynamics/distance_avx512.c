/* The distance kernel in AVX-512, 16 constraints at a time (AVX-512F only). Compiled with
 * -mavx512f (and never with FMA contraction); only called when the processor has AVX-512F. The
 * remainder of a range is one masked batch. */
#include "dynamics/distance_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

#include "dynamics/batch_layout.h"
#include "dynamics/points_avx512.h"

/* Points by byte offset (plait_point_offset). */
static inline float *point_at(plait_point *points, uint32_t offset)
{
	return (float *)((char *)points + offset);
}

static inline __m128 load_point(plait_point *points, uint32_t offset)
{
	return _mm_load_ps(point_at(points, offset));
}

/* Loads the points of one side of 16 constraints and transposes them into a register per
 * coordinate, lane k holding constraint k: register r_m gets points m, m + 4, m + 8 and m + 12
 * in its four 128-bit blocks, and a 4x4 transpose inside each block finishes the job. */
static inline void gather16_at(plait_point *points, const uint32_t *offset, __m512 *x, __m512 *y, __m512 *z,
                               __m512 *w)
{
	__m512 r[4];
	for (int m = 0; m < 4; ++m) {
		__m512 v = _mm512_castps128_ps512(load_point(points, offset[2 * m]));
		v = _mm512_insertf32x4(v, load_point(points, offset[2 * (m + 4)]), 1);
		v = _mm512_insertf32x4(v, load_point(points, offset[2 * (m + 8)]), 2);
		r[m] = _mm512_insertf32x4(v, load_point(points, offset[2 * (m + 12)]), 3);
	}
	transpose_points16(r, x, y, z, w);
}

/* The inverse of gather16_at, storing the first `count` lanes only (lanes past a range's end
 * repeat lane 0's points, which must not be written back over it). Lane k's offset is
 * offset[2 k]: one side of a block's point_offset pairs. */
static inline void scatter16_at(plait_point *points, const uint32_t *offset, int count, __m512 x, __m512 y,
                                __m512 z, __m512 w)
{
	__m512 r[4];
	untranspose_points16(x, y, z, w, r);
	if (count == 16) {
		for (int m = 0; m < 4; ++m) {
			_mm_store_ps(point_at(points, offset[2 * m]), _mm512_castps512_ps128(r[m]));
			_mm_store_ps(point_at(points, offset[2 * (m + 4)]), _mm512_extractf32x4_ps(r[m], 1));
			_mm_store_ps(point_at(points, offset[2 * (m + 8)]), _mm512_extractf32x4_ps(r[m], 2));
			_mm_store_ps(point_at(points, offset[2 * (m + 12)]), _mm512_extractf32x4_ps(r[m], 3));
		}
		return;
	}
	_Alignas(64) plait_point lanes[16];
	for (int m = 0; m < 4; ++m) {
		_mm_store_ps(&lanes[m].x.x, _mm512_castps512_ps128(r[m]));
		_mm_store_ps(&lanes[m + 4].x.x, _mm512_extractf32x4_ps(r[m], 1));
		_mm_store_ps(&lanes[m + 8].x.x, _mm512_extractf32x4_ps(r[m], 2));
		_mm_store_ps(&lanes[m + 12].x.x, _mm512_extractf32x4_ps(r[m], 3));
	}
	for (int k = 0; k < count; ++k) {
		_mm_store_ps(point_at(points, offset[2 * k]), _mm_load_ps(&lanes[k].x.x));
	}
}

/* Batches whose 32 points lie in runs of consecutive points (batch_layout.h; most full
 * batches of a grid cloth) move them with full-width loads and stores and a few block
 * permutes instead of sixteen 128-bit loads and stores a side and their inserts and extracts:
 * the kernel is bound by those shuffles (on Zen 4 a 512-bit shuffle takes two of its shuffle
 * slots). The lanes then hold the constraints in another order (BLOCK_LANES), the same on both
 * sides and for the rest lengths; each lane's arithmetic is unchanged, so are the bits. */

/* Lane 4 b + m of a batch in one of the run layouts holds its constraint 4 m + b. */
#define BLOCK_LANES POINT_LANES
/* Shear batches' blocks hold constraints 4 m, 4 m + 2, 4 m + 1, 4 m + 3: lane L holds
 * SHEAR_LANES[L], and constraint k is in lane SHEAR_SLOTS[k]. (BLOCK_LANES is its own
 * inverse.) */
#define SHEAR_LANES _mm512_setr_epi32(0, 4, 8, 12, 2, 6, 10, 14, 1, 5, 9, 13, 3, 7, 11, 15)
#define SHEAR_SLOTS _mm512_setr_epi32(0, 8, 4, 12, 1, 9, 5, 13, 2, 10, 6, 14, 3, 11, 7, 15)

/* The batch's 16 values of a per-constraint array from `from` (its first constraint), in the
 * layout's lane order; a gathered batch's first `count` (the rest zero). */
static inline __m512 load_values(const float *from, plait_batch_layout layout, __mmask16 lanes)
{
	switch (layout) {
	case PLAIT_LAYOUT_GATHER:
		return _mm512_maskz_loadu_ps(lanes, from);
	case PLAIT_LAYOUT_SHEAR:
		return _mm512_permutexvar_ps(SHEAR_LANES, _mm512_loadu_ps(from));
	default:
		return _mm512_permutexvar_ps(BLOCK_LANES, _mm512_loadu_ps(from));
	}
}

/* The inverse of load_values for the lanes in `update`. */
static inline void store_values(float *to, plait_batch_layout layout, __mmask16 update, __m512 values)
{
	switch (layout) {
	case PLAIT_LAYOUT_GATHER:
		_mm512_mask_storeu_ps(to, update, values);
		break;
	case PLAIT_LAYOUT_SHEAR:
		_mm512_storeu_ps(to, _mm512_permutexvar_ps(SHEAR_SLOTS, values));
		break;
	default:
		_mm512_storeu_ps(to, _mm512_permutexvar_ps(BLOCK_LANES, values));
		break;
	}
}

/* Permute indices picking 128-bit blocks from two registers: block k of the result is block
 * (q >> 1) of the first source (q even) or the second (q odd), q = the k-th argument. */
#define BLOCKS(q0, q1, q2, q3)                                                                               \
	_mm512_setr_epi32(BLOCK_INDEX(q0, 0), BLOCK_INDEX(q0, 1), BLOCK_INDEX(q0, 2), BLOCK_INDEX(q0, 3),        \
	                  BLOCK_INDEX(q1, 0), BLOCK_INDEX(q1, 1), BLOCK_INDEX(q1, 2), BLOCK_INDEX(q1, 3),        \
	                  BLOCK_INDEX(q2, 0), BLOCK_INDEX(q2, 1), BLOCK_INDEX(q2, 2), BLOCK_INDEX(q2, 3),        \
	                  BLOCK_INDEX(q3, 0), BLOCK_INDEX(q3, 1), BLOCK_INDEX(q3, 2), BLOCK_INDEX(q3, 3))
#define BLOCK_INDEX(q, lane) ((((q)&1) << 4) | (((q) >> 1) << 2) | (lane))
#define FIRST(block) (2 * (block))      /* block of the first source */
#define SECOND(block) (2 * (block) + 1) /* block of the second */

/* Both sides of a batch in a run layout, block b of i[m] and j[m] holding the points of
 * constraint 4 m + b (BLOCK_LANES once transposed; in a shear batch, 4 m + (0, 2, 1, 3)[b]:
 * SHEAR_LANES). */
static inline void load_blocks(plait_point *points, const uint32_t *offset, plait_batch_layout layout,
                               __m512 i[4], __m512 j[4])
{
	const float *a = point_at(points, offset[0]);
	if (layout == PLAIT_LAYOUT_RUNS) {
		const float *b = point_at(points, offset[1]);
		for (int m = 0; m < 4; ++m) {
			i[m] = _mm512_loadu_ps(a + 16 * m);
			j[m] = _mm512_loadu_ps(b + 16 * m);
		}
	} else if (layout == PLAIT_LAYOUT_PAIRS) {
		for (int m = 0; m < 4; ++m) {
			__m512 low = _mm512_loadu_ps(a + 32 * m), high = _mm512_loadu_ps(a + 32 * m + 16);
			i[m] = _mm512_shuffle_f32x4(low, high, _MM_SHUFFLE(2, 0, 2, 0));
			j[m] = _mm512_shuffle_f32x4(low, high, _MM_SHUFFLE(3, 1, 3, 1));
		}
	} else if (layout == PLAIT_LAYOUT_SKIP) {
		for (int m = 0; m < 4; ++m) {
			/* Points 8 m .. 8 m + 3: constraints 4 m and 4 m + 1 joining the first two to the last two. */
			__m512 low = _mm512_loadu_ps(a + 32 * m), high = _mm512_loadu_ps(a + 32 * m + 16);
			i[m] = _mm512_shuffle_f32x4(low, high, _MM_SHUFFLE(1, 0, 1, 0));
			j[m] = _mm512_shuffle_f32x4(low, high, _MM_SHUFFLE(3, 2, 3, 2));
		}
	} else {
		const float *b = point_at(points, offset[2]);
		for (int m = 0; m < 4; ++m) {
			__m512 ra = _mm512_loadu_ps(a + 16 * m), rb = _mm512_loadu_ps(b + 16 * m);
			/* Blocks: constraints 4 m, 4 m + 2, 4 m + 1, 4 m + 3 (SHEAR_LANES). */
			i[m] = _mm512_shuffle_f32x4(ra, rb, _MM_SHUFFLE(2, 0, 2, 0));
			j[m] = _mm512_shuffle_f32x4(rb, ra, _MM_SHUFFLE(3, 1, 3, 1));
		}
	}
}

/* The inverse of load_blocks. */
static inline void store_blocks(plait_point *points, const uint32_t *offset, plait_batch_layout layout,
                                const __m512 i[4], const __m512 j[4])
{
	float *a = point_at(points, offset[0]);
	if (layout == PLAIT_LAYOUT_RUNS) {
		float *b = point_at(points, offset[1]);
		for (int m = 0; m < 4; ++m) {
			_mm512_storeu_ps(a + 16 * m, i[m]);
			_mm512_storeu_ps(b + 16 * m, j[m]);
		}
	} else if (layout == PLAIT_LAYOUT_PAIRS) {
		const __m512i first = BLOCKS(FIRST(0), SECOND(0), FIRST(1), SECOND(1));
		const __m512i second = BLOCKS(FIRST(2), SECOND(2), FIRST(3), SECOND(3));
		for (int m = 0; m < 4; ++m) {
			_mm512_storeu_ps(a + 32 * m, _mm512_permutex2var_ps(i[m], first, j[m]));
			_mm512_storeu_ps(a + 32 * m + 16, _mm512_permutex2var_ps(i[m], second, j[m]));
		}
	} else if (layout == PLAIT_LAYOUT_SKIP) {
		for (int m = 0; m < 4; ++m) {
			_mm512_storeu_ps(a + 32 * m, _mm512_shuffle_f32x4(i[m], j[m], _MM_SHUFFLE(1, 0, 1, 0)));
			_mm512_storeu_ps(a + 32 * m + 16, _mm512_shuffle_f32x4(i[m], j[m], _MM_SHUFFLE(3, 2, 3, 2)));
		}
	} else {
		float *b = point_at(points, offset[2]);
		const __m512i to_a = BLOCKS(FIRST(0), SECOND(2), FIRST(1), SECOND(3));
		const __m512i to_b = BLOCKS(FIRST(2), SECOND(0), FIRST(3), SECOND(1));
		for (int m = 0; m < 4; ++m) {
			_mm512_storeu_ps(a + 16 * m, _mm512_permutex2var_ps(i[m], to_a, j[m]));
			_mm512_storeu_ps(b + 16 * m, _mm512_permutex2var_ps(i[m], to_b, j[m]));
		}
	}
}

/* Projects constraints [c + skip, c + count), count <= 16. Lanes past count compute on copies
 * of lane 0, are masked out of the block's arrays and are not written back. The first `skip`
 * lanes (a range's tail batch, `tail`: count is 16 and they were projected by the batch before)
 * compute without effect and write their points back unchanged, which no other lane touches. */
static inline __attribute__((always_inline)) void project16(plait_distance_block *block, plait_point *points,
                                                            int c, int count, int skip, bool tail, __m512 ih2,
                                                            bool rigid, plait_batch_layout layout)
{
	const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
	const __m512 negative_zero = _mm512_set1_ps(-0.0f), tiny = _mm512_set1_ps(1e-12f);
	const __m512 tiny_sq = _mm512_set1_ps(1e-24f);
	__mmask16 lanes = (__mmask16)((1u << count) - 1u);
	__mmask16 update = tail ? (__mmask16)(0xFFFFu << skip) : lanes;
	/* A full batch reads its offsets where they are; a short one copies them, lane 0's
	 * repeated past count. */
	const uint32_t *offset = block->point_offset[c];
	uint32_t short_offset[2 * 16];
	if (count < 16) {
		for (int k = 0; k < 16; ++k) {
			int lane = k < count ? k : 0;
			short_offset[2 * k] = offset[2 * lane];
			short_offset[2 * k + 1] = offset[2 * lane + 1];
		}
		offset = short_offset;
	}
	__m512 xi, yi, zi, wi, xj, yj, zj, wj;
	if (layout != PLAIT_LAYOUT_GATHER) {
		__m512 ri[4], rj[4];
		load_blocks(points, offset, layout, ri, rj);
		transpose_points16(ri, &xi, &yi, &zi, &wi);
		transpose_points16(rj, &xj, &yj, &zj, &wj);
	} else {
		gather16_at(points, offset, &xi, &yi, &zi, &wi);
		gather16_at(points, offset + 1, &xj, &yj, &zj, &wj);
	}
	__m512 dx = _mm512_sub_ps(xj, xi), dy = _mm512_sub_ps(yj, yi), dz = _mm512_sub_ps(zj, zi);
	__m512 length_sq =
	    _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz));
	__m512 s;
	if (rigid) {
		/* No compliance: the rational step of distance_scalar.c, without a square root. */
		__m512 rest = load_values(block->rest + c, layout, lanes);
		__m512 rest_sq = _mm512_mul_ps(rest, rest);
		__m512 sum_sq = _mm512_max_ps(_mm512_add_ps(length_sq, rest_sq), tiny_sq);
		__m512 w_sum = _mm512_add_ps(wi, wj);
		__mmask16 moving = _mm512_mask_cmp_ps_mask(update, w_sum, zero, _CMP_GT_OQ);
		__m512 denominator = _mm512_mask_blend_ps(moving, one, _mm512_mul_ps(w_sum, sum_sq));
		s = _mm512_maskz_mov_ps(moving, _mm512_div_ps(_mm512_sub_ps(rest_sq, length_sq), denominator));
	} else {
		__m512 length = _mm512_max_ps(_mm512_sqrt_ps(length_sq), tiny);
		__m512 C = _mm512_sub_ps(length, load_values(block->rest + c, layout, lanes));
		__mmask16 stretched = _mm512_cmp_ps_mask(C, zero, _CMP_GT_OQ);
		__m512 alpha =
		    _mm512_mask_blend_ps(stretched, load_values(block->compliance_compression + c, layout, lanes),
		                         load_values(block->compliance_tension + c, layout, lanes));
		__m512 w_sum = _mm512_add_ps(wi, wj);
		__mmask16 moving = _mm512_cmp_ps_mask(w_sum, zero, _CMP_GT_OQ);
		__mmask16 active = _mm512_mask_cmp_ps_mask(moving & update, alpha, zero, _CMP_GE_OQ);
		__m512 alpha_tilde = _mm512_mul_ps(_mm512_max_ps(alpha, zero), ih2);
		__m512 denominator = _mm512_mul_ps(_mm512_add_ps(w_sum, alpha_tilde), length);
		denominator = _mm512_mask_blend_ps(moving, one, denominator);
		__m512 lambda = load_values(block->lambda + c, layout, lanes);
		s = _mm512_div_ps(_mm512_sub_ps(_mm512_sub_ps(negative_zero, C), _mm512_mul_ps(alpha_tilde, lambda)),
		                  denominator);
		s = _mm512_maskz_mov_ps(active, s);
		store_values(block->lambda + c, layout, update, _mm512_add_ps(lambda, _mm512_mul_ps(s, length)));
	}
	__m512 si = _mm512_mul_ps(wi, s), sj = _mm512_mul_ps(wj, s);
	/* Each end by its own difference to the other (distance_kernel.h). Skipped lanes keep their
	 * loaded bits (x - 0 d would turn a -0 into +0). */
	__m512 ex = _mm512_sub_ps(xi, xj), ey = _mm512_sub_ps(yi, yj), ez = _mm512_sub_ps(zi, zj);
	xi = _mm512_mask_sub_ps(xi, update, xi, _mm512_mul_ps(si, dx));
	yi = _mm512_mask_sub_ps(yi, update, yi, _mm512_mul_ps(si, dy));
	zi = _mm512_mask_sub_ps(zi, update, zi, _mm512_mul_ps(si, dz));
	xj = _mm512_mask_sub_ps(xj, update, xj, _mm512_mul_ps(sj, ex));
	yj = _mm512_mask_sub_ps(yj, update, yj, _mm512_mul_ps(sj, ey));
	zj = _mm512_mask_sub_ps(zj, update, zj, _mm512_mul_ps(sj, ez));
	if (layout != PLAIT_LAYOUT_GATHER) {
		__m512 ri[4], rj[4];
		untranspose_points16(xi, yi, zi, wi, ri);
		untranspose_points16(xj, yj, zj, wj, rj);
		store_blocks(points, offset, layout, ri, rj);
		return;
	}
	scatter16_at(points, offset, count, xi, yi, zi, wi);
	scatter16_at(points, offset + 1, count, xj, yj, zj, wj);
}

/* A full batch, in its layout: a case for each, so that each gets its own copy of project16 with
 * the layout a constant. */
static inline __attribute__((always_inline)) void project_full16(plait_distance_block *block,
                                                                 plait_point *points, int c, __m512 ih2,
                                                                 bool rigid, plait_batch_layout layout)
{
	switch (layout) {
	case PLAIT_LAYOUT_RUNS:
		project16(block, points, c, 16, 0, false, ih2, rigid, PLAIT_LAYOUT_RUNS);
		break;
	case PLAIT_LAYOUT_PAIRS:
		project16(block, points, c, 16, 0, false, ih2, rigid, PLAIT_LAYOUT_PAIRS);
		break;
	case PLAIT_LAYOUT_SHEAR:
		project16(block, points, c, 16, 0, false, ih2, rigid, PLAIT_LAYOUT_SHEAR);
		break;
	case PLAIT_LAYOUT_SKIP:
		project16(block, points, c, 16, 0, false, ih2, rigid, PLAIT_LAYOUT_SKIP);
		break;
	case PLAIT_LAYOUT_GATHER:
	default: /* (no other value is kept) */
		project16(block, points, c, 16, 0, false, ih2, rigid, PLAIT_LAYOUT_GATHER);
		break;
	}
}

void plait_project_distance_avx512(plait_distance_block *block, plait_point *points, int begin, int end,
                                   float inverse_h_squared)
{
	const __m512 ih2 = _mm512_set1_ps(inverse_h_squared);
	int c = begin;
	bool rigid = block->compliant_count == 0;
	const unsigned char *kept = block->colouring.batch_layout;
	/* A range of 16 or more ends with a full batch over its last 16, the lanes done already
	 * skipped: a short batch's copies and masked moves cost about two full ones, and most
	 * colour runs end in one. */
	if (rigid) {
		for (; c + 16 <= end; c += 16) {
			project_full16(block, points, c, ih2, true,
			               kept != NULL ? plait_layout16(kept[c]) : PLAIT_LAYOUT_GATHER);
		}
		if (c < end && end - begin >= 16) {
			project16(block, points, end - 16, 16, c - (end - 16), true, ih2, true, PLAIT_LAYOUT_GATHER);
			c = end;
		}
	} else {
		for (; c + 16 <= end; c += 16) {
			project_full16(block, points, c, ih2, false,
			               kept != NULL ? plait_layout16(kept[c]) : PLAIT_LAYOUT_GATHER);
		}
		if (c < end && end - begin >= 16) {
			project16(block, points, end - 16, 16, c - (end - 16), true, ih2, false, PLAIT_LAYOUT_GATHER);
			c = end;
		}
	}
	if (c < end) {
		project16(block, points, c, end - c, 0, false, ih2, rigid, PLAIT_LAYOUT_GATHER);
	}
	/* Clean upper halves before returning to code built for SSE: the compiler leaves them
	 * dirty when the remainder is a tail call, and SSE instructions after that carry a false
	 * dependency on them (the dihedral bend kernel, SSE, ran twice as slow). */
	_mm256_zeroupper();
}
#endif
