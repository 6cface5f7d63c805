/* The distance kernel in AVX2, 8 constraints at a time. Compiled with -mavx2 (and never with
 * FMA contraction); only called when the processor has AVX2. */
#include "dynamics/distance_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

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

/* Projects constraints [c, c + count), count <= 8. Lanes past count compute on copies of lane
 * 0, are masked out of the block's arrays and are not written back. */
static inline __attribute__((always_inline)) void project8(plait_distance_block *block, plait_point *points,
                                                           int c, int count, __m256 ih2, bool rigid)
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
	gather8_at(points, offset, 2, &xi, &yi, &zi, &wi);
	gather8_at(points, offset + 1, 2, &xj, &yj, &zj, &wj);
	__m256 dx = _mm256_sub_ps(xj, xi), dy = _mm256_sub_ps(yj, yi), dz = _mm256_sub_ps(zj, zi);
	__m256 length_sq =
	    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
	__m256 s;
	if (rigid) {
		/* No compliance: the step without a square root (distance_kernel.h). */
		__m256 rest = load_lanes(block->rest + c, lanes, count);
		__m256 rest_sq = _mm256_mul_ps(rest, rest);
		__m256 sum_sq = _mm256_max_ps(_mm256_add_ps(length_sq, rest_sq), tiny_sq);
		__m256 w_sum = _mm256_add_ps(wi, wj);
		__m256 moving = _mm256_cmp_ps(w_sum, zero, _CMP_GT_OQ);
		__m256 denominator = _mm256_blendv_ps(one, _mm256_mul_ps(w_sum, sum_sq), moving);
		s = _mm256_and_ps(_mm256_div_ps(_mm256_sub_ps(rest_sq, length_sq), denominator), moving);
	} else {
		__m256 length = _mm256_max_ps(_mm256_sqrt_ps(length_sq), tiny);
		__m256 C = _mm256_sub_ps(length, load_lanes(block->rest + c, lanes, count));
		__m256 alpha = _mm256_blendv_ps(load_lanes(block->compliance_compression + c, lanes, count),
		                                load_lanes(block->compliance_tension + c, lanes, count),
		                                _mm256_cmp_ps(C, zero, _CMP_GT_OQ));
		__m256 w_sum = _mm256_add_ps(wi, wj);
		__m256 moving = _mm256_cmp_ps(w_sum, zero, _CMP_GT_OQ);
		__m256 active = _mm256_and_ps(_mm256_cmp_ps(alpha, zero, _CMP_GE_OQ), moving);
		__m256 alpha_tilde = _mm256_mul_ps(_mm256_max_ps(alpha, zero), ih2);
		__m256 denominator = _mm256_mul_ps(_mm256_add_ps(w_sum, alpha_tilde), length);
		denominator = _mm256_blendv_ps(one, denominator, moving);
		__m256 lambda = load_lanes(block->lambda + c, lanes, count);
		s = _mm256_div_ps(_mm256_sub_ps(_mm256_sub_ps(negative_zero, C), _mm256_mul_ps(alpha_tilde, lambda)),
		                  denominator);
		s = _mm256_and_ps(s, active);
		store_lanes(block->lambda + c, lanes, count, _mm256_add_ps(lambda, _mm256_mul_ps(s, length)));
	}
	__m256 si = _mm256_mul_ps(wi, s), sj = _mm256_mul_ps(wj, s);
	xi = _mm256_sub_ps(xi, _mm256_mul_ps(si, dx));
	yi = _mm256_sub_ps(yi, _mm256_mul_ps(si, dy));
	zi = _mm256_sub_ps(zi, _mm256_mul_ps(si, dz));
	xj = _mm256_add_ps(xj, _mm256_mul_ps(sj, dx));
	yj = _mm256_add_ps(yj, _mm256_mul_ps(sj, dy));
	zj = _mm256_add_ps(zj, _mm256_mul_ps(sj, dz));
	if (count == 8) {
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

void plait_project_distance_avx2(plait_distance_block *block, plait_point *points, int begin, int end,
                                 float inverse_h_squared)
{
	const __m256 ih2 = _mm256_set1_ps(inverse_h_squared);
	int c = begin;
	if (block->compliant_count == 0) {
		for (; c + 8 <= end; c += 8) {
			project8(block, points, c, 8, ih2, true);
		}
		if (c < end) {
			project8(block, points, c, end - c, ih2, true);
		}
	} else {
		for (; c + 8 <= end; c += 8) {
			project8(block, points, c, 8, ih2, false);
		}
		if (c < end) {
			project8(block, points, c, end - c, ih2, false);
		}
	}
	/* Clean upper halves before returning to code built for SSE: the compiler leaves them
	 * dirty when the remainder is a tail call, and SSE instructions after that carry a false
	 * dependency on them (the dihedral bend kernel, SSE, ran twice as slow). */
	_mm256_zeroupper();
}
#endif
