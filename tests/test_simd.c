/* The solver core's promises about how it runs: the portable, AVX2 and AVX-512 kernels give
 * the same bits; the sweep order (regions and coloured runs) never puts two constraints that
 * share a particle where they could run at once; and a whole simulation is byte-identical
 * whichever instruction set runs it. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "dynamics/batch_layout.h"
#include "dynamics/colouring.h"
#include "dynamics/bend_kernel.h"
#include "dynamics/distance_kernel.h"
#include "test_support.h"
#include "world/world.h"

static const plait_simd levels[] = {PLAIT_SIMD_SCALAR, PLAIT_SIMD_AVX2, PLAIT_SIMD_AVX512};

static uint32_t next_random(uint32_t *state)
{
	*state = *state * 1664525u + 1013904223u;
	return *state >> 8;
}

static float random_unit(uint32_t *state)
{
	return (float)next_random(state) / 16777216.0f;
}

/* A block of independent constraints (disjoint pairs) of every kind the kernel branches on:
 * stretched and compressed, soft and rigid, one-sided (no resistance one way), pinned ends,
 * both ends pinned, coincident points. Counts that are not multiples of 8 or 16 exercise the
 * masked and scalar remainders. A rigid block (every compliance zero) takes the kernels' path
 * without multipliers. */
static void make_block(plait_distance_block *block, plait_point *points, int count, uint32_t seed, bool rigid)
{
	uint32_t state = seed;
	block->count = block->capacity = count;
	block->pair = malloc(sizeof *block->pair * (size_t)count);
	block->point_offset = malloc(sizeof *block->point_offset * (size_t)count);
	block->rest = malloc(sizeof(float) * (size_t)count);
	block->compliance_tension = malloc(sizeof(float) * (size_t)count);
	block->compliance_compression = malloc(sizeof(float) * (size_t)count);
	block->lambda = malloc(sizeof(float) * (size_t)count);
	for (int c = 0; c < count; ++c) {
		block->pair[c][0] = 2 * c + 1;
		block->pair[c][1] = 2 * c;
		block->point_offset[c][0] = plait_point_offset(block->pair[c][0]);
		block->point_offset[c][1] = plait_point_offset(block->pair[c][1]);
		block->rest[c] = 0.01f + random_unit(&state);
		float alphas[4] = {0.0f, 1e-6f, 1e-3f, PLAIT_NO_RESISTANCE};
		block->compliance_tension[c] = rigid ? 0.0f : alphas[next_random(&state) % 4];
		block->compliance_compression[c] = rigid ? 0.0f : alphas[next_random(&state) % 4];
		block->lambda[c] = rigid ? 0.0f : random_unit(&state) - 0.5f;
		block->compliant_count +=
		    block->compliance_tension[c] != 0.0f || block->compliance_compression[c] != 0.0f;
	}
	for (int i = 0; i < 2 * count; ++i) {
		points[i].x =
		    (plait_vec3){random_unit(&state), random_unit(&state) - 0.5f, 2.0f * random_unit(&state)};
		uint32_t kind = next_random(&state) % 8;
		points[i].w = kind == 0 ? 0.0f : 0.5f + random_unit(&state);
	}
	points[6].x = points[7].x; /* a zero-length constraint */
	points[8].w = points[9].w = 0.0f;
}

static void free_block(plait_distance_block *block)
{
	free(block->pair);
	free(block->point_offset);
	free(block->rest);
	free(block->compliance_tension);
	free(block->compliance_compression);
	free(block->lambda);
}

typedef void block_maker(plait_distance_block *block, plait_point *points, int count, uint32_t seed,
                         bool rigid);

/* A column kernel's sweep of [begin, end), cut into ranges of `cut` constraints: most cuts
 * fall inside segments, which a range of a parallel loop may do. */
static void sweep_columns(plait_distance_block *block, const plait_columns *columns, int begin, int end,
                          int cut)
{
	for (int c = begin; c < end; c += cut) {
		columns->project(block, columns, c, c + cut < end ? c + cut : end, 3600.0f);
	}
}

/* A block of count constraints over point_count points from `make`, swept five times by every
 * kernel the processor runs (over [0, split) and then [split, count)), with the batch layouts
 * kept as colouring keeps them (the two ranges as its runs) and without (every batch gathered),
 * and by the column kernel on the segments found in those runs (the points copied into columns
 * and back), its ranges cut every 16 constraints and then every 7 (inside segments): each must
 * leave the portable kernel's positions and multipliers, bit for bit. */
