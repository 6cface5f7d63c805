/* Small vector and matrix helpers used everywhere in the library. Float, like the particle
 * store: every hot array is float; doubles are used only where precision needs it (CCD). */
#ifndef PLAIT_CORE_MATH_H
#define PLAIT_CORE_MATH_H

#include <math.h>
#include <stdbool.h>

#include <plait/plait.h>

typedef plait_vec3 vec3;

/* Row-major 3x3 matrix: m[row][column]. */
typedef struct mat3 {
	float m[3][3];
} mat3;

#define PLAIT_PI 3.14159265358979323846f

/* For loops written to be vectorised (lane by lane over arrays, selects instead of branches):
 * an AVX2 copy besides the baseline one, picked when the program loads. Lanes do the same
 * IEEE operations either way (no contraction into FMA), so the results are the same bits. */
#if PLAIT_X86_KERNELS && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) &&                   \
    defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) /* ifunc: glibc only */
#define PLAIT_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PLAIT_VECTOR_CLONES
#endif

/* Selects for branch-free lane code (vectorised loops): an int condition, not a bool, keeps
 * gcc's vectoriser from mixing mask widths. */
static inline float plait_select(int condition, float a, float b)
{
	return condition ? a : b;
}

/* Plain comparisons: fmaxf/fminf must honour NaN rules and become library calls in hot loops. */
static inline float plait_maxf(float a, float b)
{
	return a > b ? a : b;
}
static inline float plait_minf(float a, float b)
{
	return a < b ? a : b;
}

/* atan2 within 2e-6 radians, with no library call: a minimax polynomial for atan on [0, 1]
 * and the octant folded back. Deterministic, and several times cheaper than atan2f. */
static inline float plait_atan2f(float y, float x)
{
	float ax = fabsf(x), ay = fabsf(y);
	float high = ax > ay ? ax : ay, low = ax > ay ? ay : ax;
	if (high == 0.0f) {
		return 0.0f;
	}
	float a = low / high, s = a * a;
	float r =
	    a *
	    (0.99997726f +
	     s * (-0.33262347f + s * (0.19354346f + s * (-0.11643287f + s * (0.05265332f + s * -0.01172120f)))));
	r = ay > ax ? 1.57079632679489662f - r : r;
	r = x < 0.0f ? 3.14159265358979324f - r : r;
	return y < 0.0f ? -r : r;
}

static inline vec3 v3(float x, float y, float z)
{
	return (vec3){x, y, z};
}
static inline vec3 v3_add(vec3 a, vec3 b)
{
	return (vec3){a.x + b.x, a.y + b.y, a.z + b.z};
}
static inline vec3 v3_sub(vec3 a, vec3 b)
{
	return (vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}
static inline vec3 v3_scale(vec3 a, float s)
{
	return (vec3){a.x * s, a.y * s, a.z * s};
}
static inline vec3 v3_mul_add(vec3 a, float s, vec3 b)
{
	return (vec3){a.x + s * b.x, a.y + s * b.y, a.z + s * b.z};
}
static inline vec3 v3_neg(vec3 a)
{
	return (vec3){-a.x, -a.y, -a.z};
}
static inline float v3_dot(vec3 a, vec3 b)
{
	return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline vec3 v3_cross(vec3 a, vec3 b)
{
	return (vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline float v3_length_sq(vec3 a)
{
	return v3_dot(a, a);
}
static inline float v3_length(vec3 a)
{
	return sqrtf(v3_dot(a, a));
}
static inline vec3 v3_select(int condition, vec3 a, vec3 b)
{
	return (vec3){condition ? a.x : b.x, condition ? a.y : b.y, condition ? a.z : b.z};
}
static inline vec3 v3_lerp(vec3 a, vec3 b, float t)
{
	return v3_mul_add(a, t, v3_sub(b, a));
}
static inline bool v3_is_finite(vec3 a)
{
	return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}
/* The largest of a vector's coordinates in size (its infinity norm). */
static inline float v3_largest_abs(vec3 a)
{
	return plait_maxf(fabsf(a.x), plait_maxf(fabsf(a.y), fabsf(a.z)));
}

static inline vec3 v3_min(vec3 a, vec3 b)
{
	return (vec3){plait_minf(a.x, b.x), plait_minf(a.y, b.y), plait_minf(a.z, b.z)};
}
static inline vec3 v3_max(vec3 a, vec3 b)
{
	return (vec3){plait_maxf(a.x, b.x), plait_maxf(a.y, b.y), plait_maxf(a.z, b.z)};
}

/* Unit vector, or the zero vector when a is too short to have a direction. */
static inline vec3 v3_normalize(vec3 a)
{
	float length = v3_length(a);
	return length > 1e-30f ? v3_scale(a, 1.0f / length) : (vec3){0.0f, 0.0f, 0.0f};
}

static inline vec3 m3_mul_v3(const mat3 *a, vec3 v)
{
	return (vec3){a->m[0][0] * v.x + a->m[0][1] * v.y + a->m[0][2] * v.z,
	              a->m[1][0] * v.x + a->m[1][1] * v.y + a->m[1][2] * v.z,
	              a->m[2][0] * v.x + a->m[2][1] * v.y + a->m[2][2] * v.z};
}

/* Transpose times vector: the inverse rotation for orthonormal a. */
static inline vec3 m3_tmul_v3(const mat3 *a, vec3 v)
{
	return (vec3){a->m[0][0] * v.x + a->m[1][0] * v.y + a->m[2][0] * v.z,
	              a->m[0][1] * v.x + a->m[1][1] * v.y + a->m[2][1] * v.z,
	              a->m[0][2] * v.x + a->m[1][2] * v.y + a->m[2][2] * v.z};
}

mat3 m3_identity(void);
mat3 m3_mul(const mat3 *a, const mat3 *b);
/* Rotation by degrees about x, then y, then z: R = Rz * Ry * Rx. */
mat3 m3_from_euler_deg(vec3 degrees);

#endif
