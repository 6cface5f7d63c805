/* The distance kernel in AVX2, 8 constraints at a time. Compiled with -mavx2 (and never with
 * FMA contraction); only called when the processor has AVX2. */
#include "dynamics/distance_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

#include "dynamics/batch_layout.h"
#include "dynamics/points_avx2.h"

/* Masked moves are slow on some processors (a masked store is microcoded on AMD's): full
 * batches use plain ones. */
static inline __m256 load_lanes(const float *from, __m256i lanes, int count)
{
	return count == 8 ? _mm256_loadu_ps(from) : _mm256_maskload_ps(from, lanes);
}

static inline void store_lanes(float *to, __m256i lanes, int count, __m256 value)
{
	if (count == 8) {
		_mm256_storeu_ps(to, value);
	} else {
		_mm256_maskstore_ps(to, lanes, value);
	}
}

/* Full batches whose 16 points lie in runs of consecutive points move them with 256-bit loads
 * and stores (two points each) instead of 128-bit ones and their inserts and extracts, as the
 * AVX-512 kernel does (the layouts: batch_layout.h). Here all four leave
 * lane 4 h + m holding constraint 2 m + h (RUN_LANES); each lane's arithmetic is unchanged, so
 * are the bits. */

/* Lane 4 h + m holds constraint 2 m + h; constraint k is in lane RUN_SLOTS[k]. */
#define RUN_LANES _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7)
#define RUN_SLOTS _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7)

/* A per-constraint array's 8 values from `from` in the layout's lane order. */
static inline __m256 load_values(const float *from, plait_batch_layout layout, __m256i lanes, int count)
{
	if (layout == PLAIT_LAYOUT_GATHER) {
		return load_lanes(from, lanes, count);
	}
	return _mm256_permutevar8x32_ps(_mm256_loadu_ps(from), RUN_LANES);
}

static inline void store_values(float *to, plait_batch_layout layout, __m256i lanes, int count, __m256 values)
{
	if (layout == PLAIT_LAYOUT_GATHER) {
		store_lanes(to, lanes, count, values);
	} else {
		_mm256_storeu_ps(to, _mm256_permutevar8x32_ps(values, RUN_SLOTS));
	}
}

/* gather8's transposition within each 128-bit half: half h of r[m] holds the point of
 * constraint 2 m + h. */
