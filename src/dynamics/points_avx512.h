/* Moving points and vectors between memory and AVX-512 registers, sixteen at a time: points
 * (16 bytes each: x, y, z, w) with a 4x4 transpose in each 128-bit block, vec3 arrays by
 * two-source permutes. Shared by the AVX-512 kernels (the distance kernel addresses its points
 * by byte offset and gathers them itself); include only from files compiled with -mavx512f. */
#ifndef PLAIT_DYNAMICS_POINTS_AVX512_H
#define PLAIT_DYNAMICS_POINTS_AVX512_H

#include <immintrin.h>

#include "dynamics/sim.h"

/* Four registers of four points each (block b of r[m]: a point's x, y, z, w) into a register
 * per coordinate, lane 4 b + m holding block b of r[m]: a 4x4 transpose in each 128-bit block. */
static inline void transpose_points16(const __m512 r[4], __m512 *x, __m512 *y, __m512 *z, __m512 *w)
{
	__m512 t0 = _mm512_unpacklo_ps(r[0], r[1]), t1 = _mm512_unpacklo_ps(r[2], r[3]);
	__m512 t2 = _mm512_unpackhi_ps(r[0], r[1]), t3 = _mm512_unpackhi_ps(r[2], r[3]);
	*x = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	*y = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	*z = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	*w = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* Its inverse (a 4x4 transpose is its own). */
static inline void untranspose_points16(__m512 x, __m512 y, __m512 z, __m512 w, __m512 r[4])
{
	__m512 t0 = _mm512_unpacklo_ps(x, y), t1 = _mm512_unpacklo_ps(z, w);
	__m512 t2 = _mm512_unpackhi_ps(x, y), t3 = _mm512_unpackhi_ps(z, w);
	r[0] = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	r[1] = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	r[2] = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	r[3] = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* Points index[0..16) into a register per coordinate, lane k holding point index[k]. */
static inline void gather16(const plait_point *points, const int *index, __m512 *x, __m512 *y, __m512 *z,
                            __m512 *w)
{
	__m512 r[4];
	for (int m = 0; m < 4; ++m) {
		__m512 v = _mm512_castps128_ps512(_mm_load_ps(&points[index[m]].x.x));
		v = _mm512_insertf32x4(v, _mm_load_ps(&points[index[m + 4]].x.x), 1);
		v = _mm512_insertf32x4(v, _mm_load_ps(&points[index[m + 8]].x.x), 2);
		r[m] = _mm512_insertf32x4(v, _mm_load_ps(&points[index[m + 12]].x.x), 3);
	}
	transpose_points16(r, x, y, z, w);
}

/* The inverse of gather16 (a 4x4 transpose is its own inverse), storing the first `count`
 * lanes only (lanes past a range's end repeat lane 0's point, which must not be written back
 * over it). */
static inline void scatter16(plait_point *points, const int *index, int count, __m512 x, __m512 y, __m512 z,
                             __m512 w)
{
	__m512 r[4];
	untranspose_points16(x, y, z, w, r);
	if (count == 16) {
		for (int m = 0; m < 4; ++m) {
			_mm_store_ps(&points[index[m]].x.x, _mm512_castps512_ps128(r[m]));
			_mm_store_ps(&points[index[m + 4]].x.x, _mm512_extractf32x4_ps(r[m], 1));
			_mm_store_ps(&points[index[m + 8]].x.x, _mm512_extractf32x4_ps(r[m], 2));
			_mm_store_ps(&points[index[m + 12]].x.x, _mm512_extractf32x4_ps(r[m], 3));
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
		_mm_store_ps(&points[index[k]].x.x, _mm_load_ps(&lanes[k].x.x));
	}
}

/* Points first..first + 16 (consecutive) into a register per coordinate, lane k holding point
 * first + k, as gather16 gives them: four full-width loads and gather16's transposition, which
 * leaves lane 4 b + m holding point 4 m + b, then a permute back (the permutation is its own
 * inverse). Fewer shuffles than gather16's inserts: on Zen 4 a 512-bit shuffle takes two of
 * the processor's shuffle slots. */
#define POINT_LANES _mm512_setr_epi32(0, 4, 8, 12, 1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15)

static inline void load_points16(const plait_point *points, int first, __m512 *x, __m512 *y, __m512 *z,
                                 __m512 *w)
{
	const float *f = &points[first].x.x;
	__m512 r[4] = {_mm512_loadu_ps(f), _mm512_loadu_ps(f + 16), _mm512_loadu_ps(f + 32),
	               _mm512_loadu_ps(f + 48)};
	transpose_points16(r, x, y, z, w);
	const __m512i lanes = POINT_LANES;
	*x = _mm512_permutexvar_ps(lanes, *x);
	*y = _mm512_permutexvar_ps(lanes, *y);
	*z = _mm512_permutexvar_ps(lanes, *z);
	*w = _mm512_permutexvar_ps(lanes, *w);
}

/* The inverse of load_points16. */
static inline void store_points16(plait_point *points, int first, __m512 x, __m512 y, __m512 z, __m512 w)
{
	const __m512i lanes = POINT_LANES;
	__m512 r[4];
	untranspose_points16(_mm512_permutexvar_ps(lanes, x), _mm512_permutexvar_ps(lanes, y),
	                     _mm512_permutexvar_ps(lanes, z), _mm512_permutexvar_ps(lanes, w), r);
	float *f = &points[first].x.x;
	for (int m = 0; m < 4; ++m) {
		_mm512_storeu_ps(f + 16 * m, r[m]);
	}
}

/* Sixteen vec3 (48 floats) into a register per coordinate: coordinate k of vector j is float
 * 3 j + k; the first 32 floats are picked from a and b, the rest from c. */
static inline void load_vec3x16(const vec3 *from, __m512 *x, __m512 *y, __m512 *z)
{
	const float *f = &from->x;
	__m512 a = _mm512_loadu_ps(f), b = _mm512_loadu_ps(f + 16), c = _mm512_loadu_ps(f + 32);
	const __m512i ab_x = _mm512_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21, 24, 27, 30, 0, 0, 0, 0, 0);
	const __m512i ab_y = _mm512_setr_epi32(1, 4, 7, 10, 13, 16, 19, 22, 25, 28, 31, 0, 0, 0, 0, 0);
	const __m512i ab_z = _mm512_setr_epi32(2, 5, 8, 11, 14, 17, 20, 23, 26, 29, 0, 0, 0, 0, 0, 0);
	const __m512i c_x = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 17, 20, 23, 26, 29);
	const __m512i c_y = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 18, 21, 24, 27, 30);
	const __m512i c_z = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 16, 19, 22, 25, 28, 31);
	*x = _mm512_permutex2var_ps(_mm512_permutex2var_ps(a, ab_x, b), c_x, c);
	*y = _mm512_permutex2var_ps(_mm512_permutex2var_ps(a, ab_y, b), c_y, c);
	*z = _mm512_permutex2var_ps(_mm512_permutex2var_ps(a, ab_z, b), c_z, c);
}

