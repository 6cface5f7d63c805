/* The distance kernel in AVX2, 8 constraints at a time. Compiled with -mavx2 (and never with
 * FMA contraction); only called when the processor has AVX2. */
#include "dynamics/distance_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

/* Loads the points of one side of 8 constraints (16 bytes each: x, y, z, w) and transposes
 * them into a register per coordinate, lane k holding constraint k. */
static inline void gather8(const plait_point *points, const int *index, __m256 *x, __m256 *y, __m256 *z,
                           __m256 *w)
{
	__m256 r0 = _mm256_castps128_ps256(_mm_load_ps(&points[index[0]].x.x));
	__m256 r1 = _mm256_castps128_ps256(_mm_load_ps(&points[index[1]].x.x));
	__m256 r2 = _mm256_castps128_ps256(_mm_load_ps(&points[index[2]].x.x));
	__m256 r3 = _mm256_castps128_ps256(_mm_load_ps(&points[index[3]].x.x));
	r0 = _mm256_insertf128_ps(r0, _mm_load_ps(&points[index[4]].x.x), 1);
	r1 = _mm256_insertf128_ps(r1, _mm_load_ps(&points[index[5]].x.x), 1);
	r2 = _mm256_insertf128_ps(r2, _mm_load_ps(&points[index[6]].x.x), 1);
	r3 = _mm256_insertf128_ps(r3, _mm_load_ps(&points[index[7]].x.x), 1);
	__m256 t0 = _mm256_unpacklo_ps(r0, r1); /* x0 x1 y0 y1 | x4 x5 y4 y5 */
	__m256 t1 = _mm256_unpacklo_ps(r2, r3); /* x2 x3 y2 y3 | x6 x7 y6 y7 */
	__m256 t2 = _mm256_unpackhi_ps(r0, r1); /* z0 z1 w0 w1 | z4 z5 w4 w5 */
	__m256 t3 = _mm256_unpackhi_ps(r2, r3);
	*x = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	*y = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	*z = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	*w = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* The inverse of gather8 (a 4x4 transpose is its own inverse), storing the first `count`
 * lanes only (lanes past a range's end repeat lane 0's points, which must not be written back
 * over it). */
static inline void scatter8(plait_point *points, const int *index, int count, __m256 x, __m256 y, __m256 z,
                            __m256 w)
{
	__m256 t0 = _mm256_unpacklo_ps(x, y); /* x0 y0 x1 y1 | x4 y4 x5 y5 */
	__m256 t1 = _mm256_unpacklo_ps(z, w); /* z0 w0 z1 w1 | z4 w4 z5 w5 */
	__m256 t2 = _mm256_unpackhi_ps(x, y); /* x2 y2 x3 y3 | x6 y6 x7 y7 */
	__m256 t3 = _mm256_unpackhi_ps(z, w);
	__m256 r[4] = {_mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0)), /* point 0 | point 4 */
	               _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2)),
	               _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0)),
	               _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2))};
	if (count == 8) {
		for (int m = 0; m < 4; ++m) {
			_mm_store_ps(&points[index[m]].x.x, _mm256_castps256_ps128(r[m]));
			_mm_store_ps(&points[index[m + 4]].x.x, _mm256_extractf128_ps(r[m], 1));
		}
		return;
	}
	_Alignas(32) plait_point lanes[8];
	for (int m = 0; m < 4; ++m) {
		_mm_store_ps(&lanes[m].x.x, _mm256_castps256_ps128(r[m]));
		_mm_store_ps(&lanes[m + 4].x.x, _mm256_extractf128_ps(r[m], 1));
	}
	for (int k = 0; k < count; ++k) {
		_mm_store_ps(&points[index[k]].x.x, _mm_load_ps(&lanes[k].x.x));
	}
}

/* Projects constraints [c, c + count), count <= 8. Lanes past count compute on copies of lane
 * 0, are masked out of the block's arrays and are not written back. */
