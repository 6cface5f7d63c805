/* The dihedral bend kernel in AVX2, 8 hinges at a time: project_bend_batch's arithmetic
 * (constraints.c) in the same order, so both give the same bits. Compiled with -mavx2, never
 * with FMA contraction; only called when the processor has AVX2. */
#include "dynamics/bend_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

#include "dynamics/points_avx2.h"

static inline __m256 neg(__m256 v)
{
	return _mm256_sub_ps(_mm256_set1_ps(-0.0f), v); /* exactly -v */
}

static inline __m256 select(__m256 mask, __m256 when_true, __m256 when_false)
{
	return _mm256_blendv_ps(when_false, when_true, mask);
}

static inline __m256 dot(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz)
{
	return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)), _mm256_mul_ps(az, bz));
}

/* plait_atan2f (core/math.h), lane by lane. */
static inline __m256 atan2_8(__m256 y, __m256 x)
{
	const __m256 zero = _mm256_setzero_ps(), sign = _mm256_set1_ps(-0.0f);
	__m256 ax = _mm256_andnot_ps(sign, x), ay = _mm256_andnot_ps(sign, y);
	__m256 x_wider = _mm256_cmp_ps(ax, ay, _CMP_GT_OQ);
	__m256 high = select(x_wider, ax, ay), low = select(x_wider, ay, ax);
	__m256 a = _mm256_div_ps(low, high), s = _mm256_mul_ps(a, a);
	__m256 p = _mm256_mul_ps(s, _mm256_set1_ps(-0.01172120f));
	p = _mm256_mul_ps(s, _mm256_add_ps(_mm256_set1_ps(0.05265332f), p));
	p = _mm256_mul_ps(s, _mm256_add_ps(_mm256_set1_ps(-0.11643287f), p));
	p = _mm256_mul_ps(s, _mm256_add_ps(_mm256_set1_ps(0.19354346f), p));
	p = _mm256_mul_ps(s, _mm256_add_ps(_mm256_set1_ps(-0.33262347f), p));
	__m256 r = _mm256_mul_ps(a, _mm256_add_ps(_mm256_set1_ps(0.99997726f), p));
	r = select(_mm256_cmp_ps(ay, ax, _CMP_GT_OQ), _mm256_sub_ps(_mm256_set1_ps(1.57079632679489662f), r), r);
	r = select(_mm256_cmp_ps(x, zero, _CMP_LT_OQ), _mm256_sub_ps(_mm256_set1_ps(3.14159265358979324f), r), r);
	r = select(_mm256_cmp_ps(y, zero, _CMP_LT_OQ), neg(r), r);
	return select(_mm256_cmp_ps(high, zero, _CMP_EQ_OQ), zero, r);
}

/* Hinges [c, c + count), count <= 8; lanes past count repeat hinge c with zero inverse masses
 * and are neither read from the block's arrays nor written back. */