static void check_kernels(block_maker *make, int count, int point_count, int split, uint32_t seed, bool rigid)
{
	plait_point *reference = malloc(sizeof *reference * (size_t)point_count);
	float *reference_lambda = malloc(sizeof(float) * (size_t)count);
	/* Passes 0-5: each level, without and with kept layouts; 6-7: the column kernel, cut every 16
	 * and every 7; 8: the column kernel without segments (every constraint alone). */
	for (int pass = 0; pass < 2 * 3 + 3; ++pass) {
		int l = pass < 6 ? pass / 2 : 2;
		bool keep_layouts = pass % 2 == 1, columns = pass >= 6;
		if (!plait_simd_supported(levels[l])) {
			cr_log_info("simd level %d not supported here: skipped", (int)levels[l]);
			continue;
		}
		plait_distance_block block;
		memset(&block, 0, sizeof block);
		// aligned_alloc wants a size that is a multiple of the alignment (ASan enforces it).
		size_t bytes = (sizeof(plait_point) * (size_t)point_count + 63) / 64 * 64;
		plait_point *points = aligned_alloc(64, bytes);
		memset(points, 0, bytes); /* points the maker leaves alone compare equal */
		make(&block, points, count, seed, rigid);
		cr_assert_eq(block.compliant_count == 0, rigid);
		int run_start[3] = {0, split, count}, region_start[2] = {0, 2};
		unsigned char *layouts = calloc((size_t)count, 1);
		plait_segment *segments = calloc((size_t)count, sizeof *segments);
		if (keep_layouts || columns) {
			block.colouring = (plait_colouring){1, 2, region_start, run_start, NULL, NULL, 0, 0, NULL};
			plait_find_batch_layouts(&block, layouts);
			block.colouring.batch_layout = layouts;
			block.colouring.segment_count = plait_find_segments(&block, segments);
			block.colouring.segments = segments;
			if (pass == 8) {
				block.colouring.segment_count = 0;
				block.colouring.segments = NULL;
			}
		}
		if (columns) {
			plait_column_ops ops = plait_column_ops_for(levels[l]);
			cr_assert(ops.project != NULL && ops.to_columns != NULL && ops.from_columns != NULL);
			float *column = aligned_alloc(64, (sizeof(float) * 4 * (size_t)point_count + 63) / 64 * 64);
			plait_columns as_columns = {column, column + point_count, column + 2 * point_count,
			                            column + 3 * point_count, ops.project};
			ops.to_columns(points, &as_columns, 0, point_count);
			memset(points, 0xff, sizeof *points * (size_t)point_count); /* all back from the columns */
			for (int sweep = 0; sweep < 5; ++sweep) {
				sweep_columns(&block, &as_columns, 0, split, pass % 2 == 0 ? 16 : 7);
				sweep_columns(&block, &as_columns, split, count, pass % 2 == 0 ? 16 : 7);
			}
			ops.from_columns(points, &as_columns, 0, point_count);
			free(column);
		} else {
			plait_distance_kernel *kernel = plait_distance_kernel_for(levels[l]);
			for (int sweep = 0; sweep < 5; ++sweep) {
				kernel(&block, points, 0, split, 3600.0f);
				kernel(&block, points, split, count, 3600.0f);
			}
		}
		for (int i = 0; i < point_count; ++i) {
			cr_assert(isfinite(points[i].x.x) && isfinite(points[i].x.y) && isfinite(points[i].x.z));
		}
		if (pass == 0) {
			memcpy(reference, points, sizeof *reference * (size_t)point_count);
			memcpy(reference_lambda, block.lambda, sizeof(float) * (size_t)count);
		} else {
			for (int i = 0; i < point_count; ++i) {
				cr_assert(memcmp(&reference[i], &points[i], sizeof *points) == 0,
				          "level %d (layouts kept %d, columns %d) differs from the portable kernel at point "
				          "%d of %d constraints (rigid %d)",
				          (int)levels[l], (int)keep_layouts, (int)columns, i, count, (int)rigid);
			}
			cr_assert(memcmp(reference_lambda, block.lambda, sizeof(float) * (size_t)count) == 0,
			          "level %d (layouts kept %d, columns %d) multipliers differ at %d constraints",
			          (int)levels[l], (int)keep_layouts, (int)columns, count);
		}
		free(layouts);
		free(segments);
		free_block(&block);
		free(points);
	}
	free(reference);
	free(reference_lambda);
}

Test(simd, every_kernel_gives_the_bits_of_the_portable_one)
{
	int counts[] = {1, 7, 8, 15, 16, 17, 33, 1000};
	for (size_t n = 0; n < 2 * sizeof counts / sizeof counts[0]; ++n) {
		int count = counts[n / 2];
		/* make_block sets points 6 to 9 whatever the count: room for 16 more. */
		check_kernels(make_block, count, 2 * count + 16, 0, 12345u + (uint32_t)count, n % 2 == 1);
	}
}

/* Batches laid out as a grid cloth's colour runs often are, which the vector kernels move with
 * full-width loads and stores (batch_layout.h): each 16 constraints a region of points of its
 * own, starting anywhere (not on a 64-byte line), taking in turn the four layouts (the first three
 * with their second run below their first or above it), a shuffled batch, and each layout but for
 * one lane (its first or second point moved to a free point of the region):
 *   runs: constraint k joins a + k and b + k;
 *   neighbours: a + 2k and a + 2k + 1;
 *   diagonals: 2m joins a + 2m and b + 2m + 1, 2m + 1 joins b + 2m and a + 2m + 1;
 *   skip-one: 2m joins a + 4m and a + 4m + 2, 2m + 1 joins a + 4m + 1 and a + 4m + 3.
 * One constraint of each batch has coincident ends and another both ends pinned. The count
 * leaves a tail batch and a remainder. */
enum { LAYOUT_KINDS = 12, REGION_POINTS = 70 };

static void layout_pair(int kind, int k, int base, int *i, int *j)
{
	int m = k / 2;
	bool low_second = kind % 2 == 1; /* the second run below the first */
	int a = low_second ? base + 34 : base, b = low_second ? base : base + 34;
	switch (kind) {
	case 0:
	case 1:
	case 6: /* runs; 6: lane 15's second point moved */
		*i = a + k;
		*j = kind == 6 && k == 15 ? base + 66 : b + k;
		break;
	case 2:
	case 3:
	case 7: /* neighbours; 7: lane 7's second point moved */
		*i = base + 2 * k;
		*j = kind == 7 && k == 7 ? base + 66 : base + 2 * k + 1;
		break;
	case 4:
	case 5:
	case 8: /* diagonals; 8: lane 10's first point moved */
		*i = k % 2 == 0 ? a + 2 * m : b + 2 * m;
		*j = k % 2 == 0 ? b + 2 * m + 1 : a + 2 * m + 1;
		if (kind == 8 && k == 10) {
			*i = base + 67;
		}
		break;
	case 10:
	case 11: /* skip-one; 11: lane 5's second point moved */
		*i = base + 4 * m + k % 2;
		*j = kind == 11 && k == 5 ? base + 66 : *i + 2;
		break;
	default: /* shuffled: constraint k joins points 2k and 2k + 1 of a permutation */
		*i = base + (int)((7u * (uint32_t)(2 * k) + 3u) % 32u);
		*j = base + (int)((7u * (uint32_t)(2 * k + 1) + 3u) % 32u);
		break;
	}
}