static inline void project8(plait_distance_block *block, plait_point *points, int c, int count, __m256 ih2)
{
	const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
	const __m256 negative_zero = _mm256_set1_ps(-0.0f), tiny = _mm256_set1_ps(1e-12f);
	__m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(count), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
	/* Copied out: the compiler cannot tell that the stores to points leave them alone. */
	const int(*pair)[2] = (const int(*)[2])block->pair + c;
	int index_i[8], index_j[8];
	for (int k = 0; k < 8; ++k) {
		int lane = k < count ? k : 0;
		index_i[k] = pair[lane][0];
		index_j[k] = pair[lane][1];
	}
	__m256 xi, yi, zi, wi, xj, yj, zj, wj;
	gather8(points, index_i, &xi, &yi, &zi, &wi);
	gather8(points, index_j, &xj, &yj, &zj, &wj);
	__m256 dx = _mm256_sub_ps(xj, xi), dy = _mm256_sub_ps(yj, yi), dz = _mm256_sub_ps(zj, zi);
	__m256 length_sq =
	    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
	__m256 length = _mm256_max_ps(_mm256_sqrt_ps(length_sq), tiny);
	__m256 C = _mm256_sub_ps(length, _mm256_maskload_ps(block->rest + c, lanes));
	__m256 alpha = _mm256_blendv_ps(_mm256_maskload_ps(block->compliance_compression + c, lanes),
	                                _mm256_maskload_ps(block->compliance_tension + c, lanes),
	                                _mm256_cmp_ps(C, zero, _CMP_GT_OQ));
	__m256 w_sum = _mm256_add_ps(wi, wj);
	__m256 moving = _mm256_cmp_ps(w_sum, zero, _CMP_GT_OQ);
	__m256 active = _mm256_and_ps(_mm256_cmp_ps(alpha, zero, _CMP_GE_OQ), moving);
	__m256 alpha_tilde = _mm256_mul_ps(_mm256_max_ps(alpha, zero), ih2);
	__m256 denominator = _mm256_mul_ps(_mm256_add_ps(w_sum, alpha_tilde), length);
	denominator = _mm256_blendv_ps(one, denominator, moving);
	__m256 lambda = _mm256_maskload_ps(block->lambda + c, lanes);
	__m256 s = _mm256_div_ps(
	    _mm256_sub_ps(_mm256_sub_ps(negative_zero, C), _mm256_mul_ps(alpha_tilde, lambda)), denominator);
	s = _mm256_and_ps(s, active);
	_mm256_maskstore_ps(block->lambda + c, lanes, _mm256_add_ps(lambda, _mm256_mul_ps(s, length)));
	__m256 si = _mm256_mul_ps(wi, s), sj = _mm256_mul_ps(wj, s);
	xi = _mm256_sub_ps(xi, _mm256_mul_ps(si, dx));
	yi = _mm256_sub_ps(yi, _mm256_mul_ps(si, dy));
	zi = _mm256_sub_ps(zi, _mm256_mul_ps(si, dz));
	xj = _mm256_add_ps(xj, _mm256_mul_ps(sj, dx));
	yj = _mm256_add_ps(yj, _mm256_mul_ps(sj, dy));
	zj = _mm256_add_ps(zj, _mm256_mul_ps(sj, dz));
	scatter8(points, index_i, count, xi, yi, zi, wi);
	scatter8(points, index_j, count, xj, yj, zj, wj);
}

void plait_project_distance_avx2(plait_distance_block *block, plait_point *points, int begin, int end,
                                 float inverse_h_squared)
{
	const __m256 ih2 = _mm256_set1_ps(inverse_h_squared);
	int c = begin;
	for (; c + 8 <= end; c += 8) {
		project8(block, points, c, 8, ih2);
	}
	if (c < end) {
		project8(block, points, c, end - c, ih2);
	}
	/* Clean upper halves before returning to code built for SSE: the compiler leaves them
	 * dirty when the remainder is a tail call, and SSE instructions after that carry a false
	 * dependency on them (the dihedral bend kernel, SSE, ran twice as slow). */
	_mm256_zeroupper();
}
#endif
