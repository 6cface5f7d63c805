/* Gravity, air drag, lift and wind (seed 000 §3.1.1, §5.3, §5.4; seed 003: force and mass by
 * area). All coefficients are SI; space_scale s (metres per scene unit) converts them.
 *
 * For a cloth triangle of area A (m^2), unit normal n, and air velocity relative to it
 * u = wind - v (m/s), with air density rho (kg/m^3):
 *   normal drag      F_n = drag            * rho * A * (u.n) n              (linear in speed)
 *   tangential drag  F_t = tangential_drag * rho * A * (u - (u.n) n)
 *   lift             F_l = lift * rho * A * |u|^2 * |cos a| sin a * l,  cos a = |u.n|/|u|,
 *                    l = the unit part of sign(u.n) n perpendicular to u (sheet pushed across
 *                    the flow toward the side the air strikes)
 * Each triangle gives a third of its force to each corner; the masses are area-weighted too, so
 * a flat sheet of mass m falling face-down in still air reaches v = m g / (drag rho A): that is
 * the contract for drag. Curves and particles use the isotropic form F = drag rho A u with
 * A = pi r^2 of each vertex.
 *
 * Drag is integrated implicitly per vertex: with K the vertex's summed drag tensor (kg/s),
 * (m I + h K) v' = m v + h (m g + K w + F_lift), stable for any drag, exact at terminal speed.
 * Lift, quadratic in speed, stays explicit; one substep of it may change a vertex's velocity by
 * at most half the air speed relative to the vertex, which keeps strong lift from pumping
 * energy (seed 000 §5.3 warns of exactly that) and never binds in ordinary scenes.
 * Wind noise adds to each triangle's wind a smooth random vector of length up to
 * noise * speed, varying over 0.5 m cells and 0.25 s. */
#ifndef PLAIT_DYNAMICS_AIR_H
#define PLAIT_DYNAMICS_AIR_H

#include <math.h>

#include "dynamics/sim.h"

/* Whether any object feels the air (decides whether the air stage runs at all). */
bool plait_air_active(const plait_sim *sim);

/* Fills particles.drag_matrix and air_force for the substep starting at time (seconds). */
void plait_air_accumulate(plait_sim *sim, double time);

/* v <- velocity after gravity, air and damping over h, for every free particle. */
void plait_integrate_velocities(plait_sim *sim, float h, bool air, int begin, int end);

/* Damping at rate damp (1/s) over h: exact exponential decay. */
static inline vec3 plait_damp_velocity(vec3 v, float damp, float h)
{
	return damp > 0.0f ? v3_scale(v, expf(-damp * h)) : v;
}

#endif
