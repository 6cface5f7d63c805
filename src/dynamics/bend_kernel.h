/* The dihedral bend kernel: projection of a range of hinges that share no particle (see
 * constraints.c for the math). Portable C (8 lanes the compiler vectorises) and AVX2, chosen
 * with the distance kernel; both give the same bits. */
#ifndef PLAIT_DYNAMICS_BEND_KERNEL_H
#define PLAIT_DYNAMICS_BEND_KERNEL_H

#include "dynamics/sim.h"

typedef void plait_bend_kernel(plait_bend_block *block, plait_point *points, int begin, int end,
                               float inverse_h_squared);

plait_bend_kernel plait_project_bend_portable;
#if PLAIT_X86_KERNELS
plait_bend_kernel plait_project_bend_avx2;
#endif

/* The kernel of a supported level other than AUTO (AVX-512 runs the AVX2 one). */
plait_bend_kernel *plait_bend_kernel_for(plait_simd level);

#endif