/* FILLERS constraints first, in points of their own after the regions: the kernels run over
 * them and then over the batches, which so start off a multiple of 16 in the block, as a colour
 * run's do. */
enum { FILLERS = 5 };

static int layout_point_count(int count)
{
	return REGION_POINTS * ((count - FILLERS + 15) / 16) + 2 * FILLERS;
}

static void make_layout_block(plait_distance_block *block, plait_point *points, int count, uint32_t seed,
                              bool rigid)
{
	make_block(block, points, count, seed, rigid);
	uint32_t state = seed ^ 0x9e3779b9u;
	int point_count = layout_point_count(count);
	for (int i = 0; i < point_count; ++i) {
		points[i].x =
		    (plait_vec3){random_unit(&state), random_unit(&state) - 0.5f, 2.0f * random_unit(&state)};
		points[i].w = next_random(&state) % 8 == 0 ? 0.0f : 0.5f + random_unit(&state);
	}
	for (int c = 0; c < count; ++c) {
		int i, j;
		if (c < FILLERS) {
			i = point_count - 2 * FILLERS + 2 * c + 1;
			j = point_count - 2 * FILLERS + 2 * c;
		} else {
			int batch = (c - FILLERS) / 16, k = (c - FILLERS) % 16;
			layout_pair(batch % LAYOUT_KINDS, k, REGION_POINTS * batch + batch % 3, &i, &j);
			if (k == 3) {
				points[j].x = points[i].x; /* coincident ends */
			} else if (k == 12) {
				points[i].w = points[j].w = 0.0f; /* both ends pinned */
			}
		}
		block->pair[c][0] = i;
		block->pair[c][1] = j;
		block->point_offset[c][0] = plait_point_offset(i);
		block->point_offset[c][1] = plait_point_offset(j);
	}
}

Test(simd, batches_in_runs_of_points_give_the_bits_of_the_portable_kernel)
{
	int counts[] = {FILLERS + 16 * LAYOUT_KINDS, FILLERS + 16 * 2 * LAYOUT_KINDS + 7};
	for (size_t n = 0; n < 2 * sizeof counts / sizeof counts[0]; ++n) {
		int count = counts[n / 2];
		check_kernels(make_layout_block, count, layout_point_count(count), FILLERS, 777u + (uint32_t)count,
		              n % 2 == 1);
	}
}

/* make_layout_block's batches with every third constraint turned the other way round (its
 * points swapped: segments still find it, the point kernels then gather its batch), and points
 * at -0 at both ends of some constraints, each in one coordinate: there d is +0 from either end,
 * and a kernel that negated d for the second end instead of working it as the portable kernel
 * does would turn -0 into +0 where that one keeps it, or the other way. */
static void make_turned_layout_block(plait_distance_block *block, plait_point *points, int count,
                                     uint32_t seed, bool rigid)
{
	make_layout_block(block, points, count, seed, rigid);
	for (int c = FILLERS; c < count; ++c) {
		int k = (c - FILLERS) % 16, i = block->pair[c][0], j = block->pair[c][1];
		if (k == 5 || k == 10) {
			points[i].x.x = points[j].x.x = -0.0f;
		} else if (k == 6 || k == 13) {
			points[i].x.y = points[j].x.y = -0.0f;
		}
		if (c % 3 == 1) {
			block->pair[c][0] = j;
			block->pair[c][1] = i;
			uint32_t first = block->point_offset[c][0];
			block->point_offset[c][0] = block->point_offset[c][1];
			block->point_offset[c][1] = first;
		}
	}
}

Test(simd, constraints_either_way_round_and_points_at_minus_zero_give_the_bits_of_the_portable_kernel)
{
	int counts[] = {FILLERS + 16 * LAYOUT_KINDS, FILLERS + 16 * 2 * LAYOUT_KINDS + 7};
	for (size_t n = 0; n < 2 * sizeof counts / sizeof counts[0]; ++n) {
		int count = counts[n / 2];
		check_kernels(make_turned_layout_block, count, layout_point_count(count), FILLERS,
		              4242u + (uint32_t)count, n % 2 == 1);
	}
}

/* The layouts found for make_layout_block's batches are the ones it laid out: whole for 16
 * lanes, and for each half of 8 (the moved lane spoils only its own half). */
