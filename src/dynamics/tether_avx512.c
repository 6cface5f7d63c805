/* Rows of two tethers (a particle held to two pins, tether.c) in AVX-512, sixteen rows at a
 * time: tether_avx2.c's kernel, lane for lane the same operations in the same order (the same
 * bits), with masks for its selects. Half the instructions a row of the AVX2 copy; the square
 * roots and divisions cost the same a row (Zen 4 runs 512-bit ones at half rate). Compiled with
 * -mavx512f (never with FMA contraction); only called when the processor has AVX-512F. */
#include "dynamics/tether_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>

#include "dynamics/points_avx512.h"

#include <stdbool.h>

typedef struct lanes3 {
	__m512 x, y, z;
} lanes3;

static inline lanes3 sub3(lanes3 a, lanes3 b)
{
	return (lanes3){_mm512_sub_ps(a.x, b.x), _mm512_sub_ps(a.y, b.y), _mm512_sub_ps(a.z, b.z)};
}

/* a + s b, as v3_mul_add. */
static inline lanes3 mul_add3(lanes3 a, __m512 s, lanes3 b)
{
	return (lanes3){_mm512_add_ps(a.x, _mm512_mul_ps(s, b.x)), _mm512_add_ps(a.y, _mm512_mul_ps(s, b.y)),
	                _mm512_add_ps(a.z, _mm512_mul_ps(s, b.z))};
}

/* a . b, as v3_dot: (x x + y y) + z z. */
static inline __m512 dot3(lanes3 a, lanes3 b)
{
	return _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(a.x, b.x), _mm512_mul_ps(a.y, b.y)),
	                     _mm512_mul_ps(a.z, b.z));
}

/* condition ? a : b, lane by lane. */
static inline lanes3 select3(__mmask16 condition, lanes3 a, lanes3 b)
{
	return (lanes3){_mm512_mask_blend_ps(condition, b.x, a.x), _mm512_mask_blend_ps(condition, b.y, a.y),
	                _mm512_mask_blend_ps(condition, b.z, a.z)};
}

static inline __m512 select1(__mmask16 condition, __m512 a, __m512 b)
{
	return _mm512_mask_blend_ps(condition, b, a);
}

/* -a by its sign bit (a float xor is AVX-512DQ; this is AVX-512F). */
static inline __m512 negate(__m512 a, __m512 negative_zero)
{
	return _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(a), _mm512_castps_si512(negative_zero)));
}

static inline lanes3 broadcast3(vec3 v)
{
	return (lanes3){_mm512_set1_ps(v.x), _mm512_set1_ps(v.y), _mm512_set1_ps(v.z)};
}

/* within_reach in tether.c: |q - anchor|^2 <= (length (1 + tolerance))^2. */
static inline __mmask16 within_reach16(lanes3 q, lanes3 anchor, __m512 length, __m512 tolerance)
{
	lanes3 d = sub3(q, anchor);
	__m512 reach = _mm512_mul_ps(length, tolerance);
	return _mm512_cmp_ps_mask(dot3(d, d), _mm512_mul_ps(reach, reach), _CMP_LE_OQ);
}

/* Rows whose sixteen particles are consecutive (a cloth's rows mostly are: tether.c sorts them
 * by particle) load and store their points whole (load_points16), not by a gather. */
