/* Moving points between memory and AVX2 registers: 8 points (16 bytes each: x, y, z, w) to a
 * register per coordinate and back, with a 4x4 transpose in each 128-bit half. Shared by the
 * AVX2 kernels; include only from files compiled with -mavx2. */
#ifndef PLAIT_DYNAMICS_POINTS_AVX2_H
#define PLAIT_DYNAMICS_POINTS_AVX2_H

#include <immintrin.h>

#include "dynamics/sim.h"

/* Loads points index[0..8) into a register per coordinate, lane k holding point index[k]. */
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

/* gather8 and scatter8 with the points given by byte offsets (plait_point_offset), offset[k *
 * stride] for lane k: no index to widen and scale, which was a fifth of the distance kernel's
 * instructions. */
static inline const float *point_at(const plait_point *points, uint32_t offset)
{
	return (const float *)((const char *)points + offset);
}

static inline void gather8_at(const plait_point *points, const uint32_t *offset, int stride, __m256 *x,
                              __m256 *y, __m256 *z, __m256 *w)
{
	__m256 r0 = _mm256_castps128_ps256(_mm_load_ps(point_at(points, offset[0 * stride])));
	__m256 r1 = _mm256_castps128_ps256(_mm_load_ps(point_at(points, offset[1 * stride])));
	__m256 r2 = _mm256_castps128_ps256(_mm_load_ps(point_at(points, offset[2 * stride])));
	__m256 r3 = _mm256_castps128_ps256(_mm_load_ps(point_at(points, offset[3 * stride])));
	r0 = _mm256_insertf128_ps(r0, _mm_load_ps(point_at(points, offset[4 * stride])), 1);
	r1 = _mm256_insertf128_ps(r1, _mm_load_ps(point_at(points, offset[5 * stride])), 1);
	r2 = _mm256_insertf128_ps(r2, _mm_load_ps(point_at(points, offset[6 * stride])), 1);
	r3 = _mm256_insertf128_ps(r3, _mm_load_ps(point_at(points, offset[7 * stride])), 1);
	__m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpacklo_ps(r2, r3);
	__m256 t2 = _mm256_unpackhi_ps(r0, r1), t3 = _mm256_unpackhi_ps(r2, r3);
	*x = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	*y = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	*z = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	*w = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

/* All eight lanes stored (a full batch). */
static inline void scatter8_at(plait_point *points, const uint32_t *offset, int stride, __m256 x, __m256 y,
                               __m256 z, __m256 w)
{
	__m256 t0 = _mm256_unpacklo_ps(x, y), t1 = _mm256_unpacklo_ps(z, w);
	__m256 t2 = _mm256_unpackhi_ps(x, y), t3 = _mm256_unpackhi_ps(z, w);
	__m256 r[4] = {_mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0)),
	               _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2)),
	               _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0)),
	               _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2))};
	for (int m = 0; m < 4; ++m) {
		_mm_store_ps((float *)point_at(points, offset[m * stride]), _mm256_castps256_ps128(r[m]));
		_mm_store_ps((float *)point_at(points, offset[(m + 4) * stride]), _mm256_extractf128_ps(r[m], 1));
	}
}

#endif