Test(simd, each_batch_is_found_in_the_layout_it_was_laid_out_in)
{
	const plait_batch_layout whole[LAYOUT_KINDS] = {
	    PLAIT_LAYOUT_RUNS,   PLAIT_LAYOUT_RUNS,   PLAIT_LAYOUT_PAIRS,  PLAIT_LAYOUT_PAIRS,
	    PLAIT_LAYOUT_SHEAR,  PLAIT_LAYOUT_SHEAR,  PLAIT_LAYOUT_GATHER, PLAIT_LAYOUT_GATHER,
	    PLAIT_LAYOUT_GATHER, PLAIT_LAYOUT_GATHER, PLAIT_LAYOUT_SKIP,   PLAIT_LAYOUT_GATHER};
	/* Kinds 6, 7, 8 and 11 move a point of lane 15, 7, 10 and 5. */
	const plait_batch_layout halves[LAYOUT_KINDS][2] = {
	    {PLAIT_LAYOUT_RUNS, PLAIT_LAYOUT_RUNS},    {PLAIT_LAYOUT_RUNS, PLAIT_LAYOUT_RUNS},
	    {PLAIT_LAYOUT_PAIRS, PLAIT_LAYOUT_PAIRS},  {PLAIT_LAYOUT_PAIRS, PLAIT_LAYOUT_PAIRS},
	    {PLAIT_LAYOUT_SHEAR, PLAIT_LAYOUT_SHEAR},  {PLAIT_LAYOUT_SHEAR, PLAIT_LAYOUT_SHEAR},
	    {PLAIT_LAYOUT_RUNS, PLAIT_LAYOUT_GATHER},  {PLAIT_LAYOUT_GATHER, PLAIT_LAYOUT_PAIRS},
	    {PLAIT_LAYOUT_SHEAR, PLAIT_LAYOUT_GATHER}, {PLAIT_LAYOUT_GATHER, PLAIT_LAYOUT_GATHER},
	    {PLAIT_LAYOUT_SKIP, PLAIT_LAYOUT_SKIP},    {PLAIT_LAYOUT_GATHER, PLAIT_LAYOUT_SKIP}};
	int count = FILLERS + 16 * LAYOUT_KINDS;
	plait_distance_block block;
	memset(&block, 0, sizeof block);
	plait_point *points = calloc((size_t)layout_point_count(count), sizeof *points);
	make_layout_block(&block, points, count, 5u, false);
	for (int batch = 0; batch < LAYOUT_KINDS; ++batch) {
		const uint32_t *offset = block.point_offset[FILLERS + 16 * batch];
		cr_assert_eq(plait_batch_layout_of(offset, 16), whole[batch], "batch %d", batch);
		cr_assert_eq(plait_batch_layout_of(offset, 8), halves[batch][0], "batch %d, first half", batch);
		cr_assert_eq(plait_batch_layout_of(offset + 16, 8), halves[batch][1], "batch %d, second half", batch);
	}
	/* Kept per position: batches start a multiple of 16 (8) after their run's start. */
	int run_start[3] = {0, FILLERS, count}, region_start[2] = {0, 2};
	block.colouring = (plait_colouring){1, 2, region_start, run_start, NULL, NULL, 0, 0, NULL};
	unsigned char *kept = malloc((size_t)count);
	memset(kept, 0xff, (size_t)count);
	plait_find_batch_layouts(&block, kept);
	for (int c = 0; c < count; ++c) {
		int k = c - FILLERS;
		plait_batch_layout expect16 = k >= 0 && k % 16 == 0 ? whole[k / 16] : PLAIT_LAYOUT_GATHER;
		plait_batch_layout expect8 = k >= 0 && k % 8 == 0 ? halves[k / 16][k % 16 / 8] : PLAIT_LAYOUT_GATHER;
		cr_assert_eq(plait_layout16(kept[c]), expect16, "position %d", c);
		cr_assert_eq(plait_layout8(kept[c]), expect8, "position %d", c);
	}
	free(kept);
	free_block(&block);
	free(points);
}

/* The segments found in make_layout_block's batches (after its FILLERS constraints, in a run
 * of their own): a whole batch where it was laid out, and around a moved lane the longest
 * prefixes that still lie in a layout, the constraints between alone; a shuffled batch's
 * constraints all alone. With every constraint turned the other way round, the same segments. */
Test(simd, segments_are_found_in_the_layouts_they_lie_in)
{
	/* Per kind: the lengths of its segments and their layout (G: alone). */
	enum { R = PLAIT_LAYOUT_RUNS, P = PLAIT_LAYOUT_PAIRS, S = PLAIT_LAYOUT_SHEAR, K = PLAIT_LAYOUT_SKIP };
	enum { G = PLAIT_LAYOUT_GATHER };
	const int lengths[LAYOUT_KINDS][17] = {
	    {16}, {16},      {16},      {16},          {16},
	    {16}, {15, 1},   {7, 1, 8}, {10, 1, 1, 4}, {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1},
	    {16}, {5, 1, 10}};
	const int layouts[LAYOUT_KINDS][17] = {
	    {R}, {R},      {P},       {P},          {S},
	    {S}, {R, G},   {P, G, P}, {S, G, G, S}, {G, G, G, G, G, G, G, G, G, G, G, G, G, G, G, G},
	    {K}, {K, G, K}};
	int count = FILLERS + 16 * LAYOUT_KINDS;
	for (int flip = 0; flip < 2; ++flip) {
		plait_distance_block block;
		memset(&block, 0, sizeof block);
		plait_point *points = calloc((size_t)layout_point_count(count), sizeof *points);
		make_layout_block(&block, points, count, 5u, false);
		for (int c = 0; flip && c < count; ++c) {
			uint32_t first = block.point_offset[c][0];
			block.point_offset[c][0] = block.point_offset[c][1];
			block.point_offset[c][1] = first;
		}
		int run_start[3] = {0, FILLERS, count}, region_start[2] = {0, 2};
		block.colouring = (plait_colouring){1, 2, region_start, run_start, NULL, NULL, 0, 0, NULL};
		plait_segment *segments = calloc((size_t)count, sizeof *segments);
		int found = plait_find_segments(&block, segments);
		cr_assert_eq(plait_find_segments(&block, NULL), found);
		/* The fillers join points 2 f + 1 and 2 f: neighbours the other way round. */
		cr_assert(segments[0].start == 0 && segments[0].length == FILLERS && segments[0].layout == P);
		int k = 1, c = FILLERS;
		for (int batch = 0; batch < LAYOUT_KINDS; ++batch) {
			for (int m = 0; m < 17 && lengths[batch][m] > 0; ++m, ++k) {
				cr_assert(k < found);
				cr_assert_eq(segments[k].start, c, "flip %d, batch %d, segment %d", flip, batch, m);
				cr_assert_eq(segments[k].length, lengths[batch][m], "flip %d, batch %d, segment %d", flip,
				             batch, m);
				cr_assert_eq(segments[k].layout == PLAIT_LAYOUT_SHEAR_FLIPPED ? S : segments[k].layout,
				             layouts[batch][m], "flip %d, batch %d, segment %d", flip, batch, m);
				c += segments[k].length;
			}
		}
		cr_assert_eq(found, k);
		cr_assert_eq(c, count);
		free(segments);
		free_block(&block);
		free(points);
	}
}

