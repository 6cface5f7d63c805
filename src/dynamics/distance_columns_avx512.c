/* The distance kernel on points as columns (x, y, z and w in arrays of their own), AVX-512F.
 *
 * The point kernel (distance_avx512.c) spends most of its time turning points into a register
 * per coordinate and back: four loads and a 4 x 4 transpose a side of each batch, and the same
 * on the way out, where a 512-bit shuffle takes two of Zen 4's shuffle slots. On columns a
 * batch whose points lie in runs (batch_layout.h) loads each coordinate whole, and the other
 * layouts need one in-lane swap a coordinate: about 0.4-0.7 ns a projection instead of 1.3
 * (RUNS) to 2.1 (PAIRS). Columns have no cheap gather, though (Zen 4's vgatherdps is slower
 * than the point kernel's transposes), so the solver only uses them when nearly every
 * constraint lies in a segment (colouring.c, choose_columns) and keeps the point array the
 * rest of the time (solver.c, "Columns").
 *
 * The lanes of a PAIRS or SKIP segment hold points, not constraints: both ends of each
 * constraint, each with the other's coordinates beside it (a swap inside each 128-bit block),
 * so both compute the constraint, each moving by its own difference to the other, as every
 * kernel moves each end (distance_kernel.h): x -= w s (x_other - x). That is symmetric in the two
 * ends, so a SHEAR segment's second constraint of each pair, whose ends swap rows, and a
 * constraint stored the other way round need nothing of their own, and d^2 and w_i + w_j are the
 * same bits from either end. Every value is the portable kernel's, operation for
 * operation. Compiled with -mavx512f (never with FMA contraction); only called when the
 * processor has AVX-512F. */
#include "dynamics/distance_kernel.h"

#if PLAIT_X86_KERNELS
#include <immintrin.h>
#include <math.h>

#include "dynamics/batch_layout.h"
#include "dynamics/colouring.h"
#include "dynamics/distance_columns.h"
#include "dynamics/points_avx512.h"

/* Swaps inside each 128-bit block: neighbours (PAIRS, SHEAR) and halves (SKIP). */
#define SWAP_NEIGHBOURS _MM_SHUFFLE(2, 3, 0, 1)
#define SWAP_HALVES _MM_SHUFFLE(1, 0, 3, 2)

/* The constraint of each lane, in a vector of a PAIRS or SKIP segment (add 8 for the second). */
#define PAIRS_LANES _mm512_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7)
#define SKIP_LANES _mm512_setr_epi32(0, 1, 0, 1, 2, 3, 2, 3, 4, 5, 4, 5, 6, 7, 6, 7)
/* Back: the lane (of two vectors, the second from 16) holding each constraint's first end. */
#define PAIRS_FIRSTS _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30)
#define SKIP_FIRSTS _mm512_setr_epi32(0, 1, 4, 5, 8, 9, 12, 13, 16, 17, 20, 21, 24, 25, 28, 29)

/* A constraint's values (rest length, compliances, multiplier) for the lanes of a vector. */
typedef struct lane_values {
	__m512 rest, tension, compression, lambda;
} lane_values;

static inline lane_values load_lane_values(const plait_distance_block *block, int c, __mmask16 constraints,
                                           bool rigid, bool spread, __m512i lanes)
{
	lane_values v;
	v.rest = _mm512_maskz_loadu_ps(constraints, block->rest + c);
	if (spread) {
		v.rest = _mm512_permutexvar_ps(lanes, v.rest);
	}
	if (!rigid) {
		v.tension = _mm512_maskz_loadu_ps(constraints, block->compliance_tension + c);
		v.compression = _mm512_maskz_loadu_ps(constraints, block->compliance_compression + c);
		v.lambda = _mm512_maskz_loadu_ps(constraints, block->lambda + c);
		if (spread) {
			v.tension = _mm512_permutexvar_ps(lanes, v.tension);
			v.compression = _mm512_permutexvar_ps(lanes, v.compression);
			v.lambda = _mm512_permutexvar_ps(lanes, v.lambda);
		}
	}
	return v;
}