static inline void bend8(plait_bend_block *block, plait_point *points, int c, int count, __m256 ih2)
{
	const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
	__m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(count), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
	__m256 lane_mask = _mm256_castsi256_ps(lanes);
	int index[4][8];
	for (int lane = 0; lane < 8; ++lane) {
		const int *quad = block->quad[c + (lane < count ? lane : 0)];
		for (int k = 0; k < 4; ++k) {
			index[k][lane] = quad[k];
		}
	}
	__m256 px[4], py[4], pz[4], w[4], wq[4];
	for (int k = 0; k < 4; ++k) {
		gather8(points, index[k], &px[k], &py[k], &pz[k], &w[k]);
		wq[k] = _mm256_and_ps(w[k], lane_mask);
	}
	__m256 rest = _mm256_maskload_ps(block->rest_angle + c, lanes);
	__m256 compliance = _mm256_maskload_ps(block->compliance + c, lanes);
	__m256 lambda = _mm256_maskload_ps(block->lambda + c, lanes);

	__m256 ex = _mm256_sub_ps(px[1], px[0]), ey = _mm256_sub_ps(py[1], py[0]),
	       ez = _mm256_sub_ps(pz[1], pz[0]);
	__m256 ax = _mm256_sub_ps(px[2], px[0]), ay = _mm256_sub_ps(py[2], py[0]),
	       az = _mm256_sub_ps(pz[2], pz[0]);
	__m256 bx = _mm256_sub_ps(px[3], px[1]), by = _mm256_sub_ps(py[3], py[1]),
	       bz = _mm256_sub_ps(pz[3], pz[1]);
	__m256 nax = _mm256_sub_ps(_mm256_mul_ps(ey, az), _mm256_mul_ps(ez, ay));
	__m256 nay = _mm256_sub_ps(_mm256_mul_ps(ez, ax), _mm256_mul_ps(ex, az));
	__m256 naz = _mm256_sub_ps(_mm256_mul_ps(ex, ay), _mm256_mul_ps(ey, ax));
	__m256 nbx = neg(_mm256_sub_ps(_mm256_mul_ps(ey, bz), _mm256_mul_ps(ez, by)));
	__m256 nby = neg(_mm256_sub_ps(_mm256_mul_ps(ez, bx), _mm256_mul_ps(ex, bz)));
	__m256 nbz = neg(_mm256_sub_ps(_mm256_mul_ps(ex, by), _mm256_mul_ps(ey, bx)));
	__m256 e2 = dot(ex, ey, ez, ex, ey, ez);
	__m256 na2 = dot(nax, nay, naz, nax, nay, naz), nb2 = dot(nbx, nby, nbz, nbx, nby, nbz);
	__m256 valid = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(e2, _mm256_set1_ps(1e-24f), _CMP_GT_OQ),
	                                           _mm256_cmp_ps(na2, _mm256_set1_ps(1e-30f), _CMP_GT_OQ)),
	                             _mm256_cmp_ps(nb2, _mm256_set1_ps(1e-30f), _CMP_GT_OQ));
	e2 = select(valid, e2, one);
	na2 = select(valid, na2, one);
	nb2 = select(valid, nb2, one);
	__m256 el = _mm256_sqrt_ps(e2);
	__m256 cx = _mm256_sub_ps(_mm256_mul_ps(nay, nbz), _mm256_mul_ps(naz, nby));
	__m256 cy = _mm256_sub_ps(_mm256_mul_ps(naz, nbx), _mm256_mul_ps(nax, nbz));
	__m256 cz = _mm256_sub_ps(_mm256_mul_ps(nax, nby), _mm256_mul_ps(nay, nbx));
	__m256 sine = _mm256_div_ps(dot(cx, cy, cz, ex, ey, ez), el);
	__m256 cosine = dot(nax, nay, naz, nbx, nby, nbz);
	__m256 C = _mm256_sub_ps(atan2_8(sine, cosine), rest);
	const __m256 pi = _mm256_set1_ps(PLAIT_PI), two_pi = _mm256_set1_ps(2.0f * PLAIT_PI);
	C = select(_mm256_cmp_ps(C, pi, _CMP_GT_OQ), _mm256_sub_ps(C, two_pi), C);
	C = select(_mm256_cmp_ps(C, neg(pi), _CMP_LT_OQ), _mm256_add_ps(C, two_pi), C);
	__m256 fa = _mm256_div_ps(neg(el), na2), fb = _mm256_div_ps(neg(el), nb2);
	__m256 g2x = _mm256_mul_ps(nax, fa), g2y = _mm256_mul_ps(nay, fa), g2z = _mm256_mul_ps(naz, fa);
	__m256 g3x = _mm256_mul_ps(nbx, fb), g3y = _mm256_mul_ps(nby, fb), g3z = _mm256_mul_ps(nbz, fb);
	__m256 a2 = _mm256_div_ps(dot(ax, ay, az, ex, ey, ez), e2);
	__m256 dx3 = _mm256_sub_ps(px[3], px[0]), dy3 = _mm256_sub_ps(py[3], py[0]),
	       dz3 = _mm256_sub_ps(pz[3], pz[0]);
	__m256 a3 = _mm256_div_ps(dot(dx3, dy3, dz3, ex, ey, ez), e2);
	__m256 a2m = _mm256_sub_ps(a2, one), a3m = _mm256_sub_ps(a3, one), na2c = neg(a2), na3c = neg(a3);
	__m256 gx[4], gy[4], gz[4];
	gx[0] = _mm256_add_ps(_mm256_mul_ps(g2x, a2m), _mm256_mul_ps(g3x, a3m));
	gy[0] = _mm256_add_ps(_mm256_mul_ps(g2y, a2m), _mm256_mul_ps(g3y, a3m));
	gz[0] = _mm256_add_ps(_mm256_mul_ps(g2z, a2m), _mm256_mul_ps(g3z, a3m));
	gx[1] = _mm256_add_ps(_mm256_mul_ps(g2x, na2c), _mm256_mul_ps(g3x, na3c));
	gy[1] = _mm256_add_ps(_mm256_mul_ps(g2y, na2c), _mm256_mul_ps(g3y, na3c));
	gz[1] = _mm256_add_ps(_mm256_mul_ps(g2z, na2c), _mm256_mul_ps(g3z, na3c));
	gx[2] = g2x;
	gy[2] = g2y;
	gz[2] = g2z;
	gx[3] = g3x;
	gy[3] = g3y;
	gz[3] = g3z;
	__m256 denominator = zero;
	for (int k = 0; k < 4; ++k) {
		denominator =
		    _mm256_add_ps(denominator, _mm256_mul_ps(wq[k], dot(gx[k], gy[k], gz[k], gx[k], gy[k], gz[k])));
	}
	__m256 alpha_tilde = _mm256_mul_ps(compliance, ih2);
	denominator = _mm256_add_ps(denominator, alpha_tilde);
	__m256 active = _mm256_and_ps(valid, _mm256_cmp_ps(denominator, _mm256_set1_ps(1e-30f), _CMP_GT_OQ));
	denominator = select(active, denominator, one);
	__m256 active_one = _mm256_and_ps(active, one); /* (float)active */
	__m256 dlambda = _mm256_div_ps(
	    _mm256_mul_ps(active_one, _mm256_sub_ps(neg(C), _mm256_mul_ps(alpha_tilde, lambda))), denominator);
	_mm256_maskstore_ps(block->lambda + c, lanes, _mm256_add_ps(lambda, dlambda));
	for (int k = 0; k < 4; ++k) {
		__m256 s = _mm256_mul_ps(wq[k], dlambda);
		px[k] = _mm256_add_ps(px[k], _mm256_mul_ps(s, gx[k]));
		py[k] = _mm256_add_ps(py[k], _mm256_mul_ps(s, gy[k]));
		pz[k] = _mm256_add_ps(pz[k], _mm256_mul_ps(s, gz[k]));
	}
	for (int k = 0; k < 4; ++k) {
		scatter8(points, index[k], count, px[k], py[k], pz[k], w[k]);
	}
}

void plait_project_bend_avx2(plait_bend_block *block, plait_point *points, int begin, int end,
                             float inverse_h_squared)
{
	const __m256 ih2 = _mm256_set1_ps(inverse_h_squared);
	int c = begin;
	for (; c + 8 <= end; c += 8) {
		bend8(block, points, c, 8, ih2);
	}
	if (c < end) {
		bend8(block, points, c, end - c, ih2);
	}
	_mm256_zeroupper(); /* see distance_avx2.c */
}
#endif