/* A grid cloth is projected on columns with AVX-512 (its segments hold about 14 constraints);
 * with AVX2 or the portable kernel it is not, nor is a cloth whose vertices are numbered at
 * random (its constraints lie in no layout). */
Test(simd, a_grid_cloth_is_projected_on_columns_and_a_scrambled_one_is_not)
{
	for (int scrambled = 0; scrambled < 2; ++scrambled) {
		for (int l = 0; l < 3; ++l) {
			if (!plait_simd_is_supported(levels[l])) {
				continue;
			}
			plait_world_def wdef = plait_default_world_def();
			wdef.simd = levels[l];
			plait_world_id world = plait_create_world(&wdef, NULL);
			test_grid grid = test_grid_make(64, 64, 2.0f, 2.0f);
			if (scrambled) {
				/* Vertex v becomes (v * 2654435761) mod n, n = 65 x 65: the multiplier is a prime
				 * that does not divide n, so a permutation (in 64 bits: modulo 2^32 first it was
				 * not, and left vertices unwritten, which made the test fail at random). */
				int n = grid.vertex_count;
				plait_vec3 *moved = malloc(sizeof *moved * (size_t)n);
				for (int v = 0; v < n; ++v) {
					moved[(int)(((uint64_t)v * 2654435761u) % (uint64_t)n)] = grid.positions[v];
				}
				memcpy(grid.positions, moved, sizeof *moved * (size_t)n);
				free(moved);
				int corners = 0;
				for (int f = 0; f < grid.face_count; ++f) {
					corners += grid.face_sizes[f];
				}
				for (int k = 0; k < corners; ++k) {
					grid.face_indices[k] =
					    (int)(((uint64_t)grid.face_indices[k] * 2654435761u) % (uint64_t)n);
				}
			}
			plait_cloth_def def = plait_default_cloth_def();
			def.mesh = test_grid_mesh(&grid);
			def.bend_model = PLAIT_BEND_DISTANCE;
			cr_assert(!plait_object_id_is_null(plait_create_cloth(world, &def, NULL)));
			cr_assert(test_step_frames(world, 1));
			const plait_sim *sim = &world.world->sim;
			bool expected = !scrambled && levels[l] == PLAIT_SIMD_AVX512;
			cr_assert_eq(sim->use_columns, expected, "level %d, scrambled %d", (int)levels[l], scrambled);
			cr_assert(!sim->in_columns, "a step ends with the points in the point array");
			plait_destroy_world(world);
			test_grid_free(&grid);
		}
	}
}

/* Once coloured, a grid cloth's distance blocks keep the layout of each batch that starts a
 * multiple of 16 (8) after its run's start and ends in it, as plait_batch_layout_of finds it, and
 * gathered elsewhere; and most of each block's batches (68-78% at 128 x 128) are kept in a layout
 * of runs. */
Test(simd, a_coloured_cloth_keeps_the_layouts_of_its_batches)
{
	plait_world_def wdef = plait_default_world_def();
	plait_world_id world = plait_create_world(&wdef, NULL);
	test_grid grid = test_grid_make(128, 128, 2.0f, 2.0f);
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	def.bend_model = PLAIT_BEND_DISTANCE;
	cr_assert(!plait_object_id_is_null(plait_create_cloth(world, &def, NULL)));
	cr_assert(test_step_frames(world, 1));
	plait_sim *sim = &world.world->sim;
	plait_distance_block *blocks[3] = {&sim->stretch, &sim->shear, &sim->bend_distance};
	for (int b = 0; b < 3; ++b) {
		const plait_colouring *colouring = &blocks[b]->colouring;
		cr_assert(colouring->run_count > 0 && colouring->batch_layout != NULL, "block %d", b);
		int batches = 0, laid_out = 0;
		for (int run = 0; run < colouring->run_count; ++run) {
			int begin = colouring->run_start[run], end = colouring->run_start[run + 1];
			for (int c = begin; c < end; ++c) {
				const uint32_t *offset = blocks[b]->point_offset[c];
				bool whole = (c - begin) % 16 == 0 && c + 16 <= end,
				     half = (c - begin) % 8 == 0 && c + 8 <= end;
				plait_batch_layout expect16 = whole ? plait_batch_layout_of(offset, 16) : PLAIT_LAYOUT_GATHER;
				plait_batch_layout expect8 = half ? plait_batch_layout_of(offset, 8) : PLAIT_LAYOUT_GATHER;
				cr_assert_eq(plait_layout16(colouring->batch_layout[c]), expect16, "block %d, position %d", b,
				             c);
				cr_assert_eq(plait_layout8(colouring->batch_layout[c]), expect8, "block %d, position %d", b,
				             c);
				batches += whole;
				laid_out += expect16 != PLAIT_LAYOUT_GATHER;
			}
		}
		cr_log_info("block %d: %d of %d batches of 16 laid out", b, laid_out, batches);
		cr_assert(laid_out * 10 > batches * 6, "block %d: %d of %d batches laid out", b, laid_out, batches);
	}
	plait_destroy_world(world);
	test_grid_free(&grid);
}

/* Hinges with disjoint corners, folded at random angles, some pinned, one degenerate (its
 * wing on the hinge line): the AVX2 bend kernel gives the portable one's bits. */
