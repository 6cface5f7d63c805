/* The per-particle stages of a substep (the frame loop, solver.c): the start of a substep
 * (gravity, damping and the predicted position) and its end (the velocity update). They are
 * shared by the portable loops of solver.c and the AVX2 pass of particle_avx2.c, which does
 * the same operations in the same order, eight particles at a time: the two give the same bits. */
#ifndef PLAIT_DYNAMICS_PARTICLE_STEP_H
#define PLAIT_DYNAMICS_PARTICLE_STEP_H

#include "dynamics/contact.h"
#include "dynamics/sim.h"

/* What the per-particle stages read of the substep, copied into locals once per range: read
 * through the job, every store to a particle could change them as far as the compiler knows,
 * and it would load them (and divide by h) again for every particle. */
typedef struct plait_particle_step {
	float h, inverse_h, t_end, resting_speed;
	vec3 gravity, half_gravity_step;
	bool air;
	const plait_material *materials;
	bool damp_shared; /* every free particle's material damps by shared_damp_factor (solver.c) */
	float shared_damp_factor;
} plait_particle_step;

/* Start of a substep for particle i: its velocity takes gravity and damping (air, when on, has
 * been applied to the range already); then a pinned particle moves to its interpolated target,
 * a free one to its predicted position. v then holds the end-of-substep velocity; moving with
 * v - h g / 2, the mean velocity over the substep under constant gravity, makes free flight
 * exact (x0 + v0 t + g t^2 / 2) instead of off by g h t / 2. v keeps that value until the
 * velocity update: collisions read it as the velocity before the constraints. The contacts of
 * the last substep are forgotten; what rested on a plane collider in it is held by it in this
 * one (see surface_contact.c). */
static inline void plait_begin_particle(const plait_particle_step *k, plait_particles *p, int i)
{
	const uint8_t cleared =
	    (uint8_t) ~(PLAIT_PARTICLE_CONTACT | PLAIT_PARTICLE_SUPPORTED | PLAIT_PARTICLE_ON_PLANE);
	uint8_t flags = p->flags[i];
	p->flags[i] =
	    (uint8_t)((flags & cleared) | ((flags & PLAIT_PARTICLE_ON_PLANE) ? PLAIT_PARTICLE_SUPPORTED : 0));
	p->x_prev[i] = p->point[i].x;
	if (p->point[i].w == 0.0f) {
		p->point[i].x = v3_lerp(p->pin_start[i], p->pin_end[i], k->t_end);
		return;
	}
	/* Without air, plait_integrate_velocities in the same pass: gravity and damping. */
	if (!k->air) {
		float damp_factor = k->damp_shared ? k->shared_damp_factor : k->materials[p->material[i]].damp_factor;
		p->v[i] = v3_scale(v3_mul_add(p->v[i], k->h, k->gravity), damp_factor);
	}
	p->point[i].x = v3_mul_add(p->point[i].x, k->h, v3_sub(p->v[i], k->half_gravity_step));
}

/* End of a substep for particle i: v = (x - x_prev) / h is the mean velocity of the substep;
 * adding h g / 2 back gives the velocity at its end (the inverse of the prediction above).
 * Then restitution and stickiness of its collider contact, which compare it with the velocity
 * before. */
static inline void plait_end_particle(const plait_particle_step *k, plait_particles *p, int i)
{
	vec3 mean = v3_scale(v3_sub(p->point[i].x, p->x_prev[i]), k->inverse_h);
	if (p->point[i].w == 0.0f) {
		p->v[i] = mean;
		return;
	}
	vec3 v = v3_add(mean, k->half_gravity_step);
	if (p->flags[i] & PLAIT_PARTICLE_CONTACT) {
		v = plait_respond_to_collider_contact(p, i, p->v[i], v, k->resting_speed);
	}
	p->v[i] = v;
}

/* The end of a substep (with `ending`: plait_end_particle) and the start of the next (with
 * `beginning`: plait_begin_particle, without air) for particles [begin, end), eight at a time,
 * to the same bits. Only call when the processor runs AVX2 (plait_simd_supported). */
void plait_step_particles_avx2(const plait_particle_step *k, plait_particles *p, int begin, int end,
                               bool ending, bool beginning);
/* The same sixteen at a time (particle_avx512.c); only when the processor runs AVX-512F. */
void plait_step_particles_avx512(const plait_particle_step *k, plait_particles *p, int begin, int end,
                                 bool ending, bool beginning);
/* The end of a substep and, with `beginning`, the start of the next, on the points as columns
 * (solver.c, "Columns"; w is read there, not written), to the same bits; the point array is
 * written only for the last (end - begin) % 16 particles, which take the portable operations
 * through it. */
void plait_step_columns_avx512(const plait_particle_step *k, plait_particles *p, const plait_columns *columns,
                               int begin, int end, bool beginning);

#endif
