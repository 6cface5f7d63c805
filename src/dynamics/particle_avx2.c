/* The end of one substep and the start of the next (particle_step.h) in AVX2, eight particles
 * at a time, each alone or both in one pass. Compiled with -mavx2 (never with FMA contraction); only called
 * when the processor has AVX2. Every lane does plait_end_particle then plait_begin_particle's operations in
 * their order, so the bits are the portable loop's. The rare cases go back to those functions' parts lane by
 * lane: a collider contact's restitution between the two halves, and a pinned particle's target after them.
 */
#include "dynamics/particle_step.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>
#include <string.h>

#include "dynamics/points_avx2.h"

/* Eight vec3 (24 floats from `from`) into a register per coordinate, and back. Lane k of the
 * blends below holds coordinate k % 3 of vector k / 3 in register a (k < 8), b or c; the
 * permutes put each coordinate's lanes in vector order. */
static inline void load_vec3x8(const vec3 *from, __m256 *x, __m256 *y, __m256 *z)
{
	const float *f = &from->x;
	__m256 a = _mm256_loadu_ps(f), b = _mm256_loadu_ps(f + 8), c = _mm256_loadu_ps(f + 16);
	*x = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(a, b, 0x92), c, 0x24),
	                              _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
	*y = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(a, b, 0x24), c, 0x49),
	                              _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
	*z = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(a, b, 0x49), c, 0x92),
	                              _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
}