Test(simd, the_bend_kernels_agree_bit_for_bit)
{
	int counts[] = {1, 5, 8, 9, 23, 300};
	for (size_t n = 0; n < sizeof counts / sizeof counts[0]; ++n) {
		int count = counts[n];
		plait_point *reference = NULL;
		float *reference_lambda = NULL;
		for (int l = 0; l < 3; ++l) {
			if (!plait_simd_supported(levels[l])) {
				continue;
			}
			uint32_t state = 777u + (uint32_t)count;
			plait_bend_block block;
			memset(&block, 0, sizeof block);
			block.count = block.capacity = count;
			block.quad = malloc(sizeof *block.quad * (size_t)count);
			block.rest_angle = malloc(sizeof(float) * (size_t)count);
			block.compliance = malloc(sizeof(float) * (size_t)count);
			block.lambda = malloc(sizeof(float) * (size_t)count);
			size_t bytes = (sizeof(plait_point) * (size_t)(4 * count) + 63) / 64 * 64;
			plait_point *points = aligned_alloc(64, bytes);
			for (int c = 0; c < count; ++c) {
				for (int k = 0; k < 4; ++k) {
					block.quad[c][k] = 4 * c + (k + c) % 4;
				}
				block.rest_angle[c] = 2.0f * random_unit(&state) - 1.0f;
				block.compliance[c] = (next_random(&state) % 2) ? 0.0f : 1e-4f;
				block.lambda[c] = random_unit(&state) - 0.5f;
				for (int k = 0; k < 4; ++k) {
					points[4 * c + k].x =
					    (plait_vec3){random_unit(&state), random_unit(&state), random_unit(&state)};
					points[4 * c + k].w = next_random(&state) % 6 == 0 ? 0.0f : 1.0f + random_unit(&state);
				}
			}
			/* A wing on the hinge line: a degenerate hinge, left alone. */
			points[block.quad[0][2]].x = points[block.quad[0][0]].x;
			plait_bend_kernel *kernel = plait_bend_kernel_for(levels[l]);
			for (int sweep = 0; sweep < 4; ++sweep) {
				kernel(&block, points, 0, count, 3600.0f);
			}
			if (reference == NULL) {
				reference = malloc(bytes);
				reference_lambda = malloc(sizeof(float) * (size_t)count);
				memcpy(reference, points, sizeof *points * (size_t)(4 * count));
				memcpy(reference_lambda, block.lambda, sizeof(float) * (size_t)count);
			} else {
				cr_assert(memcmp(reference, points, sizeof *points * (size_t)(4 * count)) == 0,
				          "bend: level %d differs from the portable kernel at %d hinges", (int)levels[l],
				          count);
				cr_assert(memcmp(reference_lambda, block.lambda, sizeof(float) * (size_t)count) == 0);
			}
			free(block.quad);
			free(block.rest_angle);
			free(block.compliance);
			free(block.lambda);
			free(points);
		}
		free(reference);
		free(reference_lambda);
	}
}

/* Every run holds constraints that share no particle, regions share no particle, and the order
 * is a permutation. */
static void check_colouring(const int *vertices, int arity, int count, int particle_count)
{
	plait_allocator allocator = {NULL, NULL, NULL};
	int *order = malloc(sizeof(int) * (size_t)count);
	plait_colouring colouring;
	cr_assert(
	    plait_colour_constraints(&allocator, vertices, arity, count, particle_count, order, &colouring));
	cr_assert_eq(plait_colouring_end(&colouring), count);
	int *seen = calloc((size_t)count, sizeof(int));
	for (int k = 0; k < count; ++k) {
		cr_assert(order[k] >= 0 && order[k] < count && seen[order[k]] == 0);
		seen[order[k]] = 1;
	}
	int *stamp = malloc(sizeof(int) * (size_t)particle_count);
	int *owner = malloc(sizeof(int) * (size_t)particle_count);
	for (int i = 0; i < particle_count; ++i) {
		stamp[i] = -1;
		owner[i] = -1;
	}
	for (int run = 0; run < colouring.run_count; ++run) {
		for (int k = colouring.run_start[run]; k < colouring.run_start[run + 1]; ++k) {
			const int *tuple = vertices + (size_t)order[k] * (size_t)arity;
			for (int a = 0; a < arity; ++a) {
				cr_assert_neq(stamp[tuple[a]], run, "run %d uses particle %d twice", run, tuple[a]);
				stamp[tuple[a]] = run;
			}
		}
	}
	for (int r = 0; r < colouring.region_count; ++r) {
		for (int run = colouring.region_start[r]; run < colouring.region_start[r + 1]; ++run) {
			for (int k = colouring.run_start[run]; k < colouring.run_start[run + 1]; ++k) {
				const int *tuple = vertices + (size_t)order[k] * (size_t)arity;
				for (int a = 0; a < arity; ++a) {
					cr_assert(owner[tuple[a]] == -1 || owner[tuple[a]] == r,
					          "regions %d and %d share particle %d", owner[tuple[a]], r, tuple[a]);
					owner[tuple[a]] = r;
				}
			}
		}
	}
	plait_colouring_clear(&colouring, &allocator);
	free(order);
	free(seen);
	free(stamp);
	free(owner);
}

/* A grid's edges, diagonals and skip-one pairs, and random pairs with a hub vertex that
 * takes part in more constraints than there are colours. */
static void check_grid_colouring(int n)
{
	int count = 0;
	int(*pairs)[2] = malloc(sizeof *pairs * (size_t)(8 * n * n + 200));
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i) {
			int a = j * n + i;
			int neighbours[6][2] = {{i + 1, j}, {i, j + 1}, {i + 1, j + 1},
			                        {i + 2, j}, {i, j + 2}, {i - 1, j + 1}};
			for (int k = 0; k < 6; ++k) {
				int u = neighbours[k][0], v = neighbours[k][1];
				if (u >= 0 && u < n && v < n) {
					pairs[count][0] = a;
					pairs[count][1] = v * n + u;
					++count;
				}
			}
		}
	}
	for (int k = 0; k < 150; ++k) {
		pairs[count][0] = 7;
		pairs[count][1] = (k * 37) % (n * n) == 7 ? 8 : (k * 37) % (n * n);
		++count;
	}
	check_colouring(&pairs[0][0], 2, count, n * n);
	free(pairs);
}

Test(simd, runs_and_regions_share_no_particle)
{
	check_grid_colouring(60);
	/* 240,000 constraints: more regions than PLAIT_MAX_REGIONS, so larger regions and slabs. */
	check_grid_colouring(200);
}

