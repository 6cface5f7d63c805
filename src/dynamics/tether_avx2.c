/* Rows of two tethers (a particle held to two pins, tether.c) in AVX2, eight rows at a time,
 * straight from the points and back: the portable path loads the rows into lane arrays, finds
 * the taut ones and packs them before solving (solve_taut in tether.c), and the loads, the
 * packing and the store forwarding between them cost more than the solve. Here a group of
 * eight with no taut row is left after the test; the others are solved whole, in registers,
 * with solve_taut's operations in its order, so a taut row gets the same bits either way and a
 * slack one is written back unchanged. Compiled with -mavx2 (never with FMA contraction); only
 * called when the processor has AVX2. */
#include "dynamics/tether_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

#include "dynamics/points_avx2.h"

typedef struct lanes3 {
	__m256 x, y, z;
} lanes3;

static inline lanes3 sub3(lanes3 a, lanes3 b)
{
	return (lanes3){_mm256_sub_ps(a.x, b.x), _mm256_sub_ps(a.y, b.y), _mm256_sub_ps(a.z, b.z)};
}

/* a + s b, as v3_mul_add. */
static inline lanes3 mul_add3(lanes3 a, __m256 s, lanes3 b)
{
	return (lanes3){_mm256_add_ps(a.x, _mm256_mul_ps(s, b.x)), _mm256_add_ps(a.y, _mm256_mul_ps(s, b.y)),
	                _mm256_add_ps(a.z, _mm256_mul_ps(s, b.z))};
}

/* a . b, as v3_dot: (x x + y y) + z z. */
static inline __m256 dot3(lanes3 a, lanes3 b)
{
	return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a.x, b.x), _mm256_mul_ps(a.y, b.y)),
	                     _mm256_mul_ps(a.z, b.z));
}

/* condition ? a : b, lane by lane. */
static inline lanes3 select3(__m256 condition, lanes3 a, lanes3 b)
{
	return (lanes3){_mm256_blendv_ps(b.x, a.x, condition), _mm256_blendv_ps(b.y, a.y, condition),
	                _mm256_blendv_ps(b.z, a.z, condition)};
}

static inline __m256 select1(__m256 condition, __m256 a, __m256 b)
{
	return _mm256_blendv_ps(b, a, condition);
}

static inline lanes3 broadcast3(vec3 v)
{
	return (lanes3){_mm256_set1_ps(v.x), _mm256_set1_ps(v.y), _mm256_set1_ps(v.z)};
}

/* within_reach in tether.c: |q - anchor|^2 <= (length (1 + tolerance))^2. */
static inline __m256 within_reach8(lanes3 q, lanes3 anchor, __m256 length, __m256 tolerance)
{
	lanes3 d = sub3(q, anchor);
	__m256 reach = _mm256_mul_ps(length, tolerance);
	return _mm256_cmp_ps(dot3(d, d), _mm256_mul_ps(reach, reach), _CMP_LE_OQ);
}

static inline __m256 load_rows(const float *from, int count, __m256i lanes)
{
	return count == 8 ? _mm256_loadu_ps(from) : _mm256_maskload_ps(from, lanes);
}

