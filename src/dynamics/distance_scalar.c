#include "dynamics/distance_kernel.h"

#include <math.h>

/* The reference arithmetic: the vector kernels repeat these operations lane by lane, in this
 * order, so the three give the same bits. A rigid block (no compliance) takes the general
 * formula with alpha = 0 and lambda = 0 in the same operations, without touching the
 * compliance and lambda arrays; `rigid` is a constant in each call below, so the compiler
 * makes two loops. */
static inline __attribute__((always_inline)) void project_range(plait_distance_block *block,
                                                                plait_point *points, int begin, int end,
                                                                float inverse_h_squared, bool rigid)
{
	const int(*pair)[2] = (const int(*)[2])block->pair;
	const float *rest = block->rest, *tension = block->compliance_tension;
	const float *compression = block->compliance_compression;
	float *lambda = block->lambda;
	for (int c = begin; c < end; ++c) {
		plait_point *pi = &points[pair[c][0]], *pj = &points[pair[c][1]];
		float wi = pi->w, wj = pj->w;
		float dx = pj->x.x - pi->x.x, dy = pj->x.y - pi->x.y, dz = pj->x.z - pi->x.z;
		float length = sqrtf(dx * dx + dy * dy + dz * dz);
		length = length > 1e-12f ? length : 1e-12f;
		float C = length - rest[c];
		float w_sum = wi + wj;
		float s;
		if (rigid) {
			float denominator = w_sum > 0.0f ? w_sum * length : 1.0f;
			s = w_sum > 0.0f ? -C / denominator : 0.0f;
		} else {
			float alpha = C > 0.0f ? tension[c] : compression[c];
			bool active = (alpha >= 0.0f) & (w_sum > 0.0f);
			float alpha_tilde = (alpha > 0.0f ? alpha : 0.0f) * inverse_h_squared;
			float denominator = (w_sum + alpha_tilde) * length;
			denominator = w_sum > 0.0f ? denominator : 1.0f;
			s = (-C - alpha_tilde * lambda[c]) / denominator;
			s = active ? s : 0.0f;
			lambda[c] = lambda[c] + s * length;
		}
		float si = wi * s, sj = wj * s;
		pi->x.x = pi->x.x - si * dx;
		pi->x.y = pi->x.y - si * dy;
		pi->x.z = pi->x.z - si * dz;
		pj->x.x = pj->x.x + sj * dx;
		pj->x.y = pj->x.y + sj * dy;
		pj->x.z = pj->x.z + sj * dz;
	}
}

void plait_project_distance_scalar(plait_distance_block *block, plait_point *points, int begin, int end,
                                   float inverse_h_squared)
{
	if (block->compliant_count == 0) {
		project_range(block, points, begin, end, inverse_h_squared, true);
	} else {
		project_range(block, points, begin, end, inverse_h_squared, false);
	}
}

#if PLAIT_X86_KERNELS
bool plait_simd_supported(plait_simd level)
{
	switch (level) {
	case PLAIT_SIMD_AUTO:
	case PLAIT_SIMD_SCALAR:
		return true;
	case PLAIT_SIMD_AVX2:
		return __builtin_cpu_supports("avx2");
	case PLAIT_SIMD_AVX512:
		return __builtin_cpu_supports("avx512f");
	}
	return false;
}
#else
bool plait_simd_supported(plait_simd level)
{
	return level == PLAIT_SIMD_AUTO || level == PLAIT_SIMD_SCALAR;
}
#endif

/* AMD's Zen 4 runs 512-bit shuffles at half the rate of 256-bit ones, and the kernels are
 * bound by the transposes of their gathers and scatters: there AVX2 is the faster
 * (bench/bench_kernels: about 2.1 against 2.6 ns per projection at hang-128). Elsewhere the
 * widest wins. The choice never changes results, only speed. */
plait_simd plait_simd_best(void)
{
#if PLAIT_X86_KERNELS
	bool prefer_avx2 = __builtin_cpu_is("amd") && plait_simd_supported(PLAIT_SIMD_AVX2);
	if (plait_simd_supported(PLAIT_SIMD_AVX512) && !prefer_avx2) {
		return PLAIT_SIMD_AVX512;
	}
#endif
	return plait_simd_supported(PLAIT_SIMD_AVX2) ? PLAIT_SIMD_AVX2 : PLAIT_SIMD_SCALAR;
}

plait_distance_kernel *plait_distance_kernel_for(plait_simd level)
{
	switch (level) {
#if PLAIT_X86_KERNELS
	case PLAIT_SIMD_AVX2:
		return plait_project_distance_avx2;
	case PLAIT_SIMD_AVX512:
		return plait_project_distance_avx512;
#endif
	default:
		return plait_project_distance_scalar;
	}
}