/* The step of each lane as a quotient, before its division: s = numerator / denominator in the
 * lanes of `use` (zero elsewhere), and the lane's length for the multiplier (compliant blocks:
 * lambda += s length). distance_avx512.c's project16, operation for operation. */
typedef struct step_parts {
	__m512 numerator, denominator, length;
	__mmask16 use;
} step_parts;

static inline __attribute__((always_inline)) step_parts parts_of(__m512 dx, __m512 dy, __m512 dz,
                                                                 __m512 w_sum, __mmask16 update,
                                                                 const lane_values *v, __m512 ih2, bool rigid)
{
	const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
	step_parts parts;
	__m512 length_sq =
	    _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz));
	if (rigid) {
		__m512 rest_sq = _mm512_mul_ps(v->rest, v->rest);
		__m512 sum_sq = _mm512_max_ps(_mm512_add_ps(length_sq, rest_sq), _mm512_set1_ps(1e-24f));
		parts.use = _mm512_mask_cmp_ps_mask(update, w_sum, zero, _CMP_GT_OQ);
		parts.denominator = _mm512_mask_blend_ps(parts.use, one, _mm512_mul_ps(w_sum, sum_sq));
		parts.numerator = _mm512_sub_ps(rest_sq, length_sq);
		parts.length = zero;
		return parts;
	}
	__m512 length = _mm512_max_ps(_mm512_sqrt_ps(length_sq), _mm512_set1_ps(1e-12f));
	__m512 C = _mm512_sub_ps(length, v->rest);
	__mmask16 stretched = _mm512_cmp_ps_mask(C, zero, _CMP_GT_OQ);
	__m512 alpha = _mm512_mask_blend_ps(stretched, v->compression, v->tension);
	__mmask16 moving = _mm512_cmp_ps_mask(w_sum, zero, _CMP_GT_OQ);
	parts.use = _mm512_mask_cmp_ps_mask(moving & update, alpha, zero, _CMP_GE_OQ);
	__m512 alpha_tilde = _mm512_mul_ps(_mm512_max_ps(alpha, zero), ih2);
	__m512 denominator = _mm512_mul_ps(_mm512_add_ps(w_sum, alpha_tilde), length);
	parts.denominator = _mm512_mask_blend_ps(moving, one, denominator);
	parts.numerator =
	    _mm512_sub_ps(_mm512_sub_ps(_mm512_set1_ps(-0.0f), C), _mm512_mul_ps(alpha_tilde, v->lambda));
	parts.length = length;
	return parts;
}

/* RUNS (constraint k joins a + k and b + k) and SHEAR (constraint 2m joins a + 2m and
 * b1 + 2m + 1, constraint 2m + 1 joins b1 + 2m and a + 2m + 1: lane k holds a + k and, after a
 * swap, b1 + (k ^ 1)): constraint k in lane k. */