/* A rope of ROPE_VERTICES beside the scenes' cloths, pinned at one end, bent (rod_bend). */
enum { ROPE_VERTICES = 24 };

static plait_object_id add_rope(plait_world_id world)
{
	plait_vec3 rope[ROPE_VERTICES];
	for (int i = 0; i < ROPE_VERTICES; ++i) {
		rope[i] = (plait_vec3){2.5f + 0.05f * (float)i, 0.5f, 0.0f};
	}
	plait_curve_def def = plait_default_curve_def();
	def.positions = rope;
	def.vertex_count = ROPE_VERTICES;
	def.bend_resistance = 5.0f;
	int pin = 0;
	def.pins = &pin;
	def.pin_count = 1;
	return plait_create_curve(world, &def, NULL);
}

/* Two cloths with everything on (tethers, bend as distances and as dihedral angles,
 * self-collision, a collider), stepped
 * with each instruction set: identical positions, byte for byte. */
/* Two cloths, one tethered and pinned, one falling onto it, over a sphere, and a rope; with air, and
 * without (then the velocity update and the next prediction run as one pass, particle_avx2.c),
 * with damping and a bouncy, sticky sphere so that the pass's rare lanes (pinned particles,
 * contacts) are taken too. With shared_damping every material damps alike, and the particle
 * passes take one factor for all; without, the second cloth damps more, and they look each
 * particle's material up. */
static void run_instruction_set_scene(bool air, bool shared_damping)
{
	test_grid grid = test_grid_make(40, 40, 2.0f, 2.0f);
	plait_vec3 *reference = malloc(sizeof *reference * (size_t)(2 * grid.vertex_count));
	plait_vec3 *positions = malloc(sizeof *positions * (size_t)(2 * grid.vertex_count));
	for (int l = 0; l < 3; ++l) {
		if (!plait_simd_is_supported(levels[l])) {
			continue;
		}
		plait_world_def wdef = plait_default_world_def();
		wdef.simd = levels[l];
		wdef.fps = 60.0f;
		wdef.air_density = air ? 1.0f : 0.0f;
		plait_world_id world = plait_create_world(&wdef, NULL);
		cr_assert_eq(plait_world_get_simd(world), levels[l]);
		/* A small cloth made first and removed halfway: the others' particles move down the
		 * arrays and their constraints are renumbered (the vector kernels' point offsets too). */
		test_grid small = test_grid_make(6, 6, 0.3f, 0.3f);
		plait_cloth_def doomed_def = plait_default_cloth_def();
		for (int i = 0; i < small.vertex_count; ++i) {
			small.positions[i].y += 5.0f; /* far above the others: it meets nothing */
		}
		doomed_def.mesh = test_grid_mesh(&small);
		doomed_def.stretch_resistance = doomed_def.compression_resistance = 10000.0f;
		doomed_def.bend_model = PLAIT_BEND_DISTANCE;
		doomed_def.damp = 0.5f;
		plait_object_id doomed = plait_create_cloth(world, &doomed_def, NULL);
		test_grid_free(&small);
		cr_assert(!plait_object_id_is_null(doomed));
		plait_cloth_def def = plait_default_cloth_def();
		def.mesh = test_grid_mesh(&grid);
		def.stretch_resistance = def.compression_resistance = 10000.0f;
		def.bend_model = PLAIT_BEND_DISTANCE;
		def.iterations = 12;
		def.self_collide = true;
		def.tethers = PLAIT_TETHER_EUCLIDEAN;
		def.damp = 0.5f;
		int pins[2] = {0, 40};
		def.pins = pins;
		def.pin_count = 2;
		plait_object_id cloth = plait_create_cloth(world, &def, NULL);
		cr_assert(!plait_object_id_is_null(cloth));
		/* A second cloth, bent by dihedral angles, falling onto the first. */
		plait_cloth_def folded = def;
		plait_vec3 *lifted = malloc(sizeof *lifted * (size_t)grid.vertex_count);
		for (int i = 0; i < grid.vertex_count; ++i) {
			lifted[i] = (plait_vec3){grid.positions[i].x * 0.5f, 0.3f, grid.positions[i].z * 0.5f};
		}
		folded.mesh.positions = lifted;
		folded.bend_model = PLAIT_BEND_DIHEDRAL;
		folded.bend_resistance = 1.0f;
		folded.tethers = PLAIT_TETHER_NONE;
		folded.pins = NULL;
		folded.pin_count = 0;
		folded.damp = shared_damping ? def.damp : 1.5f;
		plait_object_id second = plait_create_cloth(world, &folded, NULL);
		free(lifted);
		cr_assert(!plait_object_id_is_null(second));
		plait_collider_def sphere = plait_default_collider_def();
		sphere.shape = PLAIT_SHAPE_SPHERE;
		sphere.center = (plait_vec3){0.2f, -0.8f, 0.1f};
		sphere.radius = 0.5f;
		sphere.surface.bounce = 0.5f;
		sphere.surface.stickiness = 0.3f;
		plait_create_collider(world, &sphere, NULL);
		/* A rope beside them, pinned at one end (a curve's bend, rod_bend). */
		cr_assert(!plait_object_id_is_null(add_rope(world)));
		cr_assert(test_step_frames(world, 20));
		plait_destroy_object(doomed);
		cr_assert(test_step_frames(world, 20));
		plait_object_get_positions(cloth, 0, grid.vertex_count, positions, NULL);
		plait_object_get_positions(second, 0, grid.vertex_count, positions + grid.vertex_count, NULL);
		if (l == 0) {
			memcpy(reference, positions, sizeof *reference * (size_t)(2 * grid.vertex_count));
		} else {
			cr_assert(
			    memcmp(reference, positions, sizeof *reference * (size_t)(2 * grid.vertex_count)) == 0,
			    "simd level %d gave other positions than the portable kernel (air %d, shared damping %d)",
			    (int)levels[l], (int)air, (int)shared_damping);
		}
		plait_destroy_world(world);
	}
	free(reference);
	free(positions);
	test_grid_free(&grid);
}