int plait_tether_rows_avx2(plait_point *points, const int *particle, const float *length0,
                           const float *length1, float stiffness, vec3 anchor0, vec3 anchor1, int count,
                           float tolerance, int *unfound)
{
	const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), half = _mm256_set1_ps(0.5f);
	const __m256 tiny = _mm256_set1_ps(1e-12f), negative_zero = _mm256_set1_ps(-0.0f);
	const __m256 reach_scale = _mm256_set1_ps(1.0f + tolerance), t = _mm256_set1_ps(stiffness);
	const lanes3 a0 = broadcast3(anchor0), a1 = broadcast3(anchor1);
	/* The axis between the pins is a1 - a0 or a0 - a1 in every lane, the same square either way:
	 * its inverse once, not once a group (one division of the nine). */
	const lanes3 axis01 = sub3(a1, a0);
	const __m256 axis_sq = dot3(axis01, axis01);
	const __m256 axis_positive = _mm256_cmp_ps(axis_sq, zero, _CMP_GT_OQ);
	const __m256 inverse_axis_sq = _mm256_div_ps(one, select1(axis_positive, axis_sq, one));
	int unfound_count = 0;
	for (int b = 0; b < count; b += 8) {
		int n = count - b < 8 ? count - b : 8;
		__m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(n), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
		int index[8];
		for (int k = 0; k < 8; ++k) {
			index[k] = particle[b + (k < n ? k : 0)];
		}
		lanes3 p;
		__m256 w;
		gather8(points, index, &p.x, &p.y, &p.z, &w);
		__m256 l0 = load_rows(length0 + b, n, lanes), l1 = load_rows(length1 + b, n, lanes);
		lanes3 d0 = sub3(p, a0), d1 = sub3(p, a1);
		__m256 d0_sq = dot3(d0, d0), d1_sq = dot3(d1, d1);
		/* find_taut: either tether longer than its length, and the particle free. */
		__m256 taut = _mm256_and_ps(_mm256_or_ps(_mm256_cmp_ps(d0_sq, _mm256_mul_ps(l0, l0), _CMP_GT_OQ),
		                                         _mm256_cmp_ps(d1_sq, _mm256_mul_ps(l1, l1), _CMP_GT_OQ)),
		                            _mm256_cmp_ps(w, zero, _CMP_NEQ_UQ));
		taut = _mm256_and_ps(taut, _mm256_castsi256_ps(lanes));
		if (_mm256_movemask_ps(taut) == 0) {
			continue;
		}
		/* solve_taut, lane by lane. */
		__m256 r0 = _mm256_sqrt_ps(d0_sq), r1 = _mm256_sqrt_ps(d1_sq);
		__m256 e0 = _mm256_sub_ps(r0, l0), e1 = _mm256_sub_ps(r1, l1);
		__m256 first_worst =
		    _mm256_and_ps(_mm256_cmp_ps(e0, zero, _CMP_GT_OQ), _mm256_cmp_ps(e0, e1, _CMP_GE_OQ));
		__m256 none = _mm256_and_ps(_mm256_cmp_ps(e0, zero, _CMP_LE_OQ), _mm256_cmp_ps(e1, zero, _CMP_LE_OQ));
		lanes3 wa = select3(first_worst, a0, a1), oa = select3(first_worst, a1, a0);
		__m256 w_length = select1(first_worst, l0, l1), o_length = select1(first_worst, l1, l0);
		lanes3 d = select3(first_worst, d0, d1);
		lanes3 projected = mul_add3(wa, _mm256_div_ps(w_length, select1(first_worst, r0, r1)), d);
		__m256 within = within_reach8(projected, oa, o_length, reach_scale);
		if (_mm256_movemask_ps(_mm256_andnot_ps(_mm256_or_ps(none, within), taut)) == 0) {
			/* Every taut row's worst tether, pulled in, leaves it inside the other one (about
			 * half the groups of a hanging cloth): the other candidates would not be chosen. */
			lanes3 q = select3(none, p, mul_add3(p, t, sub3(projected, p)));
			q = select3(taut, q, p);
			scatter8(points, index, n, q.x, q.y, q.z, w);
			continue;
		}
		lanes3 from_o = select3(first_worst, d1, d0);
		__m256 o_distance_sq = select1(first_worst, d1_sq, d0_sq);
		lanes3 onto_o = mul_add3(oa, _mm256_div_ps(o_length, select1(first_worst, r1, r0)), from_o);
		__m256 onto_o_fits =
		    _mm256_and_ps(_mm256_cmp_ps(o_distance_sq, _mm256_mul_ps(o_length, o_length), _CMP_GT_OQ),
		                  within_reach8(onto_o, wa, w_length, reach_scale));
		lanes3 axis = sub3(oa, wa);
		__m256 along = _mm256_mul_ps(
		    half, _mm256_add_ps(one, _mm256_mul_ps(_mm256_sub_ps(_mm256_mul_ps(w_length, w_length),
		                                                         _mm256_mul_ps(o_length, o_length)),
		                                           inverse_axis_sq)));
		__m256 radius_sq = _mm256_sub_ps(_mm256_mul_ps(w_length, w_length),
		                                 _mm256_mul_ps(_mm256_mul_ps(along, along), axis_sq));
		lanes3 centre = mul_add3(wa, along, axis);
		lanes3 offset = sub3(p, centre);
		__m256 s = _mm256_mul_ps(_mm256_xor_ps(dot3(offset, axis), negative_zero), inverse_axis_sq);
		lanes3 in_plane = mul_add3(offset, s, axis);
		__m256 in_plane_length = _mm256_sqrt_ps(dot3(in_plane, in_plane));
		__m256 long_enough = _mm256_cmp_ps(in_plane_length, tiny, _CMP_GT_OQ);
		__m256 safe_length = select1(long_enough, in_plane_length, one);
		__m256 reach = _mm256_div_ps(_mm256_sqrt_ps(_mm256_max_ps(radius_sq, zero)), safe_length);
		reach = _mm256_and_ps(reach, _mm256_and_ps(_mm256_cmp_ps(radius_sq, zero, _CMP_GT_OQ), long_enough));
		lanes3 on_circle = mul_add3(centre, reach, in_plane);
		__m256 circle_fits =
		    _mm256_and_ps(axis_positive, _mm256_and_ps(within_reach8(on_circle, wa, w_length, reach_scale),
		                                               within_reach8(on_circle, oa, o_length, reach_scale)));
		lanes3 q = select3(within, projected, select3(onto_o_fits, onto_o, on_circle));
		q = select3(none, p, mul_add3(p, t, sub3(q, p)));
		__m256 found = _mm256_or_ps(_mm256_or_ps(none, within), _mm256_or_ps(onto_o_fits, circle_fits));
		/* Written back: taut rows found here; the rest unchanged (the exact search reads them). */
		__m256 write = _mm256_and_ps(taut, found);
		q = select3(write, q, p);
		scatter8(points, index, n, q.x, q.y, q.z, w);
		int missing = _mm256_movemask_ps(_mm256_andnot_ps(found, taut));
		while (missing != 0) {
			int lane = __builtin_ctz((unsigned)missing);
			missing &= missing - 1;
			unfound[unfound_count++] = b + lane;
		}
	}
	_mm256_zeroupper();
	return unfound_count;
}
#endif
