/* The vector kernel of tethers held to two pins (tether.c): rows of two solved eight at a time
 * in AVX2, with the portable batch code's operations in its order (the same bits). */
#ifndef PLAIT_DYNAMICS_TETHER_KERNEL_H
#define PLAIT_DYNAMICS_TETHER_KERNEL_H

#include "dynamics/sim.h"

#if PLAIT_X86_KERNELS
/* Rows [0, count) of one run: row k holds particle[k] within length0[k] of anchor0 and
 * length1[k] of anchor1 (pins), moved `stiffness` of the way to its target (one per run: its
 * cloth's). A taut row whose
 * float candidates do not check out is left as it is and its k written to unfound[] (count
 * entries at most) for the exact search; returns how many. tolerance: tether.c's
 * INSIDE_TOLERANCE, as a float. */
int plait_tether_rows_avx2(plait_point *points, const int *particle, const float *length0,
                           const float *length1, float stiffness, vec3 anchor0, vec3 anchor1, int count,
                           float tolerance, int *unfound);
/* The same sixteen rows at a time in AVX-512 (tether_avx512.c), to the same bits. */
int plait_tether_rows_avx512(plait_point *points, const int *particle, const float *length0,
                             const float *length1, float stiffness, vec3 anchor0, vec3 anchor1, int count,
                             float tolerance, int *unfound);
/* The same on the points as columns (solver.c, "Columns"): w is read there, not written. */
int plait_tether_rows_columns_avx512(const plait_columns *columns, const int *particle, const float *length0,
                                     const float *length1, float stiffness, vec3 anchor0, vec3 anchor1,
                                     int count, float tolerance, int *unfound);
#endif

#endif