static inline void transpose_halves(const __m256 r[4], __m256 *x, __m256 *y, __m256 *z, __m256 *w)
{
	__m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpacklo_ps(r[2], r[3]);
	__m256 t2 = _mm256_unpackhi_ps(r[0], r[1]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
	*x = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	*y = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	*z = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	*w = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

static inline void untranspose_halves(__m256 x, __m256 y, __m256 z, __m256 w, __m256 r[4])
{
	__m256 t0 = _mm256_unpacklo_ps(x, y), t1 = _mm256_unpacklo_ps(z, w);
	__m256 t2 = _mm256_unpackhi_ps(x, y), t3 = _mm256_unpackhi_ps(z, w);
	r[0] = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	r[1] = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	r[2] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	r[3] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* Both sides of a batch in a run layout, half h of i[m] and j[m] holding the points of
 * constraint 2 m + h. (_mm256_permute2f128_ps picks halves: 0 and 1 the first source's, 2 and
 * 3 the second's, low nibble for the low half.) */
static inline void load_halves(plait_point *points, const uint32_t *offset, plait_batch_layout layout,
                               __m256 i[4], __m256 j[4])
{
	const float *a = point_at(points, offset[0]);
	if (layout == PLAIT_LAYOUT_RUNS) {
		const float *b = point_at(points, offset[1]);
		for (int m = 0; m < 4; ++m) {
			i[m] = _mm256_loadu_ps(a + 8 * m);
			j[m] = _mm256_loadu_ps(b + 8 * m);
		}
	} else if (layout == PLAIT_LAYOUT_PAIRS) {
		for (int m = 0; m < 4; ++m) {
			__m256 first = _mm256_loadu_ps(a + 16 * m), second = _mm256_loadu_ps(a + 16 * m + 8);
			i[m] = _mm256_permute2f128_ps(first, second, 0x20);
			j[m] = _mm256_permute2f128_ps(first, second, 0x31);
		}
	} else if (layout == PLAIT_LAYOUT_SKIP) {
		/* Points 4 m .. 4 m + 3: constraints 2 m and 2 m + 1 joining the first two to the last two. */
		for (int m = 0; m < 4; ++m) {
			i[m] = _mm256_loadu_ps(a + 16 * m);
			j[m] = _mm256_loadu_ps(a + 16 * m + 8);
		}
	} else {
		const float *b = point_at(points, offset[2]);
		for (int m = 0; m < 4; ++m) {
			__m256 ra = _mm256_loadu_ps(a + 8 * m), rb = _mm256_loadu_ps(b + 8 * m);
			i[m] = _mm256_permute2f128_ps(ra, rb, 0x20);
			j[m] = _mm256_permute2f128_ps(ra, rb, 0x13);
		}
	}
}

/* The inverse of load_halves. */
static inline void store_halves(plait_point *points, const uint32_t *offset, plait_batch_layout layout,
                                const __m256 i[4], const __m256 j[4])
{
	float *a = (float *)point_at(points, offset[0]);
	if (layout == PLAIT_LAYOUT_RUNS) {
		float *b = (float *)point_at(points, offset[1]);
		for (int m = 0; m < 4; ++m) {
			_mm256_storeu_ps(a + 8 * m, i[m]);
			_mm256_storeu_ps(b + 8 * m, j[m]);
		}
	} else if (layout == PLAIT_LAYOUT_PAIRS) {
		for (int m = 0; m < 4; ++m) {
			_mm256_storeu_ps(a + 16 * m, _mm256_permute2f128_ps(i[m], j[m], 0x20));
			_mm256_storeu_ps(a + 16 * m + 8, _mm256_permute2f128_ps(i[m], j[m], 0x31));
		}
	} else if (layout == PLAIT_LAYOUT_SKIP) {
		for (int m = 0; m < 4; ++m) {
			_mm256_storeu_ps(a + 16 * m, i[m]);
			_mm256_storeu_ps(a + 16 * m + 8, j[m]);
		}
	} else {
		float *b = (float *)point_at(points, offset[2]);
		for (int m = 0; m < 4; ++m) {
			_mm256_storeu_ps(a + 8 * m, _mm256_permute2f128_ps(i[m], j[m], 0x30));
			_mm256_storeu_ps(b + 8 * m, _mm256_permute2f128_ps(i[m], j[m], 0x21));
		}
	}
}

/* Projects constraints [c, c + count), count <= 8. Lanes past count compute on copies of lane
 * 0, are masked out of the block's arrays and are not written back. */
static inline __attribute__((always_inline)) void project8(plait_distance_block *block, plait_point *points,
                                                           int c, int count, __m256 ih2, bool rigid,
                                                           plait_batch_layout layout)
{
	const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
	const __m256 negative_zero = _mm256_set1_ps(-0.0f), tiny = _mm256_set1_ps(1e-12f);
	const __m256 tiny_sq = _mm256_set1_ps(1e-24f);
	__m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(count), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
	/* A full batch reads its offsets where they are (read again for the scatter: the compiler
	 * cannot tell that the stores to points leave them alone, and a load costs less than
	 * keeping sixteen addresses in registers); a short one copies them, lane 0's repeated. */
	const uint32_t *offset = block->point_offset[c];
	uint32_t short_offset[2 * 8];
	if (count < 8) {
		for (int k = 0; k < 8; ++k) {
			int lane = k < count ? k : 0;
			short_offset[2 * k] = offset[2 * lane];
			short_offset[2 * k + 1] = offset[2 * lane + 1];
		}
		offset = short_offset;
	}
	__m256 xi, yi, zi, wi, xj, yj, zj, wj;
	if (layout != PLAIT_LAYOUT_GATHER) {
		__m256 ri[4], rj[4];
		load_halves(points, offset, layout, ri, rj);
		transpose_halves(ri, &xi, &yi, &zi, &wi);
		transpose_halves(rj, &xj, &yj, &zj, &wj);
	} else {
		gather8_at(points, offset, 2, &xi, &yi, &zi, &wi);
		gather8_at(points, offset + 1, 2, &xj, &yj, &zj, &wj);
	}
	__m256 dx = _mm256_sub_ps(xj, xi), dy = _mm256_sub_ps(yj, yi), dz = _mm256_sub_ps(zj, zi);
	__m256 length_sq =
	    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
	__m256 s;
	if (rigid) {
		/* No compliance: the step without a square root (distance_kernel.h). */
		__m256 rest = load_values(block->rest + c, layout, lanes, count);
		__m256 rest_sq = _mm256_mul_ps(rest, rest);
		__m256 sum_sq = _mm256_max_ps(_mm256_add_ps(length_sq, rest_sq), tiny_sq);
		__m256 w_sum = _mm256_add_ps(wi, wj);
		__m256 moving = _mm256_cmp_ps(w_sum, zero, _CMP_GT_OQ);
		__m256 denominator = _mm256_blendv_ps(one, _mm256_mul_ps(w_sum, sum_sq), moving);
		s = _mm256_and_ps(_mm256_div_ps(_mm256_sub_ps(rest_sq, length_sq), denominator), moving);
	} else {
		__m256 length = _mm256_max_ps(_mm256_sqrt_ps(length_sq), tiny);
		__m256 C = _mm256_sub_ps(length, load_values(block->rest + c, layout, lanes, count));
		__m256 alpha = _mm256_blendv_ps(load_values(block->compliance_compression + c, layout, lanes, count),
		                                load_values(block->compliance_tension + c, layout, lanes, count),
		                                _mm256_cmp_ps(C, zero, _CMP_GT_OQ));
		__m256 w_sum = _mm256_add_ps(wi, wj);
		__m256 moving = _mm256_cmp_ps(w_sum, zero, _CMP_GT_OQ);
		__m256 active = _mm256_and_ps(_mm256_cmp_ps(alpha, zero, _CMP_GE_OQ), moving);
		__m256 alpha_tilde = _mm256_mul_ps(_mm256_max_ps(alpha, zero), ih2);
		__m256 denominator = _mm256_mul_ps(_mm256_add_ps(w_sum, alpha_tilde), length);
		denominator = _mm256_blendv_ps(one, denominator, moving);
		__m256 lambda = load_values(block->lambda + c, layout, lanes, count);
		s = _mm256_div_ps(_mm256_sub_ps(_mm256_sub_ps(negative_zero, C), _mm256_mul_ps(alpha_tilde, lambda)),
		                  denominator);
		s = _mm256_and_ps(s, active);
		store_values(block->lambda + c, layout, lanes, count,
		             _mm256_add_ps(lambda, _mm256_mul_ps(s, length)));
	}
	/* Each end by its own difference to the other (distance_kernel.h). */
	__m256 si = _mm256_mul_ps(wi, s), sj = _mm256_mul_ps(wj, s);
	__m256 ex = _mm256_sub_ps(xi, xj), ey = _mm256_sub_ps(yi, yj), ez = _mm256_sub_ps(zi, zj);
	xi = _mm256_sub_ps(xi, _mm256_mul_ps(si, dx));
	yi = _mm256_sub_ps(yi, _mm256_mul_ps(si, dy));
	zi = _mm256_sub_ps(zi, _mm256_mul_ps(si, dz));
	xj = _mm256_sub_ps(xj, _mm256_mul_ps(sj, ex));
	yj = _mm256_sub_ps(yj, _mm256_mul_ps(sj, ey));
	zj = _mm256_sub_ps(zj, _mm256_mul_ps(sj, ez));
	if (layout != PLAIT_LAYOUT_GATHER) {
		__m256 ri[4], rj[4];
		untranspose_halves(xi, yi, zi, wi, ri);
		untranspose_halves(xj, yj, zj, wj, rj);
		store_halves(points, offset, layout, ri, rj);
	} else if (count == 8) {
		scatter8_at(points, offset, 2, xi, yi, zi, wi);
		scatter8_at(points, offset + 1, 2, xj, yj, zj, wj);
	} else {
		int index_i[8], index_j[8];
		for (int k = 0; k < 8; ++k) {
			index_i[k] = (int)(offset[2 * k] / sizeof(plait_point));
			index_j[k] = (int)(offset[2 * k + 1] / sizeof(plait_point));
		}
		scatter8(points, index_i, count, xi, yi, zi, wi);
		scatter8(points, index_j, count, xj, yj, zj, wj);
	}
}

/* A full batch, in its layout: a case for each, so that each gets its own copy of project8 with
 * the layout a constant. */
static inline __attribute__((always_inline)) void project_full8(plait_distance_block *block,
                                                                plait_point *points, int c, __m256 ih2,
                                                                bool rigid, plait_batch_layout layout)
{
	switch (layout) {
	case PLAIT_LAYOUT_RUNS:
		project8(block, points, c, 8, ih2, rigid, PLAIT_LAYOUT_RUNS);
		break;
	case PLAIT_LAYOUT_PAIRS:
		project8(block, points, c, 8, ih2, rigid, PLAIT_LAYOUT_PAIRS);
		break;
	case PLAIT_LAYOUT_SHEAR:
		project8(block, points, c, 8, ih2, rigid, PLAIT_LAYOUT_SHEAR);
		break;
	case PLAIT_LAYOUT_SKIP:
		project8(block, points, c, 8, ih2, rigid, PLAIT_LAYOUT_SKIP);
		break;
	case PLAIT_LAYOUT_GATHER:
	default: /* (no other value is kept) */
		project8(block, points, c, 8, ih2, rigid, PLAIT_LAYOUT_GATHER);
		break;
	}
}

void plait_project_distance_avx2(plait_distance_block *block, plait_point *points, int begin, int end,
                                 float inverse_h_squared)
{
	const __m256 ih2 = _mm256_set1_ps(inverse_h_squared);
	int c = begin;
	const unsigned char *kept = block->colouring.batch_layout;
	if (block->compliant_count == 0) {
		for (; c + 8 <= end; c += 8) {
			project_full8(block, points, c, ih2, true,
			              kept != NULL ? plait_layout8(kept[c]) : PLAIT_LAYOUT_GATHER);
		}
		if (c < end) {
			project8(block, points, c, end - c, ih2, true, PLAIT_LAYOUT_GATHER);
		}
	} else {
		for (; c + 8 <= end; c += 8) {
			project_full8(block, points, c, ih2, false,
			              kept != NULL ? plait_layout8(kept[c]) : PLAIT_LAYOUT_GATHER);
		}
		if (c < end) {
			project8(block, points, c, end - c, ih2, false, PLAIT_LAYOUT_GATHER);
		}
	}
	/* Clean upper halves before returning to code built for SSE: the compiler leaves them
	 * dirty when the remainder is a tail call, and SSE instructions after that carry a false
	 * dependency on them (the dihedral bend kernel, SSE, ran twice as slow). */
	_mm256_zeroupper();
}
#endif