static inline bool consecutive16(const int *particle)
{
	__m512i expect =
	    _mm512_add_epi32(_mm512_set1_epi32(particle[0]),
	                     _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
	return _mm512_cmpneq_epi32_mask(_mm512_loadu_si512(particle), expect) == 0;
}

/* Sixteen rows' points from the point array or (columns not NULL) the columns: whole where
 * the rows' particles are consecutive, else one by one. */
static inline __attribute__((always_inline)) void load_rows(const plait_point *points,
                                                            const plait_columns *columns, bool run, int first,
                                                            const int *index, __m512 *x, __m512 *y, __m512 *z,
                                                            __m512 *w)
{
	if (columns == NULL) {
		if (run) {
			load_points16(points, first, x, y, z, w);
		} else {
			gather16(points, index, x, y, z, w);
		}
		return;
	}
	if (run) {
		load_columns16(columns, first, x, y, z, w);
		return;
	}
	__m512i lanes = _mm512_loadu_si512((const void *)index);
	*x = _mm512_i32gather_ps(lanes, columns->x, 4);
	*y = _mm512_i32gather_ps(lanes, columns->y, 4);
	*z = _mm512_i32gather_ps(lanes, columns->z, 4);
	*w = _mm512_i32gather_ps(lanes, columns->w, 4);
}

/* The inverse of load_rows for the first `count` rows (a run has all sixteen); w is not
 * written to the columns, where it does not change. */
static inline __attribute__((always_inline)) void store_rows(plait_point *points,
                                                             const plait_columns *columns, bool run,
                                                             int first, const int *index, int count, __m512 x,
                                                             __m512 y, __m512 z, __m512 w)
{
	if (columns == NULL) {
		if (run) {
			store_points16(points, first, x, y, z, w);
		} else {
			scatter16(points, index, count, x, y, z, w);
		}
		return;
	}
	if (run) {
		store_columns16(columns, first, x, y, z);
		return;
	}
	_Alignas(64) float lx[16], ly[16], lz[16];
	_mm512_store_ps(lx, x);
	_mm512_store_ps(ly, y);
	_mm512_store_ps(lz, z);
	for (int k = 0; k < count; ++k) {
		plait_column_set(columns, index[k], v3(lx[k], ly[k], lz[k]));
	}
}

static inline __attribute__((always_inline)) int
tether_rows(plait_point *points, const plait_columns *columns, const int *particle, const float *length0,
            const float *length1, float stiffness, vec3 anchor0, vec3 anchor1, int count, float tolerance,
            int *unfound)
{
	const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f), half = _mm512_set1_ps(0.5f);
	const __m512 tiny = _mm512_set1_ps(1e-12f), negative_zero = _mm512_set1_ps(-0.0f);
	const __m512 reach_scale = _mm512_set1_ps(1.0f + tolerance), t = _mm512_set1_ps(stiffness);
	const lanes3 a0 = broadcast3(anchor0), a1 = broadcast3(anchor1);
	/* As in tether_avx2.c: the axis's inverse square once. */
	const lanes3 axis01 = sub3(a1, a0);
	const __m512 axis_sq = dot3(axis01, axis01);
	const __mmask16 axis_positive = _mm512_cmp_ps_mask(axis_sq, zero, _CMP_GT_OQ);
	const __m512 inverse_axis_sq = _mm512_div_ps(one, select1(axis_positive, axis_sq, one));
	int unfound_count = 0;
	for (int b = 0; b < count; b += 16) {
		int n = count - b < 16 ? count - b : 16;
		__mmask16 lanes = (__mmask16)((1u << n) - 1u);
		bool run = n == 16 && consecutive16(particle + b);
		int index[16];
		lanes3 p;
		__m512 w, l0, l1;
		if (!run) {
			for (int k = 0; k < 16; ++k) {
				index[k] = particle[b + (k < n ? k : 0)];
			}
		}
		load_rows(points, columns, run, particle[b], index, &p.x, &p.y, &p.z, &w);
		l0 = _mm512_maskz_loadu_ps(lanes, length0 + b);
		l1 = _mm512_maskz_loadu_ps(lanes, length1 + b);
		lanes3 d0 = sub3(p, a0), d1 = sub3(p, a1);
		__m512 d0_sq = dot3(d0, d0), d1_sq = dot3(d1, d1);
		/* find_taut: either tether longer than its length, and the particle free. */
		__mmask16 taut = (__mmask16)((_mm512_cmp_ps_mask(d0_sq, _mm512_mul_ps(l0, l0), _CMP_GT_OQ) |
		                              _mm512_cmp_ps_mask(d1_sq, _mm512_mul_ps(l1, l1), _CMP_GT_OQ)) &
		                             _mm512_cmp_ps_mask(w, zero, _CMP_NEQ_UQ) & lanes);
		if (taut == 0) {
			continue;
		}
		/* solve_taut, lane by lane. */
		__m512 r0 = _mm512_sqrt_ps(d0_sq), r1 = _mm512_sqrt_ps(d1_sq);
		__m512 e0 = _mm512_sub_ps(r0, l0), e1 = _mm512_sub_ps(r1, l1);
		__mmask16 first_worst =
		    (__mmask16)(_mm512_cmp_ps_mask(e0, zero, _CMP_GT_OQ) & _mm512_cmp_ps_mask(e0, e1, _CMP_GE_OQ));
		__mmask16 none =
		    (__mmask16)(_mm512_cmp_ps_mask(e0, zero, _CMP_LE_OQ) & _mm512_cmp_ps_mask(e1, zero, _CMP_LE_OQ));
		lanes3 wa = select3(first_worst, a0, a1), oa = select3(first_worst, a1, a0);
		__m512 w_length = select1(first_worst, l0, l1), o_length = select1(first_worst, l1, l0);
		lanes3 d = select3(first_worst, d0, d1);
		lanes3 projected = mul_add3(wa, _mm512_div_ps(w_length, select1(first_worst, r0, r1)), d);
		__mmask16 within = within_reach16(projected, oa, o_length, reach_scale);
		if ((taut & (__mmask16) ~(none | within)) == 0) {
			/* Every taut row ends inside its other tether (tether_avx2.c). */
			lanes3 q = select3(none, p, mul_add3(p, t, sub3(projected, p)));
			q = select3(taut, q, p);
			store_rows(points, columns, run, particle[b], index, n, q.x, q.y, q.z, w);
			continue;
		}
		lanes3 from_o = select3(first_worst, d1, d0);
		__m512 o_distance_sq = select1(first_worst, d1_sq, d0_sq);
		lanes3 onto_o = mul_add3(oa, _mm512_div_ps(o_length, select1(first_worst, r1, r0)), from_o);
		__mmask16 onto_o_fits =
		    (__mmask16)(_mm512_cmp_ps_mask(o_distance_sq, _mm512_mul_ps(o_length, o_length), _CMP_GT_OQ) &
		                within_reach16(onto_o, wa, w_length, reach_scale));
		lanes3 axis = sub3(oa, wa);
		__m512 along = _mm512_mul_ps(
		    half, _mm512_add_ps(one, _mm512_mul_ps(_mm512_sub_ps(_mm512_mul_ps(w_length, w_length),
		                                                         _mm512_mul_ps(o_length, o_length)),
		                                           inverse_axis_sq)));
		__m512 radius_sq = _mm512_sub_ps(_mm512_mul_ps(w_length, w_length),
		                                 _mm512_mul_ps(_mm512_mul_ps(along, along), axis_sq));
		lanes3 centre = mul_add3(wa, along, axis);
		lanes3 offset = sub3(p, centre);
		__m512 s = _mm512_mul_ps(negate(dot3(offset, axis), negative_zero), inverse_axis_sq);
		lanes3 in_plane = mul_add3(offset, s, axis);
		__m512 in_plane_length = _mm512_sqrt_ps(dot3(in_plane, in_plane));
		__mmask16 long_enough = _mm512_cmp_ps_mask(in_plane_length, tiny, _CMP_GT_OQ);
		__m512 safe_length = select1(long_enough, in_plane_length, one);
		__m512 reach = _mm512_div_ps(_mm512_sqrt_ps(_mm512_max_ps(radius_sq, zero)), safe_length);
		reach = _mm512_maskz_mov_ps(
		    (__mmask16)(_mm512_cmp_ps_mask(radius_sq, zero, _CMP_GT_OQ) & long_enough), reach);
		lanes3 on_circle = mul_add3(centre, reach, in_plane);
		__mmask16 circle_fits =
		    (__mmask16)(axis_positive & within_reach16(on_circle, wa, w_length, reach_scale) &
		                within_reach16(on_circle, oa, o_length, reach_scale));
		lanes3 q = select3(within, projected, select3(onto_o_fits, onto_o, on_circle));
		q = select3(none, p, mul_add3(p, t, sub3(q, p)));
		__mmask16 found = (__mmask16)(none | within | onto_o_fits | circle_fits);
		/* Written back: taut rows found here; the rest unchanged (the exact search reads them). */
		q = select3((__mmask16)(taut & found), q, p);
		unsigned missing = (unsigned)(taut & (__mmask16)~found);
		store_rows(points, columns, run, particle[b], index, n, q.x, q.y, q.z, w);
		while (missing != 0) {
			int lane = __builtin_ctz(missing);
			missing &= missing - 1;
			unfound[unfound_count++] = b + lane;
		}
	}
	return unfound_count;
}

int plait_tether_rows_avx512(plait_point *points, const int *particle, const float *length0,
                             const float *length1, float stiffness, vec3 anchor0, vec3 anchor1, int count,
                             float tolerance, int *unfound)
{
	int missing = tether_rows(points, NULL, particle, length0, length1, stiffness, anchor0, anchor1, count,
	                          tolerance, unfound);
	_mm256_zeroupper();
	return missing;
}

int plait_tether_rows_columns_avx512(const plait_columns *columns, const int *particle, const float *length0,
                                     const float *length1, float stiffness, vec3 anchor0, vec3 anchor1,
                                     int count, float tolerance, int *unfound)
{
	int missing = tether_rows(NULL, columns, particle, length0, length1, stiffness, anchor0, anchor1, count,
	                          tolerance, unfound);
	_mm256_zeroupper();
	return missing;
}
#endif