static inline __attribute__((always_inline)) void project_two_rows(plait_distance_block *block,
                                                                   const plait_columns *columns,
                                                                   const plait_segment *segment, int n,
                                                                   __m512 ih2, bool rigid, bool shear)
{
	int c = segment->start;
	__mmask16 constraints = (__mmask16)((1u << n) - 1u);
	uint32_t a = index_of(segment->a), b = index_of(segment->b);
	/* A shear segment's second row holds constraint k's point in lane k ^ 1. */
	__mmask16 second =
	    shear ? (__mmask16)(((constraints & 0x5555u) << 1) | ((constraints & 0xAAAAu) >> 1)) : constraints;
	__m512 xi = _mm512_maskz_loadu_ps(constraints, columns->x + a);
	__m512 yi = _mm512_maskz_loadu_ps(constraints, columns->y + a);
	__m512 zi = _mm512_maskz_loadu_ps(constraints, columns->z + a);
	__m512 wi = _mm512_maskz_loadu_ps(constraints, columns->w + a);
	__m512 xj = _mm512_maskz_loadu_ps(second, columns->x + b);
	__m512 yj = _mm512_maskz_loadu_ps(second, columns->y + b);
	__m512 zj = _mm512_maskz_loadu_ps(second, columns->z + b);
	__m512 wj = _mm512_maskz_loadu_ps(second, columns->w + b);
	if (shear) {
		xj = _mm512_permute_ps(xj, SWAP_NEIGHBOURS);
		yj = _mm512_permute_ps(yj, SWAP_NEIGHBOURS);
		zj = _mm512_permute_ps(zj, SWAP_NEIGHBOURS);
		wj = _mm512_permute_ps(wj, SWAP_NEIGHBOURS);
	}
	lane_values v = load_lane_values(block, c, constraints, rigid, false, _mm512_setzero_si512());
	__m512 dx = _mm512_sub_ps(xj, xi), dy = _mm512_sub_ps(yj, yi), dz = _mm512_sub_ps(zj, zi);
	step_parts parts = parts_of(dx, dy, dz, _mm512_add_ps(wi, wj), constraints, &v, ih2, rigid);
	__m512 s = _mm512_maskz_mov_ps(parts.use, _mm512_div_ps(parts.numerator, parts.denominator));
	if (!rigid) {
		_mm512_mask_storeu_ps(block->lambda + c, constraints,
		                      _mm512_add_ps(v.lambda, _mm512_mul_ps(s, parts.length)));
	}
	/* Each end moves by its own difference to the other (distance_kernel.h), so which row holds
	 * a constraint's first end does not matter. */
	__m512 si = _mm512_mul_ps(wi, s), sj = _mm512_mul_ps(wj, s);
	__m512 ex = _mm512_sub_ps(xi, xj), ey = _mm512_sub_ps(yi, yj), ez = _mm512_sub_ps(zi, zj);
	_mm512_mask_storeu_ps(columns->x + a, constraints, _mm512_sub_ps(xi, _mm512_mul_ps(si, dx)));
	_mm512_mask_storeu_ps(columns->y + a, constraints, _mm512_sub_ps(yi, _mm512_mul_ps(si, dy)));
	_mm512_mask_storeu_ps(columns->z + a, constraints, _mm512_sub_ps(zi, _mm512_mul_ps(si, dz)));
	xj = _mm512_sub_ps(xj, _mm512_mul_ps(sj, ex));
	yj = _mm512_sub_ps(yj, _mm512_mul_ps(sj, ey));
	zj = _mm512_sub_ps(zj, _mm512_mul_ps(sj, ez));
	if (shear) {
		xj = _mm512_permute_ps(xj, SWAP_NEIGHBOURS);
		yj = _mm512_permute_ps(yj, SWAP_NEIGHBOURS);
		zj = _mm512_permute_ps(zj, SWAP_NEIGHBOURS);
	}
	_mm512_mask_storeu_ps(columns->x + b, second, xj);
	_mm512_mask_storeu_ps(columns->y + b, second, yj);
	_mm512_mask_storeu_ps(columns->z + b, second, zj);
}

/* PAIRS (constraint k joins a + 2k and a + 2k + 1) and SKIP (constraint 2m joins a + 4m and
 * a + 4m + 2, constraint 2m + 1 joins a + 4m + 1 and a + 4m + 3): 16 consecutive points, 8
 * constraints, a vector; each lane computes its constraint with its partner's coordinates. The
 * two ends of a constraint hold the same quotient, so a segment of more than 8 (`vectors` 2)
 * packs its first ends' into one register and divides once (a division is the costliest step
 * here). */
