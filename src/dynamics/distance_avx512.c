/* The distance kernel in AVX-512, 16 constraints at a time (AVX-512F only). Compiled with
 * -mavx512f (and never with FMA contraction); only called when the processor has AVX-512F. The
 * remainder of a range is one masked batch. */
#include "dynamics/distance_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

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
static inline void gather16(plait_point *points, const uint32_t *offset, __m512 *x, __m512 *y, __m512 *z,
                            __m512 *w)
{
	__m512 r[4];
	for (int m = 0; m < 4; ++m) {
		__m512 v = _mm512_castps128_ps512(load_point(points, offset[2 * m]));
		v = _mm512_insertf32x4(v, load_point(points, offset[2 * (m + 4)]), 1);
		v = _mm512_insertf32x4(v, load_point(points, offset[2 * (m + 8)]), 2);
		r[m] = _mm512_insertf32x4(v, load_point(points, offset[2 * (m + 12)]), 3);
	}
	__m512 t0 = _mm512_unpacklo_ps(r[0], r[1]);
	__m512 t1 = _mm512_unpacklo_ps(r[2], r[3]);
	__m512 t2 = _mm512_unpackhi_ps(r[0], r[1]);
	__m512 t3 = _mm512_unpackhi_ps(r[2], r[3]);
	*x = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	*y = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	*z = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	*w = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* The inverse of gather16, storing the first `count` lanes only (lanes past a range's end
 * repeat lane 0's points, which must not be written back over it). Lane k's offset is
 * offset[2 k]: one side of a block's point_offset pairs. */
static inline void scatter16(plait_point *points, const uint32_t *offset, int count, __m512 x, __m512 y,
                             __m512 z, __m512 w)
{
	__m512 t0 = _mm512_unpacklo_ps(x, y);
	__m512 t1 = _mm512_unpacklo_ps(z, w);
	__m512 t2 = _mm512_unpackhi_ps(x, y);
	__m512 t3 = _mm512_unpackhi_ps(z, w);
	__m512 r[4] = {_mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0)),
	               _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2)),
	               _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0)),
	               _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2))};
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

/* Projects constraints [c + skip, c + count), count <= 16. Lanes past count compute on copies
 * of lane 0, are masked out of the block's arrays and are not written back. The first `skip`
 * lanes (a range's tail batch, `tail`: count is 16 and they were projected by the batch before)
 * compute without effect and write their points back unchanged, which no other lane touches. */
