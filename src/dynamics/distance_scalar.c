#include "dynamics/distance_kernel.h"

#include <math.h>

/* The reference arithmetic (plait_distance_step, then each end by its own difference to the
 * other): the vector kernels repeat these operations lane by lane, in this order, so all give the
 * same bits. A rigid block (no compliance) takes the step without a square root
 * (distance_kernel.h) and never touches the compliance and lambda arrays; `rigid` is a constant
 * in each call below, so the compiler makes two loops. */
static inline __attribute__((always_inline)) void project_range(plait_distance_block *block,
                                                                plait_point *points, int begin, int end,
                                                                float inverse_h_squared, bool rigid)
{
	const int(*pair)[2] = (const int(*)[2])block->pair;
	for (int c = begin; c < end; ++c) {
		plait_point *pi = &points[pair[c][0]], *pj = &points[pair[c][1]];
		float wi = pi->w, wj = pj->w;
		float dx = pj->x.x - pi->x.x, dy = pj->x.y - pi->x.y, dz = pj->x.z - pi->x.z;
		float s = plait_distance_step(block, c, dx, dy, dz, wi, wj, inverse_h_squared, rigid);
		float si = wi * s, sj = wj * s;
		float ex = pi->x.x - pj->x.x, ey = pi->x.y - pj->x.y, ez = pi->x.z - pj->x.z;
		pi->x.x = pi->x.x - si * dx;
		pi->x.y = pi->x.y - si * dy;
		pi->x.z = pi->x.z - si * dz;
		pj->x.x = pj->x.x - sj * ex;
		pj->x.y = pj->x.y - sj * ey;
		pj->x.z = pj->x.z - sj * ez;
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

/* The widest. AMD's Zen 4 runs 512-bit shuffles at half the rate of 256-bit ones, and AVX2
 * was the faster there while the kernels widened and scaled every index (2.1 against 2.6 ns
 * per projection at hang-128); with points addressed by byte offsets the kernels issue fewer
 * instructions a constraint the wider they are, and AVX-512 wins there too (bench_kernels:
 * 1.2 against 1.55 ns). The choice never changes results, only speed. */
plait_simd plait_simd_best(void)
{
#if PLAIT_X86_KERNELS
	if (plait_simd_supported(PLAIT_SIMD_AVX512)) {
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

plait_column_ops plait_column_ops_for(plait_simd level)
{
	plait_column_ops ops = {NULL, NULL, NULL};
	switch (level) {
#if PLAIT_X86_KERNELS
	/* None for AVX2: an eight-lane column kernel was slower here than the AVX2 point kernel
	 * (docs/performance.md, session 18). */
	case PLAIT_SIMD_AVX512:
		ops = (plait_column_ops){plait_project_distance_columns_avx512, plait_points_to_columns_avx512,
		                         plait_points_from_columns_avx512};
		break;
#endif
	default:
		break;
	}
	return ops;
}