static inline __attribute__((always_inline)) void
project_one_row(plait_distance_block *block, const plait_columns *columns, const plait_segment *segment,
                int n, __m512 ih2, bool rigid, bool skip, int vectors)
{
	int c = segment->start;
	__mmask16 constraints = (__mmask16)((1u << n) - 1u);
	uint32_t a = index_of(segment->a);
	__m512 px[2], py[2], pz[2], w[2], dx[2], dy[2], dz[2], lambda[2];
	__mmask16 update[2];
	__m512i spread[2];
	step_parts parts[2];
	for (int g = 0; g < vectors; ++g) {
		int here = n - 8 * g < 8 ? n - 8 * g : 8;
		/* The lanes of this vector's `here` constraints. */
		unsigned lanes;
		if (skip) {
			unsigned quads = (unsigned)here / 2;
			lanes = ((1u << (4 * quads)) - 1u) | (here % 2 != 0 ? 5u << (4 * quads) : 0u);
		} else {
			lanes = (1u << (2 * here)) - 1u;
		}
		update[g] = (__mmask16)lanes;
		uint32_t at = a + 16 * (uint32_t)g;
		px[g] = _mm512_maskz_loadu_ps(update[g], columns->x + at);
		py[g] = _mm512_maskz_loadu_ps(update[g], columns->y + at);
		pz[g] = _mm512_maskz_loadu_ps(update[g], columns->z + at);
		w[g] = _mm512_maskz_loadu_ps(update[g], columns->w + at);
		__m512 qx, qy, qz, qw;
		if (skip) {
			qx = _mm512_permute_ps(px[g], SWAP_HALVES);
			qy = _mm512_permute_ps(py[g], SWAP_HALVES);
			qz = _mm512_permute_ps(pz[g], SWAP_HALVES);
			qw = _mm512_permute_ps(w[g], SWAP_HALVES);
		} else {
			qx = _mm512_permute_ps(px[g], SWAP_NEIGHBOURS);
			qy = _mm512_permute_ps(py[g], SWAP_NEIGHBOURS);
			qz = _mm512_permute_ps(pz[g], SWAP_NEIGHBOURS);
			qw = _mm512_permute_ps(w[g], SWAP_NEIGHBOURS);
		}
		spread[g] = _mm512_add_epi32(skip ? SKIP_LANES : PAIRS_LANES, _mm512_set1_epi32(8 * g));
		lane_values v = load_lane_values(block, c, constraints, rigid, true, spread[g]);
		lambda[g] = rigid ? _mm512_setzero_ps() : v.lambda; /* (unused when rigid) */
		dx[g] = _mm512_sub_ps(qx, px[g]);
		dy[g] = _mm512_sub_ps(qy, py[g]);
		dz[g] = _mm512_sub_ps(qz, pz[g]);
		parts[g] = parts_of(dx[g], dy[g], dz[g], _mm512_add_ps(w[g], qw), update[g], &v, ih2, rigid);
	}
	const __m512i firsts = skip ? SKIP_FIRSTS : PAIRS_FIRSTS;
	__m512 quotients =
	    vectors == 1
	        ? _mm512_setzero_ps()
	        : _mm512_div_ps(_mm512_permutex2var_ps(parts[0].numerator, firsts, parts[1].numerator),
	                        _mm512_permutex2var_ps(parts[0].denominator, firsts, parts[1].denominator));
	for (int g = 0; g < vectors; ++g) {
		__m512 quotient = vectors == 1 ? _mm512_div_ps(parts[g].numerator, parts[g].denominator)
		                               : _mm512_permutexvar_ps(spread[g], quotients);
		__m512 s = _mm512_maskz_mov_ps(parts[g].use, quotient);
		lambda[g] = _mm512_add_ps(lambda[g], _mm512_mul_ps(s, parts[g].length));
		__m512 sw = _mm512_mul_ps(w[g], s);
		uint32_t at = a + 16 * (uint32_t)g;
		_mm512_mask_storeu_ps(columns->x + at, update[g], _mm512_sub_ps(px[g], _mm512_mul_ps(sw, dx[g])));
		_mm512_mask_storeu_ps(columns->y + at, update[g], _mm512_sub_ps(py[g], _mm512_mul_ps(sw, dy[g])));
		_mm512_mask_storeu_ps(columns->z + at, update[g], _mm512_sub_ps(pz[g], _mm512_mul_ps(sw, dz[g])));
	}
	if (!rigid) {
		__m512 second = vectors == 2 ? lambda[1] : _mm512_setzero_ps();
		_mm512_mask_storeu_ps(block->lambda + c, constraints,
		                      _mm512_permutex2var_ps(lambda[0], firsts, second));
	}
}

