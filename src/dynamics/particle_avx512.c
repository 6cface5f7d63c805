/* The end of one substep and the start of the next (particle_step.h) in AVX-512, sixteen
 * particles at a time: particle_avx2.c's pass lane for lane, the same operations in the same
 * order (the portable loop's bits), with masks for its selects. Compiled with -mavx512f (never
 * with FMA contraction); only called when the processor has AVX-512F. */
#include "dynamics/particle_step.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>
#include <string.h>

/* Sixteen vec3 (48 floats) into a register per coordinate: coordinate k of vector j is float
 * 3 j + k; the first 32 floats are picked from a and b, the rest from c. */
static inline void load_vec3x16(const vec3 *from, __m512 *x, __m512 *y, __m512 *z)
{
	const float *f = &from->x;
	__m512 a = _mm512_loadu_ps(f), b = _mm512_loadu_ps(f + 16), c = _mm512_loadu_ps(f + 32);
	const __m512i ab_x = _mm512_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21, 24, 27, 30, 0, 0, 0, 0, 0);
	const __m512i ab_y = _mm512_setr_epi32(1, 4, 7, 10, 13, 16, 19, 22, 25, 28, 31, 0, 0, 0, 0, 0);
	const __m512i ab_z = _mm512_setr_epi32(2, 5, 8, 11, 14, 17, 20, 23, 26, 29, 0, 0, 0, 0, 0, 0);
	const __m512i c_x = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 17, 20, 23, 26, 29);
	const __m512i c_y = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 18, 21, 24, 27, 30);
	const __m512i c_z = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 16, 19, 22, 25, 28, 31);
	*x = _mm512_permutex2var_ps(_mm512_permutex2var_ps(a, ab_x, b), c_x, c);
	*y = _mm512_permutex2var_ps(_mm512_permutex2var_ps(a, ab_y, b), c_y, c);
	*z = _mm512_permutex2var_ps(_mm512_permutex2var_ps(a, ab_z, b), c_z, c);
}

/* The inverse: float m of the 48 is coordinate m % 3 of vector m / 3. Each output register
 * picks from two coordinates first (indices 16 and up: the second), then the third. */
static inline void store_vec3x16(vec3 *to, __m512 x, __m512 y, __m512 z)
{
	float *f = &to->x;
	/* Floats 0-15: x0 y0 z0 x1 y1 z1 ... x5 (x and y from xy, z after). */
	const __m512i a_xy = _mm512_setr_epi32(0, 16, 0, 1, 17, 0, 2, 18, 0, 3, 19, 0, 4, 20, 0, 5);
	const __m512i a_z = _mm512_setr_epi32(0, 1, 16, 3, 4, 17, 6, 7, 18, 9, 10, 19, 12, 13, 20, 15);
	/* Floats 16-31: y5 z5 x6 y6 z6 ... x10 y10. */
	const __m512i b_xy = _mm512_setr_epi32(21, 0, 6, 22, 0, 7, 23, 0, 8, 24, 0, 9, 25, 0, 10, 26);
	const __m512i b_z = _mm512_setr_epi32(0, 21, 2, 3, 22, 5, 6, 23, 8, 9, 24, 11, 12, 25, 14, 15);
	/* Floats 32-47: z10 x11 y11 z11 ... x15 y15 z15. */
	const __m512i c_xy = _mm512_setr_epi32(0, 11, 27, 0, 12, 28, 0, 13, 29, 0, 14, 30, 0, 15, 31, 0);
	const __m512i c_z = _mm512_setr_epi32(26, 1, 2, 27, 4, 5, 28, 7, 8, 29, 10, 11, 30, 13, 14, 31);
	_mm512_storeu_ps(f, _mm512_permutex2var_ps(_mm512_permutex2var_ps(x, a_xy, y), a_z, z));
	_mm512_storeu_ps(f + 16, _mm512_permutex2var_ps(_mm512_permutex2var_ps(x, b_xy, y), b_z, z));
	_mm512_storeu_ps(f + 32, _mm512_permutex2var_ps(_mm512_permutex2var_ps(x, c_xy, y), c_z, z));
}

/* Points [i, i + 16) into a register per coordinate (a 4x4 transpose in each 128-bit block),
 * and back. */
static inline void load_points16(const plait_point *points, int i, __m512 *x, __m512 *y, __m512 *z, __m512 *w)
{
	__m512 r[4];
	for (int m = 0; m < 4; ++m) {
		__m512 v = _mm512_castps128_ps512(_mm_load_ps(&points[i + m].x.x));
		v = _mm512_insertf32x4(v, _mm_load_ps(&points[i + m + 4].x.x), 1);
		v = _mm512_insertf32x4(v, _mm_load_ps(&points[i + m + 8].x.x), 2);
		r[m] = _mm512_insertf32x4(v, _mm_load_ps(&points[i + m + 12].x.x), 3);
	}
	__m512 t0 = _mm512_unpacklo_ps(r[0], r[1]), t1 = _mm512_unpacklo_ps(r[2], r[3]);
	__m512 t2 = _mm512_unpackhi_ps(r[0], r[1]), t3 = _mm512_unpackhi_ps(r[2], r[3]);
	*x = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
	*y = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
	*z = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
	*w = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

static inline void store_points16(plait_point *points, int i, __m512 x, __m512 y, __m512 z, __m512 w)
{
	__m512 t0 = _mm512_unpacklo_ps(x, y), t1 = _mm512_unpacklo_ps(z, w);
	__m512 t2 = _mm512_unpackhi_ps(x, y), t3 = _mm512_unpackhi_ps(z, w);
	__m512 r[4] = {_mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0)),
	               _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2)),
	               _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0)),
	               _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2))};
	for (int m = 0; m < 4; ++m) {
		_mm_store_ps(&points[i + m].x.x, _mm512_castps512_ps128(r[m]));
		_mm_store_ps(&points[i + m + 4].x.x, _mm512_extractf32x4_ps(r[m], 1));
		_mm_store_ps(&points[i + m + 8].x.x, _mm512_extractf32x4_ps(r[m], 2));
		_mm_store_ps(&points[i + m + 12].x.x, _mm512_extractf32x4_ps(r[m], 3));
	}
}

static inline __attribute__((always_inline)) void step_range(const plait_particle_step *k, plait_particles *p,
                                                             int begin, int end, bool ending, bool beginning)
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
	const uint64_t contact_bits = 0x0101010101010101ull * PLAIT_PARTICLE_CONTACT;
	const uint64_t kept_bits =
	    0x0101010101010101ull *
	    (uint8_t) ~(PLAIT_PARTICLE_CONTACT | PLAIT_PARTICLE_SUPPORTED | PLAIT_PARTICLE_ON_PLANE);
	const uint64_t on_plane_bits = 0x0101010101010101ull * PLAIT_PARTICLE_ON_PLANE;
	int i = begin;
	for (; i + 16 <= end; i += 16) {
		__m512 x, y, z, w;
		load_points16(p->point, i, &x, &y, &z, &w);
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
		__m512i material = _mm512_loadu_si512((const void *)(p->material + i));
		__m512 factor = _mm512_i32gather_ps(_mm512_mullo_epi32(material, material_stride), damp_factor, 4);
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
		store_points16(p->point, i, x, y, z, w);
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

void plait_step_particles_avx512(const plait_particle_step *k, plait_particles *p, int begin, int end,
                                 bool ending, bool beginning)
{
	if (ending && beginning) {
		step_range(k, p, begin, end, true, true);
	} else if (ending) {
		step_range(k, p, begin, end, true, false);
	} else if (beginning) {
		step_range(k, p, begin, end, false, true);
	}
}
#endif