Test(simd, a_simulation_is_byte_identical_with_every_instruction_set)
{
	run_instruction_set_scene(true, false);
}

Test(simd, a_simulation_without_air_is_byte_identical_with_every_instruction_set)
{
	run_instruction_set_scene(false, true);
}

Test(simd, materials_damping_apart_give_the_same_bytes_with_every_instruction_set)
{
	run_instruction_set_scene(false, false);
}

/* A cloth whose distance constraints are projected on columns (a 64 x 64 grid, with AVX-512),
 * with what runs between and around its distance events: tethers, self-collision, a sphere, air
 * (the substeps then close without the folded pass), a rope whose bend runs inside the bend
 * event (the points leave the columns for it and come back), and a cloth bent by dihedral
 * angles: the same bytes with every instruction set. */
Test(simd, a_cloth_projected_on_columns_gives_the_same_bytes_with_every_instruction_set)
{
	test_grid grid = test_grid_make(64, 64, 2.0f, 2.0f);
	int count = grid.vertex_count + ROPE_VERTICES;
	plait_vec3 *reference = malloc(sizeof *reference * (size_t)count);
	plait_vec3 *positions = malloc(sizeof *positions * (size_t)count);
	bool compared = false;
	for (int l = 0; l < 3; ++l) {
		if (!plait_simd_is_supported(levels[l])) {
			continue;
		}
		plait_world_def wdef = plait_default_world_def();
		wdef.simd = levels[l];
		wdef.air_density = 1.0f;
		plait_world_id world = plait_create_world(&wdef, NULL);
		plait_cloth_def def = plait_default_cloth_def();
		def.mesh = test_grid_mesh(&grid);
		def.stretch_resistance = def.compression_resistance = def.shear_resistance = 10000.0f;
		def.bend_resistance = 10000.0f;
		def.bend_model = PLAIT_BEND_DISTANCE;
		def.self_collide = true;
		def.tethers = PLAIT_TETHER_EUCLIDEAN;
		int pins[2] = {0, 63};
		def.pins = pins;
		def.pin_count = 2;
		plait_object_id cloth = plait_create_cloth(world, &def, NULL);
		cr_assert(!plait_object_id_is_null(cloth));
		plait_object_id curve = add_rope(world);
		cr_assert(!plait_object_id_is_null(curve));
		plait_collider_def sphere = plait_default_collider_def();
		sphere.shape = PLAIT_SHAPE_SPHERE;
		sphere.center = (plait_vec3){0.0f, -0.75f, 0.0f};
		sphere.radius = 0.5f;
		plait_create_collider(world, &sphere, NULL);
		cr_assert(test_step_frames(world, 30));
		cr_assert_eq(world.world->sim.use_columns, levels[l] == PLAIT_SIMD_AVX512, "simd level %d",
		             (int)levels[l]);
		plait_object_get_positions(cloth, 0, grid.vertex_count, positions, NULL);
		plait_object_get_positions(curve, 0, ROPE_VERTICES, positions + grid.vertex_count, NULL);
		if (l == 0) {
			memcpy(reference, positions, sizeof *reference * (size_t)count);
		} else {
			compared = compared || levels[l] == PLAIT_SIMD_AVX512;
			cr_assert(memcmp(reference, positions, sizeof *reference * (size_t)count) == 0,
			          "simd level %d gave other positions than the portable kernel", (int)levels[l]);
		}
		plait_destroy_world(world);
	}
	if (!compared) {
		cr_log_info("no AVX-512 here: the columns were not compared");
	}
	free(reference);
	free(positions);
	test_grid_free(&grid);
}

Test(simd, asking_for_a_level_the_processor_lacks_is_an_error)
{
	for (int l = 0; l < 3; ++l) {
		plait_world_def wdef = plait_default_world_def();
		wdef.simd = levels[l];
		plait_error error;
		plait_world_id world = plait_create_world(&wdef, &error);
		if (plait_simd_is_supported(levels[l])) {
			cr_assert(!plait_world_id_is_null(world));
			plait_destroy_world(world);
		} else {
			cr_assert(plait_world_id_is_null(world));
			cr_assert(strstr(error.message, "does not run it") != NULL, "%s", error.message);
		}
	}
	plait_world_def wdef = plait_default_world_def();
	wdef.simd = (plait_simd)42;
	plait_error error;
	cr_assert(plait_world_id_is_null(plait_create_world(&wdef, &error)));
	cr_assert(strstr(error.message, "simd") != NULL);
}

#if defined(__SSE2__)
#include <xmmintrin.h>

/* A step flushes subnormals on its own threads only: the caller's floating-point mode is as it
 * was before the step, and a subnormal computed after it is still subnormal. */
Test(simd, a_step_leaves_the_callers_floating_point_mode_alone)
{
	unsigned int before = _mm_getcsr();
	test_grid grid = test_grid_make(8, 8, 1.0f, 1.0f);
	plait_world_id world = plait_create_world(&(plait_world_def){0}, NULL);
	cr_assert(plait_world_id_is_null(world)); /* an uninitialised def is refused */
	plait_world_def wdef = plait_default_world_def();
	world = plait_create_world(&wdef, NULL);
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = test_grid_mesh(&grid);
	cr_assert(!plait_object_id_is_null(plait_create_cloth(world, &def, NULL)));
	cr_assert(test_step_frames(world, 2));
	cr_assert_eq(_mm_getcsr() & ~0x3Fu, before & ~0x3Fu,
	             "the control bits (not the sticky exception flags) must be restored");
	volatile float tiny = 1e-38f;
	volatile float half = tiny * 0.5f;
	cr_assert(half > 0.0f, "subnormals are flushed after a step");
	plait_destroy_world(world);
	test_grid_free(&grid);
}
#endif