static inline __attribute__((always_inline)) void project_columns(plait_distance_block *block,
                                                                  const plait_columns *columns, int begin,
                                                                  int end, float inverse_h_squared,
                                                                  bool rigid)
{
	const __m512 ih2 = _mm512_set1_ps(inverse_h_squared);
	const plait_colouring *colouring = &block->colouring;
	int coloured = plait_colouring_end(colouring);
	int c = begin;
	if (colouring->segments != NULL && c < coloured) {
		int k = segment_at(colouring, c);
		/* A range cut through a segment: its constraints in the range one at a time. */
		int cut_end = colouring->segments[k].start + colouring->segments[k].length;
		if (colouring->segments[k].start < c) {
			for (; c < cut_end && c < end; ++c) {
				project_alone(block, columns, c, (uint32_t)block->pair[c][0], (uint32_t)block->pair[c][1],
				              inverse_h_squared, rigid);
			}
			++k;
		}
		for (; c < end && c < coloured; ++k) {
			const plait_segment *segment = &colouring->segments[k];
			int n = end - c < segment->length ? end - c : segment->length;
			switch ((plait_batch_layout)segment->layout) {
			case PLAIT_LAYOUT_RUNS:
				project_two_rows(block, columns, segment, n, ih2, rigid, false);
				break;
			case PLAIT_LAYOUT_SHEAR:
			case PLAIT_LAYOUT_SHEAR_FLIPPED:
				project_two_rows(block, columns, segment, n, ih2, rigid, true);
				break;
			/* One vector or two: each a constant, for a copy of its own with its loops unrolled. */
			case PLAIT_LAYOUT_PAIRS:
				if (n > 8) {
					project_one_row(block, columns, segment, n, ih2, rigid, false, 2);
				} else {
					project_one_row(block, columns, segment, n, ih2, rigid, false, 1);
				}
				break;
			case PLAIT_LAYOUT_SKIP:
				if (n > 8) {
					project_one_row(block, columns, segment, n, ih2, rigid, true, 2);
				} else {
					project_one_row(block, columns, segment, n, ih2, rigid, true, 1);
				}
				break;
			default: /* a constraint alone: its ends are a and b */
				project_alone(block, columns, c, index_of(segment->a), index_of(segment->b),
				              inverse_h_squared, rigid);
				break;
			}
			c += n;
		}
	}
	/* Without segments, or past the coloured constraints: one at a time. */
	for (; c < end; ++c) {
		project_alone(block, columns, c, (uint32_t)block->pair[c][0], (uint32_t)block->pair[c][1],
		              inverse_h_squared, rigid);
	}
}

void plait_project_distance_columns_avx512(plait_distance_block *block, const plait_columns *columns,
                                           int begin, int end, float inverse_h_squared)
{
	if (block->compliant_count == 0) {
		project_columns(block, columns, begin, end, inverse_h_squared, true);
	} else {
		project_columns(block, columns, begin, end, inverse_h_squared, false);
	}
	_mm256_zeroupper();
}

void plait_points_to_columns_avx512(const plait_point *points, const plait_columns *columns, int begin,
                                    int end)
{
	int i = begin;
	for (; i + 16 <= end; i += 16) {
		__m512 x, y, z, w;
		load_points16(points, i, &x, &y, &z, &w);
		_mm512_storeu_ps(columns->x + i, x);
		_mm512_storeu_ps(columns->y + i, y);
		_mm512_storeu_ps(columns->z + i, z);
		_mm512_storeu_ps(columns->w + i, w);
	}
	for (; i < end; ++i) {
		columns->x[i] = points[i].x.x;
		columns->y[i] = points[i].x.y;
		columns->z[i] = points[i].x.z;
		columns->w[i] = points[i].w;
	}
	_mm256_zeroupper();
}

void plait_points_from_columns_avx512(plait_point *points, const plait_columns *columns, int begin, int end)
{
	int i = begin;
	for (; i + 16 <= end; i += 16) {
		store_points16(points, i, _mm512_loadu_ps(columns->x + i), _mm512_loadu_ps(columns->y + i),
		               _mm512_loadu_ps(columns->z + i), _mm512_loadu_ps(columns->w + i));
	}
	for (; i < end; ++i) {
		points[i].x.x = columns->x[i];
		points[i].x.y = columns->y[i];
		points[i].x.z = columns->z[i];
		points[i].w = columns->w[i];
	}
	_mm256_zeroupper();
}
#endif
