/* Four vectors at a time in SSE2 lanes (lane k: the k-th), for loops over independent elements
 * (triangles, collision elements) that gather their vertices by index. Each operation is the
 * one of core/math.h, operation for operation in the same order (no fused multiply-add; min
 * and max return the second operand on ties, as plait_minf and plait_maxf do), so a lane gives
 * the bits the scalar code gives, where the scalar code rounds each float operation to float
 * (FLT_EVAL_METHOD 0, as on x86-64). Only where __SSE2__ is defined (gcc and clang on x86-64;
 * not MSVC, which takes the scalar code). */
#ifndef PLAIT_CORE_LANES_H
#define PLAIT_CORE_LANES_H

#include <float.h>

#include "core/math.h"

#if defined(__SSE2__) && defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD == 0
#include <emmintrin.h>

#define PLAIT_HAVE_LANES 1

typedef struct lanes3 {
	__m128 x, y, z;
} lanes3;

static inline lanes3 lanes3_set1(vec3 a)
{
	return (lanes3){_mm_set1_ps(a.x), _mm_set1_ps(a.y), _mm_set1_ps(a.z)};
}

static inline lanes3 lanes3_add(lanes3 a, lanes3 b)
{
	return (lanes3){_mm_add_ps(a.x, b.x), _mm_add_ps(a.y, b.y), _mm_add_ps(a.z, b.z)};
}

static inline lanes3 lanes3_sub(lanes3 a, lanes3 b)
{
	return (lanes3){_mm_sub_ps(a.x, b.x), _mm_sub_ps(a.y, b.y), _mm_sub_ps(a.z, b.z)};
}

static inline lanes3 lanes3_scale(lanes3 a, __m128 s)
{
	return (lanes3){_mm_mul_ps(a.x, s), _mm_mul_ps(a.y, s), _mm_mul_ps(a.z, s)};
}

/* a + s b, as v3_mul_add. */
static inline lanes3 lanes3_mul_add(lanes3 a, __m128 s, lanes3 b)
{
	return (lanes3){_mm_add_ps(a.x, _mm_mul_ps(s, b.x)), _mm_add_ps(a.y, _mm_mul_ps(s, b.y)),
	                _mm_add_ps(a.z, _mm_mul_ps(s, b.z))};
}

static inline lanes3 lanes3_cross(lanes3 a, lanes3 b)
{
	return (lanes3){_mm_sub_ps(_mm_mul_ps(a.y, b.z), _mm_mul_ps(a.z, b.y)),
	                _mm_sub_ps(_mm_mul_ps(a.z, b.x), _mm_mul_ps(a.x, b.z)),
	                _mm_sub_ps(_mm_mul_ps(a.x, b.y), _mm_mul_ps(a.y, b.x))};
}

static inline __m128 lanes3_dot(lanes3 a, lanes3 b)
{
	return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a.x, b.x), _mm_mul_ps(a.y, b.y)), _mm_mul_ps(a.z, b.z));
}

/* plait_minf and plait_maxf lane by lane: a < b ? a : b, a > b ? a : b. */
static inline lanes3 lanes3_min(lanes3 a, lanes3 b)
{
	return (lanes3){_mm_min_ps(a.x, b.x), _mm_min_ps(a.y, b.y), _mm_min_ps(a.z, b.z)};
}

static inline lanes3 lanes3_max(lanes3 a, lanes3 b)
{
	return (lanes3){_mm_max_ps(a.x, b.x), _mm_max_ps(a.y, b.y), _mm_max_ps(a.z, b.z)};
}

/* Lane k: points[index[k]]. */
static inline lanes3 lanes3_gather(const vec3 *points, const int index[4])
{
	return (lanes3){
	    _mm_setr_ps(points[index[0]].x, points[index[1]].x, points[index[2]].x, points[index[3]].x),
	    _mm_setr_ps(points[index[0]].y, points[index[1]].y, points[index[2]].y, points[index[3]].y),
	    _mm_setr_ps(points[index[0]].z, points[index[1]].z, points[index[2]].z, points[index[3]].z)};
}

/* Lane k: values[index[k]]. */
static inline __m128 lanes_gather(const float *values, const int index[4])
{
	return _mm_setr_ps(values[index[0]], values[index[1]], values[index[2]], values[index[3]]);
}

/* The four lanes out, as vectors. */
static inline void lanes3_store(lanes3 a, vec3 out[4])
{
	_Alignas(16) float x[4], y[4], z[4];
	_mm_store_ps(x, a.x);
	_mm_store_ps(y, a.y);
	_mm_store_ps(z, a.z);
	for (int k = 0; k < 4; ++k) {
		out[k] = v3(x[k], y[k], z[k]);
	}
}
#endif

#endif