static inline void store_vec3x8(vec3 *to, __m256 x, __m256 y, __m256 z)
{
	__m256 xb = _mm256_permutevar8x32_ps(x, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
	__m256 yb = _mm256_permutevar8x32_ps(y, _mm256_setr_epi32(5, 0, 3, 6, 1, 4, 7, 2));
	__m256 zb = _mm256_permutevar8x32_ps(z, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
	float *f = &to->x;
	_mm256_storeu_ps(f, _mm256_blend_ps(_mm256_blend_ps(xb, yb, 0x92), zb, 0x24));
	_mm256_storeu_ps(f + 8, _mm256_blend_ps(_mm256_blend_ps(xb, yb, 0x24), zb, 0x49));
	_mm256_storeu_ps(f + 16, _mm256_blend_ps(_mm256_blend_ps(xb, yb, 0x49), zb, 0x92));
}

/* The end of a substep (with `ending`) and the start of the next (with `beginning`), one or
 * both; the three combinations are separate copies. */
static inline __attribute__((always_inline)) void step_range(const plait_particle_step *k, plait_particles *p,
                                                             int begin, int end, bool ending, bool beginning)
{
	const __m256 zero = _mm256_setzero_ps(), h = _mm256_set1_ps(k->h),
	             inverse_h = _mm256_set1_ps(k->inverse_h);
	const __m256 gx = _mm256_set1_ps(k->gravity.x), gy = _mm256_set1_ps(k->gravity.y),
	             gz = _mm256_set1_ps(k->gravity.z);
	const __m256 hx = _mm256_set1_ps(k->half_gravity_step.x), hy = _mm256_set1_ps(k->half_gravity_step.y),
	             hz = _mm256_set1_ps(k->half_gravity_step.z);
	/* Materials are read for their damping factor, as floats: its address in the first and the
	 * stride in floats (the struct has int members, so its size is a multiple of 4). */
	const float *damp_factor = &k->materials[0].damp_factor;
	const __m256i material_stride = _mm256_set1_epi32((int)(sizeof(plait_material) / sizeof(float)));
	const __m256 shared_factor = _mm256_set1_ps(k->shared_damp_factor);
	const uint64_t contact_bits = 0x0101010101010101ull * PLAIT_PARTICLE_CONTACT;
	const uint64_t kept_bits =
	    0x0101010101010101ull *
	    (uint8_t) ~(PLAIT_PARTICLE_CONTACT | PLAIT_PARTICLE_SUPPORTED | PLAIT_PARTICLE_ON_PLANE);
	const uint64_t on_plane_bits = 0x0101010101010101ull * PLAIT_PARTICLE_ON_PLANE;
	_Static_assert(PLAIT_PARTICLE_ON_PLANE == 2 * PLAIT_PARTICLE_SUPPORTED,
	               "a particle on a plane is supported in the next substep: one shift right");
	int i = begin;
	for (; i + 8 <= end; i += 8) {
		int index[8] = {i, i + 1, i + 2, i + 3, i + 4, i + 5, i + 6, i + 7};
		__m256 x, y, z, w;
		gather8(p->point, index, &x, &y, &z, &w);
		__m256 pinned = _mm256_cmp_ps(w, zero, _CMP_EQ_OQ);
		uint64_t flags;
		memcpy(&flags, p->flags + i, sizeof flags);
		__m256 vx, vy, vz, mx = zero, my = zero, mz = zero;
		if (!ending) {
			load_vec3x8(p->v + i, &vx, &vy, &vz);
		} else {
			/* plait_end_particle: the mean velocity of the substep, and for a free particle
			 * the velocity at its end. */
			__m256 px, py, pz;
			load_vec3x8(p->x_prev + i, &px, &py, &pz);
			mx = _mm256_mul_ps(_mm256_sub_ps(x, px), inverse_h);
			my = _mm256_mul_ps(_mm256_sub_ps(y, py), inverse_h);
			mz = _mm256_mul_ps(_mm256_sub_ps(z, pz), inverse_h);
			vx = _mm256_add_ps(mx, hx);
			vy = _mm256_add_ps(my, hy);
			vz = _mm256_add_ps(mz, hz);
		}
		if (ending && (flags & contact_bits)) {
			/* Restitution and stickiness, lane by lane, against the velocity before (still in
			 * p->v). */
			_Alignas(32) float lx[8], ly[8], lz[8];
			_mm256_store_ps(lx, vx);
			_mm256_store_ps(ly, vy);
			_mm256_store_ps(lz, vz);
			int pinned_lanes = _mm256_movemask_ps(pinned);
			for (int lane = 0; lane < 8; ++lane) {
				if ((p->flags[i + lane] & PLAIT_PARTICLE_CONTACT) && !(pinned_lanes & (1 << lane))) {
					vec3 v = plait_respond_to_collider_contact(
					    p, i + lane, p->v[i + lane], v3(lx[lane], ly[lane], lz[lane]), k->resting_speed);
					lx[lane] = v.x;
					ly[lane] = v.y;
					lz[lane] = v.z;
				}
			}
			vx = _mm256_load_ps(lx);
			vy = _mm256_load_ps(ly);
			vz = _mm256_load_ps(lz);
		}

		if (!beginning) {
			/* The velocity at the substep's end; a pinned particle's is its mean one. */
			store_vec3x8(p->v + i, _mm256_blendv_ps(vx, mx, pinned), _mm256_blendv_ps(vy, my, pinned),
			             _mm256_blendv_ps(vz, mz, pinned));
			continue;
		}
		/* plait_begin_particle: the contact flags, the start of the new substep, then gravity,
		 * damping and the predicted position of a free particle. */
		flags = (flags & kept_bits) | ((flags & on_plane_bits) >> 1);
		memcpy(p->flags + i, &flags, sizeof flags);
		store_vec3x8(p->x_prev + i, x, y, z);
		__m256 factor = shared_factor;
		if (!k->damp_shared) {
			__m256i material = _mm256_loadu_si256((const __m256i *)(p->material + i));
			factor = _mm256_i32gather_ps(damp_factor, _mm256_mullo_epi32(material, material_stride), 4);
		}
		vx = _mm256_mul_ps(_mm256_add_ps(vx, _mm256_mul_ps(h, gx)), factor);
		vy = _mm256_mul_ps(_mm256_add_ps(vy, _mm256_mul_ps(h, gy)), factor);
		vz = _mm256_mul_ps(_mm256_add_ps(vz, _mm256_mul_ps(h, gz)), factor);
		x = _mm256_add_ps(x, _mm256_mul_ps(h, _mm256_sub_ps(vx, hx)));
		y = _mm256_add_ps(y, _mm256_mul_ps(h, _mm256_sub_ps(vy, hy)));
		z = _mm256_add_ps(z, _mm256_mul_ps(h, _mm256_sub_ps(vz, hz)));
		/* A pinned particle keeps its velocity (the mean one, when the substep ended here) and
		 * goes to its target (below). */
		if (ending) {
			vx = _mm256_blendv_ps(vx, mx, pinned);
			vy = _mm256_blendv_ps(vy, my, pinned);
			vz = _mm256_blendv_ps(vz, mz, pinned);
		} else {
			__m256 ox, oy, oz;
			load_vec3x8(p->v + i, &ox, &oy, &oz);
			vx = _mm256_blendv_ps(vx, ox, pinned);
			vy = _mm256_blendv_ps(vy, oy, pinned);
			vz = _mm256_blendv_ps(vz, oz, pinned);
		}
		store_vec3x8(p->v + i, vx, vy, vz);
		/* A pinned particle goes to its target in the same store: a tether anchored at it may be
		 * read by another worker meanwhile (solver.c, folded_range), and must never see the
		 * free particle's prediction computed in its lane. */
		int pinned_lanes = _mm256_movemask_ps(pinned);
		if (pinned_lanes != 0) {
			_Alignas(32) float lx[8], ly[8], lz[8];
			_mm256_store_ps(lx, x);
			_mm256_store_ps(ly, y);
			_mm256_store_ps(lz, z);
			while (pinned_lanes != 0) {
				int lane = __builtin_ctz((unsigned)pinned_lanes);
				pinned_lanes &= pinned_lanes - 1;
				vec3 target = v3_lerp(p->pin_start[i + lane], p->pin_end[i + lane], k->t_end);
				lx[lane] = target.x;
				ly[lane] = target.y;
				lz[lane] = target.z;
			}
			x = _mm256_load_ps(lx);
			y = _mm256_load_ps(ly);
			z = _mm256_load_ps(lz);
		}
		scatter8(p->point, index, 8, x, y, z, w);
	}
	for (; i < end; ++i) {
		if (ending) {
			plait_end_particle(k, p, i);
		}
		if (beginning) {
			plait_begin_particle(k, p, i);
		}
	}
	_mm256_zeroupper();
}

void plait_step_particles_avx2(const plait_particle_step *k, plait_particles *p, int begin, int end,
                               bool ending, bool beginning)
{
	/* One copy per combination, each without the tests of the others. */
	if (ending && beginning) {
		step_range(k, p, begin, end, true, true);
	} else if (ending) {
		step_range(k, p, begin, end, true, false);
	} else if (beginning) {
		step_range(k, p, begin, end, false, true);
	}
}
#endif
