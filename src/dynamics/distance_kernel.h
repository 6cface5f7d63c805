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
 *     x_i -= w_i s d,   x_j += w_j s d. */
#ifndef PLAIT_DYNAMICS_DISTANCE_KERNEL_H
#define PLAIT_DYNAMICS_DISTANCE_KERNEL_H

#include "dynamics/sim.h"

typedef void plait_distance_kernel(plait_distance_block *block, plait_point *points, int begin, int end,
                                   float inverse_h_squared);

plait_distance_kernel plait_project_distance_scalar;
#if PLAIT_X86_KERNELS
plait_distance_kernel plait_project_distance_avx2;
plait_distance_kernel plait_project_distance_avx512;
#endif

/* Whether this processor can run a level (PLAIT_SIMD_AUTO: always). */
bool plait_simd_supported(plait_simd level);
/* The level AUTO means on this processor. */
plait_simd plait_simd_best(void);
/* The kernel of a supported level other than AUTO. */
plait_distance_kernel *plait_distance_kernel_for(plait_simd level);

#endif
