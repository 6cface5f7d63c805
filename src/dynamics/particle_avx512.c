/* The end of one substep and the start of the next (particle_step.h) in AVX-512, sixteen
 * particles at a time: particle_avx2.c's pass lane for lane, the same operations in the same
 * order (the portable loop's bits), with masks for its selects. Compiled with -mavx512f (never
 * with FMA contraction); only called when the processor has AVX-512F. */
#include "dynamics/particle_step.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>
#include <string.h>

#include "dynamics/points_avx512.h"

static inline __attribute__((always_inline)) void step_range(const plait_particle_step *k, plait_particles *p,
                                                             const plait_columns *columns, int begin, int end,
                                                             bool ending, bool beginning)
{
	const __m512 zero = _mm512_setzero_ps(), h = _mm512_set1_ps(k->h),
	             inverse_h = _mm512_set1_ps(k->inverse_h);
	const __m512 gx = _mm512_set1_ps(k->gravity.x), gy = _mm512_set1_ps(k->gravity.y),
	             gz = _mm512_set1_ps(k->gravity.z);
	const __m512 hx = _mm512_set1_ps(k->half_gravity_step.x), hy = _mm512_set1_ps(k->half_gravity_step.y),
	             hz = _mm512_set1_ps(k->half_gravity_step.z);
	/* Materials are read for their damping factor, as floats (particle_avx2.c). */
	const float *damp_factor = &k->materials[0].damp_factor;
	const __m512i material_stride = _mm512_set1_epi32((int)(sizeof(plait_material) / sizeof(float)));
	const __m512 shared_factor = _mm512_set1_ps(k->shared_damp_factor);
	const uint64_t contact_bits = 0x0101010101010101ull * PLAIT_PARTICLE_CONTACT;
	const uint64_t kept_bits =
	    0x0101010101010101ull *
	    (uint8_t) ~(PLAIT_PARTICLE_CONTACT | PLAIT_PARTICLE_SUPPORTED | PLAIT_PARTICLE_ON_PLANE);
	const uint64_t on_plane_bits = 0x0101010101010101ull * PLAIT_PARTICLE_ON_PLANE;
	int i = begin;
	for (; i + 16 <= end; i += 16) {
		__m512 x, y, z, w;
		if (columns != NULL) {
			load_columns16(columns, i, &x, &y, &z, &w);
		} else {
			load_points16(p->point, i, &x, &y, &z, &w);
		}
		__mmask16 pinned = _mm512_cmp_ps_mask(w, zero, _CMP_EQ_OQ);
		uint64_t flags[2];
		memcpy(flags, p->flags + i, sizeof flags);
		__m512 vx, vy, vz, mx = zero, my = zero, mz = zero;
		if (!ending) {
			load_vec3x16(p->v + i, &vx, &vy, &vz);
		} else {
			__m512 px, py, pz;
			load_vec3x16(p->x_prev + i, &px, &py, &pz);
			mx = _mm512_mul_ps(_mm512_sub_ps(x, px), inverse_h);
			my = _mm512_mul_ps(_mm512_sub_ps(y, py), inverse_h);
			mz = _mm512_mul_ps(_mm512_sub_ps(z, pz), inverse_h);
			vx = _mm512_add_ps(mx, hx);
			vy = _mm512_add_ps(my, hy);
			vz = _mm512_add_ps(mz, hz);
		}
		if (ending && ((flags[0] | flags[1]) & contact_bits)) {
			/* Restitution and stickiness, lane by lane, against the velocity before. */
			_Alignas(64) float lx[16], ly[16], lz[16];
			_mm512_store_ps(lx, vx);
			_mm512_store_ps(ly, vy);
			_mm512_store_ps(lz, vz);
			for (int lane = 0; lane < 16; ++lane) {
				if ((p->flags[i + lane] & PLAIT_PARTICLE_CONTACT) && !(pinned & (1u << lane))) {
					vec3 v = plait_respond_to_collider_contact(
					    p, i + lane, p->v[i + lane], v3(lx[lane], ly[lane], lz[lane]), k->resting_speed);
					lx[lane] = v.x;
					ly[lane] = v.y;
					lz[lane] = v.z;
				}
			}
			vx = _mm512_load_ps(lx);
			vy = _mm512_load_ps(ly);
			vz = _mm512_load_ps(lz);
		}
		if (!beginning) {
			store_vec3x16(p->v + i, _mm512_mask_blend_ps(pinned, vx, mx),
			              _mm512_mask_blend_ps(pinned, vy, my), _mm512_mask_blend_ps(pinned, vz, mz));
			continue;
		}
		for (int half = 0; half < 2; ++half) {
			flags[half] = (flags[half] & kept_bits) | ((flags[half] & on_plane_bits) >> 1);
		}
		memcpy(p->flags + i, flags, sizeof flags);
		store_vec3x16(p->x_prev + i, x, y, z);
		__m512 factor = shared_factor;
		if (!k->damp_shared) {
			__m512i material = _mm512_loadu_si512((const void *)(p->material + i));
			factor = _mm512_i32gather_ps(_mm512_mullo_epi32(material, material_stride), damp_factor, 4);
		}
		vx = _mm512_mul_ps(_mm512_add_ps(vx, _mm512_mul_ps(h, gx)), factor);
		vy = _mm512_mul_ps(_mm512_add_ps(vy, _mm512_mul_ps(h, gy)), factor);
		vz = _mm512_mul_ps(_mm512_add_ps(vz, _mm512_mul_ps(h, gz)), factor);
		x = _mm512_add_ps(x, _mm512_mul_ps(h, _mm512_sub_ps(vx, hx)));
		y = _mm512_add_ps(y, _mm512_mul_ps(h, _mm512_sub_ps(vy, hy)));
		z = _mm512_add_ps(z, _mm512_mul_ps(h, _mm512_sub_ps(vz, hz)));
		/* A pinned particle keeps its velocity (the mean one, when the substep ended here) and
		 * goes to its target, in the same store (particle_avx2.c). */
		if (ending) {
			vx = _mm512_mask_blend_ps(pinned, vx, mx);
			vy = _mm512_mask_blend_ps(pinned, vy, my);
			vz = _mm512_mask_blend_ps(pinned, vz, mz);
		} else {
			__m512 ox, oy, oz;
			load_vec3x16(p->v + i, &ox, &oy, &oz);
			vx = _mm512_mask_blend_ps(pinned, vx, ox);
			vy = _mm512_mask_blend_ps(pinned, vy, oy);
			vz = _mm512_mask_blend_ps(pinned, vz, oz);
		}
		store_vec3x16(p->v + i, vx, vy, vz);
		if (pinned != 0) {
			_Alignas(64) float lx[16], ly[16], lz[16];
			_mm512_store_ps(lx, x);
			_mm512_store_ps(ly, y);
			_mm512_store_ps(lz, z);
			for (unsigned lanes = pinned; lanes != 0; lanes &= lanes - 1) {
				int lane = __builtin_ctz(lanes);
				vec3 target = v3_lerp(p->pin_start[i + lane], p->pin_end[i + lane], k->t_end);
				lx[lane] = target.x;
				ly[lane] = target.y;
				lz[lane] = target.z;
			}
			x = _mm512_load_ps(lx);
			y = _mm512_load_ps(ly);
			z = _mm512_load_ps(lz);
		}
		if (columns != NULL) {
			store_columns16(columns, i, x, y, z);
		} else {
			store_points16(p->point, i, x, y, z, w);
		}
	}
	for (; i < end; ++i) {
		/* The last few (fewer than 16) through the point array: the portable operations. */
		if (columns != NULL) {
			p->point[i] = plait_column_point(columns, i);
		}
		if (ending) {
			plait_end_particle(k, p, i);
		}
		if (beginning) {
			plait_begin_particle(k, p, i);
		}
		if (columns != NULL) {
			plait_column_set(columns, i, p->point[i].x);
		}
	}
	_mm256_zeroupper();
}

void plait_step_particles_avx512(const plait_particle_step *k, plait_particles *p, int begin, int end,
                                 bool ending, bool beginning)
{
	if (ending && beginning) {
		step_range(k, p, NULL, begin, end, true, true);
	} else if (ending) {
		step_range(k, p, NULL, begin, end, true, false);
	} else if (beginning) {
		step_range(k, p, NULL, begin, end, false, true);
	}
}

void plait_step_columns_avx512(const plait_particle_step *k, plait_particles *p, const plait_columns *columns,
                               int begin, int end, bool beginning)
{
	if (beginning) {
		step_range(k, p, columns, begin, end, true, true);
	} else {
		step_range(k, p, columns, begin, end, true, false);
	}
}
#endif