/* The inverse: float m of the 48 is coordinate m % 3 of vector m / 3. Each output register
 * picks from two coordinates first (indices 16 and up: the second), then the third. */
static inline void store_vec3x16(vec3 *to, __m512 x, __m512 y, __m512 z)
{
	float *f = &to->x;
	/* Floats 0-15: x0 y0 z0 x1 y1 z1 ... x5 (x and y from xy, z after). */
	const __m512i a_xy = _mm512_setr_epi32(0, 16, 0, 1, 17, 0, 2, 18, 0, 3, 19, 0, 4, 20, 0, 5);
	const __m512i a_z = _mm512_setr_epi32(0, 1, 16, 3, 4, 17, 6, 7, 18, 9, 10, 19, 12, 13, 20, 15);
	/* Floats 16-31: y5 z5 x6 y6 z6 ... x10 y10. */
	const __m512i b_xy = _mm512_setr_epi32(21, 0, 6, 22, 0, 7, 23, 0, 8, 24, 0, 9, 25, 0, 10, 26);
	const __m512i b_z = _mm512_setr_epi32(0, 21, 2, 3, 22, 5, 6, 23, 8, 9, 24, 11, 12, 25, 14, 15);
	/* Floats 32-47: z10 x11 y11 z11 ... x15 y15 z15. */
	const __m512i c_xy = _mm512_setr_epi32(0, 11, 27, 0, 12, 28, 0, 13, 29, 0, 14, 30, 0, 15, 31, 0);
	const __m512i c_z = _mm512_setr_epi32(26, 1, 2, 27, 4, 5, 28, 7, 8, 29, 10, 11, 30, 13, 14, 31);
	_mm512_storeu_ps(f, _mm512_permutex2var_ps(_mm512_permutex2var_ps(x, a_xy, y), a_z, z));
	_mm512_storeu_ps(f + 16, _mm512_permutex2var_ps(_mm512_permutex2var_ps(x, b_xy, y), b_z, z));
	_mm512_storeu_ps(f + 32, _mm512_permutex2var_ps(_mm512_permutex2var_ps(x, c_xy, y), c_z, z));
}

/* Sixteen consecutive points of the columns (solver.c, "Columns") into a register per
 * coordinate, and their positions back (w does not change in a frame). */
static inline void load_columns16(const plait_columns *columns, int first, __m512 *x, __m512 *y, __m512 *z,
                                  __m512 *w)
{
	*x = _mm512_loadu_ps(columns->x + first);
	*y = _mm512_loadu_ps(columns->y + first);
	*z = _mm512_loadu_ps(columns->z + first);
	*w = _mm512_loadu_ps(columns->w + first);
}

static inline void store_columns16(const plait_columns *columns, int first, __m512 x, __m512 y, __m512 z)
{
	_mm512_storeu_ps(columns->x + first, x);
	_mm512_storeu_ps(columns->y + first, y);
	_mm512_storeu_ps(columns->z + first, z);
}

#endif
