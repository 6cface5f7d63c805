/* Constraint projection (XPBD: Macklin, Müller, Chentanez 2016). Each solve runs one
 * Gauss-Seidel sweep over a block. With compliance alpha and multiplier lambda (reset each
 * substep), one projection is
 *     dlambda = (-C - alpha~ lambda) / (sum_i w_i |grad_i C|^2 + alpha~),  alpha~ = alpha / h^2,
 *     x_i += w_i grad_i C dlambda,
 * so the material's stiffness 1/alpha does not depend on how many iterations or substeps run
 * (seed 000 §2.4: "the solver attempts to preserve the defined level of stretchiness"). */
#ifndef PLAIT_DYNAMICS_CONSTRAINTS_H
#define PLAIT_DYNAMICS_CONSTRAINTS_H

#include "core/parallel.h"
#include "dynamics/bend_kernel.h"
#include "dynamics/distance_kernel.h"
#include "dynamics/sim.h"

/* Direction of a Gauss-Seidel sweep. A forward sweep alone is not symmetric: its error
 * operator can have complex or negative eigenvalues, and turning position corrections into
 * velocities then amplifies them (a cloth solved with one forward sweep per substep can
 * explode). The solver therefore alternates forward and backward sweeps within a substep and
 * closes an odd count with a symmetric one, so every substep applies whole symmetric sweeps,
 * whose error operator has real eigenvalues in [0, 1). A kind that runs once per substep (many
 * substeps, the cheapest way to stiffness) sweeps forward in even substeps and backward in odd
 * ones instead: each pair of substeps is then one symmetric sweep, at half the cost (hang-128
 * stiff at 10 substeps: 18 -> 10 ms). Except stretch, the load-bearing kind: alternating its
 * direction ends every other substep with the edges next to a pin stretched, a period-2
 * oscillation that the velocity update feeds; a heavy rigid cloth hung without tethers blew up
 * at 16 and at 32 substeps (tests/test_stability.c, heavy_rigid_cloth_hangs_with_one_pass).
 * Stretch run once per substep sweeps symmetrically; shear and bend still alternate. */
typedef enum plait_sweep {
	PLAIT_SWEEP_FORWARD,
	PLAIT_SWEEP_BACKWARD,
	PLAIT_SWEEP_SYMMETRIC, /* forward then backward */
} plait_sweep;

/* The sweep for iteration `iteration` of `count` of a kind in substep `substep`; a
 * load-bearing kind (stretch) never alternates. */
static inline plait_sweep plait_sweep_for(int iteration, int count, int substep, bool load_bearing)
{
	if (count == 1) {
		if (load_bearing) {
			return PLAIT_SWEEP_SYMMETRIC;
		}
		return (substep & 1) ? PLAIT_SWEEP_BACKWARD : PLAIT_SWEEP_FORWARD;
	}
	if ((iteration & 1) != 0) {
		return PLAIT_SWEEP_BACKWARD;
	}
	return iteration == count - 1 ? PLAIT_SWEEP_SYMMETRIC : PLAIT_SWEEP_FORWARD;
}

/* A sweep goes colour by colour (each colour split over the workers), then through the
 * uncoloured rest one by one; a backward sweep goes the other way. A symmetric sweep does both,
 * region by region: the boundary forward, each region there and back, the boundary back. */
/* columns: NULL, or the points as columns (solver.c, "Columns"), projected there with the column
 * kernel instead of `kernel`. */
void plait_solve_distance(plait_distance_block *block, plait_particles *particles,
                          const plait_columns *columns, float inverse_h_squared, plait_sweep sweep,
                          plait_distance_kernel *kernel, plait_parallel *parallel);
/* The parts of a distance sweep on columns for a wave down the regions (dynamics/wave.h):
 * region `region` swept as plait_solve_distance sweeps it, and the boundary constraints of cut
 * `cut` (between regions cut and cut + 1; the block's boundary banded, colouring.h), run after
 * run, or backward the other way. */
void plait_distance_sweep_region(plait_distance_block *block, const plait_columns *columns, int region,
                                 float inverse_h_squared, plait_sweep sweep);
void plait_distance_sweep_cut(plait_distance_block *block, const plait_columns *columns, int cut,
                              float inverse_h_squared, bool backward);
void plait_solve_bend(plait_bend_block *block, plait_particles *particles, float inverse_h_squared,
                      plait_bend_kernel *kernel, plait_parallel *parallel);
/* Unilateral: only a tether longer than its length is pulled in, by its stiffness share. With
 * simd above scalar, rows of two held to pins run in AVX2 (tether_kernel.h), to the same bits. */
void plait_solve_tethers(plait_tether_block *block, plait_particles *particles, plait_simd simd,
                         plait_parallel *parallel);
/* Whether the tethers can be solved a range of particles at a time, side by side with other
 * ranges' velocity updates: every anchor pinned (each particle's tethers then write that
 * particle alone) and still over the frame (another range moving an anchor to its next target
 * would change what this one reads), the rows regrouped, in particle order. */
bool plait_tethers_by_particle(const plait_tether_block *block);
/* The tethers of particles [begin, end) alone, as plait_solve_tethers solves them (the same
 * bits); only when plait_tethers_by_particle. */
void plait_solve_tethers_of_particles(plait_tether_block *block, plait_point *points, plait_simd simd,
                                      int begin, int end);
/* Whether plait_solve_tethers_of_particles_on_columns can solve them: by particle, and every
 * row of two (rows of two in runs, no others). */
bool plait_tethers_on_columns(const plait_tether_block *block);
/* plait_solve_tethers_of_particles on the points as columns (solver.c, "Columns"), to the same
 * bits; only when plait_tethers_on_columns and the columns kernels run (AVX-512). */
/* Copies the anchors of tethers on columns (plait_tethers_on_columns) into the columns. */
void plait_tether_anchors_to_columns(const plait_tether_block *block, const plait_particles *particles,
                                     const plait_columns *columns);
void plait_solve_tethers_of_particles_on_columns(plait_tether_block *block, const plait_columns *columns,
                                                 int begin, int end);
/* For the frame to come: whether every tether's anchor is pinned (pins change between frames
 * only), and the solver's regrouping of the tethers, derived again if they changed. Out of
 * memory only costs speed: the tethers are then solved as they are stored. */
void plait_tethers_begin_frame(plait_tether_block *block, const plait_particles *particles,
                               const plait_allocator *allocator);
void plait_tether_lanes_destroy(plait_tether_block *block, const plait_allocator *allocator);
void plait_solve_rod_bend(plait_rod_bend_block *block, plait_particles *particles, float inverse_h_squared);

/* Signed dihedral angle (radians, in (-pi, pi]) of the hinge p0-p1 with wings p2, p3: zero when
 * flat, positive when the wings fold toward the side the normal of (p0, p1, p2) points to...
 * see bend.c. Writes the gradient with respect to the four points when gradient != NULL;
 * returns false when a triangle is degenerate. */
bool plait_dihedral_angle(vec3 p0, vec3 p1, vec3 p2, vec3 p3, float *angle, vec3 gradient[4]);

/* Largest |length / rest - 1| over a distance block. */
float plait_distance_max_strain(const plait_distance_block *block, const plait_particles *particles);

#endif
