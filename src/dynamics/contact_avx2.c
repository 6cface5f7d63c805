/* The collider cull in AVX2 (contact_kernel.h): eight particles at a time, their points and
 * x_prev loaded whole, the test of contact.c's path_may_reach in lanes, the particles kept
 * taken from the mask. Compiled with -mavx2; only called when the processor has AVX2. */
#include "dynamics/contact_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>
#include <string.h>

#include "dynamics/points_avx2.h"

int plait_cull_particles_avx2(const plait_particles *p, const plait_collider_bounds *bounds, int begin,
                              int count, int *near)
{
	const __m256 zero = _mm256_setzero_ps(), half = _mm256_set1_ps(0.5f);
	const __m256 lx = _mm256_set1_ps(bounds->lower.x), ly = _mm256_set1_ps(bounds->lower.y),
	             lz = _mm256_set1_ps(bounds->lower.z);
	const __m256 ux = _mm256_set1_ps(bounds->upper.x), uy = _mm256_set1_ps(bounds->upper.y),
	             uz = _mm256_set1_ps(bounds->upper.z);
	const __m256 cx = _mm256_set1_ps(bounds->ball_centre.x), cy = _mm256_set1_ps(bounds->ball_centre.y),
	             cz = _mm256_set1_ps(bounds->ball_centre.z);
	const __m256 ball_radius = _mm256_set1_ps(bounds->ball_radius);
	int n = 0;
	for (int k = 0; k + 8 <= count; k += 8) {
		int i = begin + k;
		uint64_t flags;
		memcpy(&flags, p->flags + i, sizeof flags);
		if ((flags & (0x0101010101010101ull * PLAIT_PARTICLE_COLLIDE)) == 0) {
			continue;
		}
		int index[8] = {i, i + 1, i + 2, i + 3, i + 4, i + 5, i + 6, i + 7};
		__m256 bx, by, bz, w;
		gather8(p->point, index, &bx, &by, &bz, &w);
		/* x_prev: 24 floats, as particle_avx2.c's load_vec3x8. */
		const float *f = &p->x_prev[i].x;
		__m256 a0 = _mm256_loadu_ps(f), a1 = _mm256_loadu_ps(f + 8), a2 = _mm256_loadu_ps(f + 16);
		__m256 ax = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x92), a2, 0x24),
		                                     _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
		__m256 ay = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x24), a2, 0x49),
		                                     _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6));
		__m256 az = _mm256_permutevar8x32_ps(_mm256_blend_ps(_mm256_blend_ps(a0, a1, 0x49), a2, 0x92),
		                                     _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
		/* path_may_reach: the path's box meets the bounds' box, and the ball around the path
		 * (its midpoint, half its length) reaches the bounds' ball. */
		__m256 in_box =
		    _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(_mm256_max_ps(ax, bx), lx, _CMP_GE_OQ),
		                                _mm256_cmp_ps(_mm256_min_ps(ax, bx), ux, _CMP_LE_OQ)),
		                  _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(_mm256_max_ps(ay, by), ly, _CMP_GE_OQ),
		                                              _mm256_cmp_ps(_mm256_min_ps(ay, by), uy, _CMP_LE_OQ)),
		                                _mm256_and_ps(_mm256_cmp_ps(_mm256_max_ps(az, bz), lz, _CMP_GE_OQ),
		                                              _mm256_cmp_ps(_mm256_min_ps(az, bz), uz, _CMP_LE_OQ))));
		__m256 dx = _mm256_sub_ps(bx, ax), dy = _mm256_sub_ps(by, ay), dz = _mm256_sub_ps(bz, az);
		__m256 length = _mm256_sqrt_ps(_mm256_add_ps(
		    _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz)));
		__m256 reach = _mm256_add_ps(ball_radius, _mm256_mul_ps(half, length));
		__m256 mx = _mm256_sub_ps(_mm256_mul_ps(_mm256_add_ps(ax, bx), half), cx);
		__m256 my = _mm256_sub_ps(_mm256_mul_ps(_mm256_add_ps(ay, by), half), cy);
		__m256 mz = _mm256_sub_ps(_mm256_mul_ps(_mm256_add_ps(az, bz), half), cz);
		__m256 in_ball = _mm256_cmp_ps(
		    _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(mx, mx), _mm256_mul_ps(my, my)), _mm256_mul_ps(mz, mz)),
		    _mm256_mul_ps(reach, reach), _CMP_LE_OQ);
		int keep = _mm256_movemask_ps(
		    _mm256_and_ps(_mm256_and_ps(in_box, in_ball), _mm256_cmp_ps(w, zero, _CMP_NEQ_UQ)));
		while (keep != 0) {
			int lane = __builtin_ctz((unsigned)keep);
			keep &= keep - 1;
			if (p->flags[i + lane] & PLAIT_PARTICLE_COLLIDE) {
				near[n++] = i + lane;
			}
		}
	}
	_mm256_zeroupper();
	return n;
}
#endif
