/* The distance-constraint kernel: XPBD projection of a range of constraints that share no
 * particle (one colour, or part of one). It is the solver's hottest loop, so it exists three
 * times: portable C, AVX2 (8 lanes) and AVX-512 (16 lanes), chosen when the world is created
 * (plait_world_def.simd). All three do the same IEEE operations in the same order (no fused
 * multiply-add, correctly rounded sqrt and divide), so they give bit-identical results; the
 * vector ones hand the remainder of a range to the narrower ones.
 *
 * One projection, with d = x_j - x_i, L = |d|, C = L - rest, alpha the compliance of the
 * direction C points to (negative: no resistance that way), alpha~ = alpha / h^2:
 *     s = (-C - alpha~ lambda) / ((w_i + w_j + alpha~) L),   lambda += s L,
 *     x_i -= w_i s (x_j - x_i),   x_j -= w_j s (x_i - x_j).
 * Each end moves by its own difference to the other rather than x_j += w_j s d: the same value,
 * but symmetric in the two ends to the bit (with d = +0, -d would be -0), so the kernels may
 * work a constraint from either end (the column kernel's lanes do).
 *
 * A rigid block (no compliance anywhere) takes a step without a square root:
 *     s = (rest^2 - L^2) / ((w_i + w_j) (L^2 + rest^2)),
 * the rational approximation of the exact -C / ((w_i + w_j) L). It has the same fixed point
 * (L = rest) and the same first-order step; with L = x rest its ratio to the exact step is
 * x (x + 1) / (x^2 + 1), between 0 (collapsed) and 1.21 (at x = 1 + sqrt 2), so it never
 * over-projects by more than a fifth and never diverges. It made the kernel about 9% faster
 * (a square root and a maximum off each batch's dependency chain) at the same strain
 * (docs/performance.md, session 7). */
#ifndef PLAIT_DYNAMICS_DISTANCE_KERNEL_H
#define PLAIT_DYNAMICS_DISTANCE_KERNEL_H

#include <math.h>

#include "dynamics/sim.h"

/* The step s of constraint c, given d = x_j - x_i and the inverse masses (and its multiplier
 * advanced, for a compliant block): the reference arithmetic, which the vector kernels repeat
 * lane by lane in this order. Shared by the portable kernel (distance_scalar.c) and the column
 * kernel's constraints alone (distance_columns.h). */
static inline __attribute__((always_inline)) float plait_distance_step(plait_distance_block *block, int c,
                                                                       float dx, float dy, float dz, float wi,
                                                                       float wj, float inverse_h_squared,
                                                                       bool rigid)
{
	float length_sq = dx * dx + dy * dy + dz * dz;
	float w_sum = wi + wj;
	if (rigid) {
		float rest_sq = block->rest[c] * block->rest[c];
		float sum_sq = length_sq + rest_sq;
		sum_sq = sum_sq > 1e-24f ? sum_sq : 1e-24f;
		float denominator = w_sum > 0.0f ? w_sum * sum_sq : 1.0f;
		return w_sum > 0.0f ? (rest_sq - length_sq) / denominator : 0.0f;
	}
	float length = sqrtf(length_sq);
	length = length > 1e-12f ? length : 1e-12f;
	float C = length - block->rest[c];
	float alpha = C > 0.0f ? block->compliance_tension[c] : block->compliance_compression[c];
	bool active = (alpha >= 0.0f) & (w_sum > 0.0f);
	float alpha_tilde = (alpha > 0.0f ? alpha : 0.0f) * inverse_h_squared;
	float denominator = (w_sum + alpha_tilde) * length;
	denominator = w_sum > 0.0f ? denominator : 1.0f;
	float s = (-C - alpha_tilde * block->lambda[c]) / denominator;
	s = active ? s : 0.0f;
	block->lambda[c] = block->lambda[c] + s * length;
	return s;
}

typedef void plait_distance_kernel(plait_distance_block *block, plait_point *points, int begin, int end,
                                   float inverse_h_squared);

plait_distance_kernel plait_project_distance_scalar;
#if PLAIT_X86_KERNELS
plait_distance_kernel plait_project_distance_avx2;
plait_distance_kernel plait_project_distance_avx512;
#endif

/* The column kernel (distance_columns_avx512.c): constraints [begin, end) of a block by its
 * segments (batch_layout.h), on the points as columns, the same bits as the point kernels; and
 * the copies of points [begin, end) into columns and back. */
#if PLAIT_X86_KERNELS
plait_column_kernel plait_project_distance_columns_avx512;
void plait_points_to_columns_avx512(const plait_point *points, const plait_columns *columns, int begin,
                                    int end);
void plait_points_from_columns_avx512(plait_point *points, const plait_columns *columns, int begin, int end);
#endif
/* The column kernel and copies of a level (all NULL where there is none: AVX-512 only). */
plait_column_ops plait_column_ops_for(plait_simd level);

/* Whether this processor can run a level (PLAIT_SIMD_AUTO: always). */
bool plait_simd_supported(plait_simd level);
/* The level AUTO means on this processor. */
plait_simd plait_simd_best(void);
/* The kernel of a supported level other than AUTO. */
plait_distance_kernel *plait_distance_kernel_for(plait_simd level);

#endif