static inline __attribute__((always_inline)) void project16(plait_distance_block *block, plait_point *points,
                                                            int c, int count, int skip, bool tail, __m512 ih2,
                                                            bool rigid)
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
	gather16(points, offset, &xi, &yi, &zi, &wi);
	gather16(points, offset + 1, &xj, &yj, &zj, &wj);
	__m512 dx = _mm512_sub_ps(xj, xi), dy = _mm512_sub_ps(yj, yi), dz = _mm512_sub_ps(zj, zi);
	__m512 length_sq =
	    _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz));
	__m512 s;
	if (rigid) {
		/* No compliance: the rational step of distance_scalar.c, without a square root. */
		__m512 rest = _mm512_maskz_loadu_ps(lanes, block->rest + c);
		__m512 rest_sq = _mm512_mul_ps(rest, rest);
		__m512 sum_sq = _mm512_max_ps(_mm512_add_ps(length_sq, rest_sq), tiny_sq);
		__m512 w_sum = _mm512_add_ps(wi, wj);
		__mmask16 moving = _mm512_mask_cmp_ps_mask(update, w_sum, zero, _CMP_GT_OQ);
		__m512 denominator = _mm512_mask_blend_ps(moving, one, _mm512_mul_ps(w_sum, sum_sq));
		s = _mm512_maskz_mov_ps(moving, _mm512_div_ps(_mm512_sub_ps(rest_sq, length_sq), denominator));
	} else {
		__m512 length = _mm512_max_ps(_mm512_sqrt_ps(length_sq), tiny);
		__m512 C = _mm512_sub_ps(length, _mm512_maskz_loadu_ps(lanes, block->rest + c));
		__mmask16 stretched = _mm512_cmp_ps_mask(C, zero, _CMP_GT_OQ);
		__m512 alpha =
		    _mm512_mask_blend_ps(stretched, _mm512_maskz_loadu_ps(lanes, block->compliance_compression + c),
		                         _mm512_maskz_loadu_ps(lanes, block->compliance_tension + c));
		__m512 w_sum = _mm512_add_ps(wi, wj);
		__mmask16 moving = _mm512_cmp_ps_mask(w_sum, zero, _CMP_GT_OQ);
		__mmask16 active = _mm512_mask_cmp_ps_mask(moving & update, alpha, zero, _CMP_GE_OQ);
		__m512 alpha_tilde = _mm512_mul_ps(_mm512_max_ps(alpha, zero), ih2);
		__m512 denominator = _mm512_mul_ps(_mm512_add_ps(w_sum, alpha_tilde), length);
		denominator = _mm512_mask_blend_ps(moving, one, denominator);
		__m512 lambda = _mm512_maskz_loadu_ps(lanes, block->lambda + c);
		s = _mm512_div_ps(_mm512_sub_ps(_mm512_sub_ps(negative_zero, C), _mm512_mul_ps(alpha_tilde, lambda)),
		                  denominator);
		s = _mm512_maskz_mov_ps(active, s);
		_mm512_mask_storeu_ps(block->lambda + c, update, _mm512_add_ps(lambda, _mm512_mul_ps(s, length)));
	}
	__m512 si = _mm512_mul_ps(wi, s), sj = _mm512_mul_ps(wj, s);
	/* Skipped lanes keep their loaded bits (x - 0 d would turn a -0 into +0). */
	xi = _mm512_mask_sub_ps(xi, update, xi, _mm512_mul_ps(si, dx));
	yi = _mm512_mask_sub_ps(yi, update, yi, _mm512_mul_ps(si, dy));
	zi = _mm512_mask_sub_ps(zi, update, zi, _mm512_mul_ps(si, dz));
	xj = _mm512_mask_add_ps(xj, update, xj, _mm512_mul_ps(sj, dx));
	yj = _mm512_mask_add_ps(yj, update, yj, _mm512_mul_ps(sj, dy));
	zj = _mm512_mask_add_ps(zj, update, zj, _mm512_mul_ps(sj, dz));
	scatter16(points, offset, count, xi, yi, zi, wi);
	scatter16(points, offset + 1, count, xj, yj, zj, wj);
}

void plait_project_distance_avx512(plait_distance_block *block, plait_point *points, int begin, int end,
                                   float inverse_h_squared)
{
	const __m512 ih2 = _mm512_set1_ps(inverse_h_squared);
	int c = begin;
	bool rigid = block->compliant_count == 0;
	/* A range of 16 or more ends with a full batch over its last 16, the lanes done already
	 * skipped: a short batch's copies and masked moves cost about two full ones, and most
	 * colour runs end in one. */
	if (rigid) {
		for (; c + 16 <= end; c += 16) {
			project16(block, points, c, 16, 0, false, ih2, true);
		}
		if (c < end && end - begin >= 16) {
			project16(block, points, end - 16, 16, c - (end - 16), true, ih2, true);
			c = end;
		}
	} else {
		for (; c + 16 <= end; c += 16) {
			project16(block, points, c, 16, 0, false, ih2, false);
		}
		if (c < end && end - begin >= 16) {
			project16(block, points, end - 16, 16, c - (end - 16), true, ih2, false);
			c = end;
		}
	}
	if (c < end) {
		project16(block, points, c, end - c, 0, false, ih2, rigid);
	}
	/* Clean upper halves before returning to code built for SSE: the compiler leaves them
	 * dirty when the remainder is a tail call, and SSE instructions after that carry a false
	 * dependency on them (the dihedral bend kernel, SSE, ran twice as slow). */
	_mm256_zeroupper();
}
#endif
