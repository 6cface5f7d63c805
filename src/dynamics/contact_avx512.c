/* The collider cull in AVX-512 (contact_kernel.h): contact_avx2.c's test sixteen particles at a
 * time, the same operations lane by lane, so the same particles in the same order. Compiled with
 * -mavx512f; only called when the processor has AVX-512F. */
#include "dynamics/contact_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>
#include <string.h>

#include "dynamics/points_avx512.h"

static inline __attribute__((always_inline)) int cull(const plait_particles *p, const plait_columns *columns,
                                                      const plait_collider_bounds *bounds, int begin,
                                                      int count, int *near)
{
	const __m512 zero = _mm512_setzero_ps(), half = _mm512_set1_ps(0.5f);
	const __m512 lx = _mm512_set1_ps(bounds->lower.x), ly = _mm512_set1_ps(bounds->lower.y),
	             lz = _mm512_set1_ps(bounds->lower.z);
	const __m512 ux = _mm512_set1_ps(bounds->upper.x), uy = _mm512_set1_ps(bounds->upper.y),
	             uz = _mm512_set1_ps(bounds->upper.z);
	const __m512 cx = _mm512_set1_ps(bounds->ball_centre.x), cy = _mm512_set1_ps(bounds->ball_centre.y),
	             cz = _mm512_set1_ps(bounds->ball_centre.z);
	const __m512 ball_radius = _mm512_set1_ps(bounds->ball_radius);
	int n = 0;
	for (int k = 0; k + 16 <= count; k += 16) {
		int i = begin + k;
		uint64_t flags[2];
		memcpy(flags, p->flags + i, sizeof flags);
		if (((flags[0] | flags[1]) & (0x0101010101010101ull * PLAIT_PARTICLE_COLLIDE)) == 0) {
			continue;
		}
		__m512 bx, by, bz, w, ax, ay, az;
		if (columns != NULL) {
			load_columns16(columns, i, &bx, &by, &bz, &w);
		} else {
			load_points16(p->point, i, &bx, &by, &bz, &w);
		}
		load_vec3x16(p->x_prev + i, &ax, &ay, &az);
		/* path_may_reach, as contact_avx2.c. */
		__mmask16 in_box = (__mmask16)(_mm512_cmp_ps_mask(_mm512_max_ps(ax, bx), lx, _CMP_GE_OQ) &
		                               _mm512_cmp_ps_mask(_mm512_min_ps(ax, bx), ux, _CMP_LE_OQ) &
		                               _mm512_cmp_ps_mask(_mm512_max_ps(ay, by), ly, _CMP_GE_OQ) &
		                               _mm512_cmp_ps_mask(_mm512_min_ps(ay, by), uy, _CMP_LE_OQ) &
		                               _mm512_cmp_ps_mask(_mm512_max_ps(az, bz), lz, _CMP_GE_OQ) &
		                               _mm512_cmp_ps_mask(_mm512_min_ps(az, bz), uz, _CMP_LE_OQ));
		__m512 dx = _mm512_sub_ps(bx, ax), dy = _mm512_sub_ps(by, ay), dz = _mm512_sub_ps(bz, az);
		__m512 length = _mm512_sqrt_ps(_mm512_add_ps(
		    _mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz)));
		__m512 reach = _mm512_add_ps(ball_radius, _mm512_mul_ps(half, length));
		__m512 mx = _mm512_sub_ps(_mm512_mul_ps(_mm512_add_ps(ax, bx), half), cx);
		__m512 my = _mm512_sub_ps(_mm512_mul_ps(_mm512_add_ps(ay, by), half), cy);
		__m512 mz = _mm512_sub_ps(_mm512_mul_ps(_mm512_add_ps(az, bz), half), cz);
		__mmask16 in_ball = _mm512_cmp_ps_mask(
		    _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(mx, mx), _mm512_mul_ps(my, my)), _mm512_mul_ps(mz, mz)),
		    _mm512_mul_ps(reach, reach), _CMP_LE_OQ);
		unsigned keep = (unsigned)(in_box & in_ball & _mm512_cmp_ps_mask(w, zero, _CMP_NEQ_UQ));
		while (keep != 0) {
			int lane = __builtin_ctz(keep);
			keep &= keep - 1;
			if (p->flags[i + lane] & PLAIT_PARTICLE_COLLIDE) {
				near[n++] = i + lane;
			}
		}
	}
	return n;
}

int plait_cull_particles_avx512(const plait_particles *p, const plait_collider_bounds *bounds, int begin,
                                int count, int *near)
{
	int n = cull(p, NULL, bounds, begin, count, near);
	_mm256_zeroupper();
	return n;
}

int plait_cull_columns_avx512(const plait_particles *p, const plait_columns *columns,
                              const plait_collider_bounds *bounds, int begin, int count, int *near)
{
	int n = cull(p, columns, bounds, begin, count, near);
	_mm256_zeroupper();
	return n;
}
#endif
