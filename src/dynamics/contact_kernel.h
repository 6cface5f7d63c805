/* The collider cull (contact.c) in AVX2: which particles' paths over the substep may reach a
 * bounded collider, eight particles at a time. */
#ifndef PLAIT_DYNAMICS_CONTACT_KERNEL_H
#define PLAIT_DYNAMICS_CONTACT_KERNEL_H

#include "dynamics/sim.h"

/* The region a collider may be met in over a substep: a box and a ball holding it, grown by
 * the largest reach of a particle (contact.c). */
typedef struct plait_collider_bounds {
	vec3 lower, upper;
	vec3 ball_centre;
	float ball_radius;
} plait_collider_bounds;

#if PLAIT_X86_KERNELS
/* Particles [begin, begin + count) that take part in collisions, are free and whose path from
 * x_prev to the point may reach the bounds, into near[] in order; returns how many. count is a
 * multiple of 8. The same decisions as contact.c's portable cull. Only call when the processor
 * runs AVX2. */
int plait_cull_particles_avx2(const plait_particles *p, const plait_collider_bounds *bounds, int begin,
                              int count, int *near);
/* The same sixteen at a time (count a multiple of 16), in AVX-512 (contact_avx512.c). */
int plait_cull_particles_avx512(const plait_particles *p, const plait_collider_bounds *bounds, int begin,
                                int count, int *near);
/* The same on the points as columns (solver.c, "Columns"), to the same particles. */
int plait_cull_columns_avx512(const plait_particles *p, const plait_columns *columns,
                              const plait_collider_bounds *bounds, int begin, int count, int *near);
#endif

#endif
