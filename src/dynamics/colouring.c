#include "dynamics/colouring.h"

#include <limits.h>
#include <stdint.h>
#include <string.h>

#include "dynamics/batch_layout.h"
#include "dynamics/wave.h"

#define NO_COLOUR (-1)

void plait_colouring_clear(plait_colouring *colouring, const plait_allocator *allocator)
{
	plait_free(allocator, colouring->region_start);
	plait_free(allocator, colouring->run_start);
	plait_free(allocator, colouring->batch_layout);
	plait_free(allocator, colouring->segments);
	plait_free(allocator, colouring->boundary_cut_start);
	memset(colouring, 0, sizeof *colouring);
}

typedef struct colouring_state {
	const int *vertices;
	int arity;
	uint64_t *used; /* colours taken, per particle, in the current slab */
	int *colour;    /* per constraint */
	int *order;     /* output: constraint at each position */
	int *run_start; /* output */
	int position, runs;
} colouring_state;

/* Colours the constraints list[0..n) slab by slab, appending them to the order and their runs. */
static void colour_list(colouring_state *state, const int *list, int n, int slab_size)
{
	int arity = state->arity;
	for (int first = 0; first < n; first += slab_size) {
		int last = first + slab_size < n ? first + slab_size : n;
		int sizes[PLAIT_MAX_COLOURS] = {0};
		int colour_count = 0, uncoloured = 0;
		for (int k = first; k < last; ++k) {
			const int *tuple = state->vertices + (size_t)list[k] * (size_t)arity;
			uint64_t taken = 0;
			for (int a = 0; a < arity; ++a) {
				taken |= state->used[tuple[a]];
			}
			if (taken == UINT64_MAX) {
				state->colour[list[k]] = NO_COLOUR;
				++uncoloured;
				continue;
			}
			int colour = 0;
			while (taken & ((uint64_t)1 << colour)) {
				++colour;
			}
			state->colour[list[k]] = colour;
			sizes[colour] += 1;
			colour_count = colour + 1 > colour_count ? colour + 1 : colour_count;
			for (int a = 0; a < arity; ++a) {
				state->used[tuple[a]] |= (uint64_t)1 << colour;
			}
		}
		/* Counting sort of the slab by colour, stable; the uncoloured follow, one run each. */
		int next[PLAIT_MAX_COLOURS + 1];
		int position = state->position;
		for (int colour = 0; colour < colour_count; ++colour) {
			state->run_start[state->runs++] = position;
			next[colour] = position;
			position += sizes[colour];
		}
		next[colour_count] = position;
		for (int u = 0; u < uncoloured; ++u) {
			state->run_start[state->runs++] = position + u;
		}
		for (int k = first; k < last; ++k) {
			int colour = state->colour[list[k]];
			state->order[next[colour == NO_COLOUR ? colour_count : colour]++] = list[k];
		}
		state->position += last - first;
		/* The next slab starts with every particle free. */
		for (int k = first; k < last; ++k) {
			const int *tuple = state->vertices + (size_t)list[k] * (size_t)arity;
			for (int a = 0; a < arity; ++a) {
				state->used[tuple[a]] = 0;
			}
		}
	}
}

/* The boundary of a coloured block, banded when it can be (colouring.h): each constraint
 * between two adjacent regions. Sorts each boundary run by cut (its constraints share no
 * particle, so their order in it changes nothing) and returns the runs' cut starts, or NULL (not
 * banded, or out of memory). That no particle is held by two cuts is checked over all the
 * blocks together (bands_agree). */
static int *band_boundary(const plait_allocator *allocator, const int *vertices, int arity,
                          int particle_count, int *order, plait_colouring *colouring)
{
	int regions = colouring->region_count;
	int first_run = colouring->region_start[regions], runs = colouring->run_count - first_run;
	if (regions < 2 || runs <= 0) {
		return NULL;
	}
	int first = colouring->run_start[first_run], count = colouring->run_start[colouring->run_count] - first;
	int *cut_of = plait_alloc(allocator, sizeof(int) * (size_t)count);
	int *sorted = plait_alloc(allocator, sizeof(int) * (size_t)count);
	int *starts = plait_alloc(allocator, sizeof(int) * ((size_t)runs * (size_t)regions + 1));
	bool banded = cut_of != NULL && sorted != NULL && starts != NULL;
	for (int k = 0; banded && k < count; ++k) {
		const int *tuple = vertices + (size_t)order[first + k] * (size_t)arity;
		int low = INT_MAX, high = -1;
		for (int a = 0; a < arity; ++a) {
			int region = (int)((int64_t)tuple[a] * regions / particle_count);
			low = region < low ? region : low;
			high = region > high ? region : high;
		}
		banded = high == low + 1;
		cut_of[k] = low;
	}
	/* Each run by cut, stably: a counting sort. */
	for (int m = 0; banded && m < runs; ++m) {
		int begin = colouring->run_start[first_run + m] - first,
		    end = colouring->run_start[first_run + m + 1] - first;
		int *cut_start = starts + (size_t)m * (size_t)regions;
		for (int c = 0; c < regions; ++c) {
			cut_start[c] = 0;
		}
		for (int k = begin; k < end; ++k) {
			cut_start[cut_of[k] + 1] += 1;
		}
		cut_start[0] = first + begin;
		for (int c = 1; c < regions; ++c) {
			cut_start[c] += cut_start[c - 1];
		}
		int next[PLAIT_MAX_REGIONS];
		memcpy(next, cut_start, sizeof(int) * (size_t)regions);
		for (int k = begin; k < end; ++k) {
			sorted[next[cut_of[k]]++ - first] = order[first + k];
		}
		memcpy(order + first + begin, sorted + begin, sizeof(int) * (size_t)(end - begin));
	}
	if (banded) {
		starts[(size_t)runs * (size_t)regions] = first + count;
	}
	plait_free(allocator, cut_of);
	plait_free(allocator, sorted);
	if (!banded) {
		plait_free(allocator, starts);
		return NULL;
	}
	return starts;
}

bool plait_colour_constraints(const plait_allocator *allocator, const int *vertices, int arity, int count,
                              int particle_count, int *order, plait_colouring *colouring)
{
	memset(colouring, 0, sizeof *colouring);
	if (count <= 0) {
		return true;
	}
	int regions = count / PLAIT_REGION_SIZE;
	/* A multiple of 8 when there are several: 2, 4 or 8 workers then split them evenly. */
	regions = regions >= 8 ? (regions + 7) / 8 * 8 : regions;
	regions = regions < 1 ? 1 : regions > PLAIT_MAX_REGIONS ? PLAIT_MAX_REGIONS : regions;
	/* Runs: at most PLAIT_MAX_COLOURS per slab, plus one per uncoloured constraint. */
	size_t run_capacity =
	    ((size_t)count / PLAIT_SLAB_SIZE + (size_t)regions + 2) * PLAIT_MAX_COLOURS + (size_t)count + 1;
	uint64_t *used =
	    plait_alloc_zero(allocator, (size_t)(particle_count > 0 ? particle_count : 1), sizeof(uint64_t));
	int *colour = plait_alloc(allocator, sizeof(int) * (size_t)count);
	int *region_of = plait_alloc(allocator, sizeof(int) * (size_t)count);
	int *list = plait_alloc(allocator, sizeof(int) * (size_t)count);
	int *run_start = plait_alloc(allocator, sizeof(int) * run_capacity);
	int *region_start = plait_alloc(allocator, sizeof(int) * (size_t)(regions + 2));
	bool ok = used != NULL && colour != NULL && region_of != NULL && list != NULL && run_start != NULL &&
	          region_start != NULL;
	if (ok) {
		/* Region of each constraint: that of its particles when they agree, else the boundary. */
		int bucket_size[PLAIT_MAX_REGIONS + 1] = {0};
		for (int c = 0; c < count; ++c) {
			const int *tuple = vertices + (size_t)c * (size_t)arity;
			int region = (int)((int64_t)tuple[0] * regions / particle_count);
			for (int a = 1; a < arity; ++a) {
				region = (int)((int64_t)tuple[a] * regions / particle_count) == region ? region : regions;
			}
			region_of[c] = region;
			bucket_size[region] += 1;
		}
		int bucket_first[PLAIT_MAX_REGIONS + 1], next[PLAIT_MAX_REGIONS + 1];
		for (int r = 0, first = 0; r <= regions; ++r) {
			bucket_first[r] = first;
			next[r] = first;
			first += bucket_size[r];
		}
		for (int c = 0; c < count; ++c) {
			list[next[region_of[c]]++] = c;
		}
		/* Where the regions are capped (PLAIT_MAX_REGIONS), they hold more than about
		 * PLAIT_REGION_SIZE constraints and their slabs grow with them, to the same share. */
		int region_slab = PLAIT_SLAB_SIZE;
		if (regions == PLAIT_MAX_REGIONS && count / regions > PLAIT_REGION_SIZE) {
			region_slab = (int)((int64_t)PLAIT_SLAB_SIZE * (count / regions) / PLAIT_REGION_SIZE);
		}
		colouring_state state = {vertices, arity, used, colour, order, run_start, 0, 0};
		for (int r = 0; r <= regions; ++r) {
			region_start[r] = state.runs;
			/* The boundary is small and scattered: coloured whole, for long runs. */
			int slab = r < regions ? region_slab : count;
			colour_list(&state, list + bucket_first[r], bucket_size[r], slab);
		}
		run_start[state.runs] = count;
		colouring->region_count = regions;
		colouring->run_count = state.runs;
		colouring->region_start = region_start;
		colouring->run_start = run_start;
		colouring->particle_count = particle_count;
		colouring->boundary_cut_start =
		    band_boundary(allocator, vertices, arity, particle_count, order, colouring);
	} else {
		plait_free(allocator, run_start);
		plait_free(allocator, region_start);
	}
	plait_free(allocator, used);
	plait_free(allocator, colour);
	plait_free(allocator, region_of);
	plait_free(allocator, list);
	return ok;
}

/* Applies order to count elements of `size` bytes at data, through scratch (room for count
 * elements of the largest size). */
static void permute(char *scratch, void *data, size_t size, int count, const int *order)
{
	if (count <= 0) {
		return;
	}
	char *base = data;
	for (int k = 0; k < count; ++k) {
		memcpy(scratch + size * (size_t)k, base + size * (size_t)order[k], size);
	}
	memcpy(base, scratch, size * (size_t)count);
}

enum { DISTANCE_BLOCKS = 3, BLOCKS = DISTANCE_BLOCKS + 1 };

/* Whether the distance blocks are projected on the points as columns (solver.c, "Columns"),
 * and room for the columns (freed when they are not used). Columns pay when segments hold 8
 * constraints or more on average: `bench_kernels N` with columns forced, ns a projection against
 * the AVX-512 point kernel's, gave 2.31 against 1.94 for a 32 x 32 grid, 1.94 against 1.99 at
 * 40 x 40 (segments of about 6.5), 1.79 against 1.94 at 48 x 48 and 1.45 against 1.90 at 64 x 64
 * (9.2); a scanned mesh's segments hold nearer one. There is a column kernel for AVX-512 only.
 * Without the memory they are not used: that only costs speed. */
static void choose_columns(plait_sim *sim, int segment_count)
{
	int constraints = sim->stretch.count + sim->shear.count + sim->bend_distance.count;
	sim->use_columns = sim->column_ops.project != NULL && constraints > 0 &&
	                   (int64_t)segment_count * 8 <= (int64_t)constraints;
	if (!sim->use_columns) {
		plait_free(&sim->allocator, sim->column_x);
		sim->column_x = sim->column_y = sim->column_z = sim->column_w = NULL;
		sim->columns_capacity = 0;
		return;
	}
	int needed = sim->particles.capacity;
	if (sim->columns_capacity >= needed) {
		return;
	}
	/* Four columns, each padded to whole cache lines. */
	int padded = (needed + 15) & ~15;
	float *columns = plait_alloc(&sim->allocator, sizeof(float) * 4 * (size_t)padded);
	if (columns == NULL) {
		sim->use_columns = false;
		return;
	}
	plait_free(&sim->allocator, sim->column_x);
	sim->column_x = columns;
	sim->column_y = columns + padded;
	sim->column_z = columns + 2 * (size_t)padded;
	sim->column_w = columns + 3 * (size_t)padded;
	sim->columns_capacity = padded;
}

/* Whether the distance blocks' boundaries are banded alike (plait_sim.bands_agree): each banded
 * (band_boundary), in the same regions, and no particle held by constraints of two cuts, in one
 * block or across them. False without the memory to check. */
static bool bands_agree(const plait_sim *sim, plait_distance_block *const *blocks, int count)
{
	int n = sim->particles.count, regions = 0;
	int *held_by = plait_alloc(&sim->allocator, sizeof(int) * (size_t)(n > 0 ? n : 1));
	bool agree = held_by != NULL;
	for (int i = 0; agree && i < n; ++i) {
		held_by[i] = -1;
	}
	for (int k = 0; agree && k < count; ++k) {
		const plait_distance_block *block = blocks[k];
		const plait_colouring *colouring = &block->colouring;
		if (block->count == 0) {
			continue;
		}
		regions = regions == 0 ? colouring->region_count : regions;
		agree = colouring->boundary_cut_start != NULL && colouring->region_count == regions;
		int runs = agree ? colouring->run_count - colouring->region_start[regions] : 0;
		for (int m = 0; agree && m < runs; ++m) {
			const int *cut_start = colouring->boundary_cut_start + (size_t)m * (size_t)regions;
			for (int cut = 0; agree && cut + 1 < regions; ++cut) {
				for (int c = cut_start[cut]; agree && c < cut_start[cut + 1]; ++c) {
					for (int end = 0; end < 2; ++end) {
						int particle = block->pair[c][end];
						agree = agree && (held_by[particle] < 0 || held_by[particle] == cut);
						held_by[particle] = cut;
					}
				}
			}
		}
	}
	plait_free(&sim->allocator, held_by);
	return agree;
}

/* Room for the wave in pieces (wave.h) where several workers may run it; none without the
 * memory (the passes then run). */
static void reserve_wave_plan(plait_sim *sim, plait_distance_block *const *blocks, int count)
{
	int regions = 0;
	for (int k = 0; k < count && regions == 0; ++k) {
		regions = blocks[k]->count > 0 ? blocks[k]->colouring.region_count : 0;
	}
	bool pieces = sim->bands_agree && regions >= 2 && sim->parallel.worker_count > 1;
	if (sim->wave_plan == NULL && pieces) {
		sim->wave_plan = plait_alloc_zero(&sim->allocator, 1, sizeof(plait_wave_plan));
	}
	if (sim->wave_plan == NULL) {
		return;
	}
	if (!pieces ||
	    !plait_wave_plan_reserve(sim->wave_plan, &sim->allocator, regions, sim->parallel.worker_count)) {
		plait_wave_plan_destroy(sim->wave_plan, &sim->allocator);
		plait_free(&sim->allocator, sim->wave_plan);
		sim->wave_plan = NULL;
	}
}

/* Every block's order is computed first and applied only when all succeeded, so a failure
 * leaves every block as it was. */
bool plait_sim_colour(plait_sim *sim)
{
	if (!sim->colouring_dirty) {
		return true;
	}
	const plait_allocator *a = &sim->allocator;
	plait_distance_block *distance[DISTANCE_BLOCKS] = {&sim->stretch, &sim->shear, &sim->bend_distance};
	plait_bend_block *bend = &sim->bend;
	int counts[BLOCKS] = {sim->stretch.count, sim->shear.count, sim->bend_distance.count, bend->count};
	const int *tuples[BLOCKS] = {NULL, NULL, NULL, NULL};
	int arity[BLOCKS] = {2, 2, 2, 4};
	for (int k = 0; k < DISTANCE_BLOCKS; ++k) {
		tuples[k] = counts[k] > 0 ? &distance[k]->pair[0][0] : NULL;
	}
	tuples[DISTANCE_BLOCKS] = counts[DISTANCE_BLOCKS] > 0 ? &bend->quad[0][0] : NULL;

	int largest = 1;
	for (int k = 0; k < BLOCKS; ++k) {
		largest = counts[k] > largest ? counts[k] : largest;
	}
	char *scratch = plait_alloc(a, sizeof bend->quad[0] * (size_t)largest);
	int *orders[BLOCKS] = {NULL, NULL, NULL, NULL};
	unsigned char *layouts[DISTANCE_BLOCKS] = {NULL, NULL, NULL};
	plait_colouring colourings[BLOCKS];
	memset(colourings, 0, sizeof colourings);
	bool ok = scratch != NULL;
	for (int k = 0; k < BLOCKS && ok; ++k) {
		orders[k] = plait_alloc(a, sizeof(int) * (size_t)(counts[k] > 0 ? counts[k] : 1));
		ok = orders[k] != NULL && plait_colour_constraints(a, tuples[k], arity[k], counts[k],
		                                                   sim->particles.count, orders[k], &colourings[k]);
	}
	for (int k = 0; k < DISTANCE_BLOCKS && ok; ++k) {
		layouts[k] = plait_alloc(a, (size_t)(counts[k] > 0 ? counts[k] : 1));
		ok = layouts[k] != NULL;
	}
	if (ok) {
		int segment_count = 0;
		for (int k = 0; k < DISTANCE_BLOCKS; ++k) {
			plait_distance_block *b = distance[k];
			permute(scratch, b->pair, sizeof *b->pair, b->count, orders[k]);
			permute(scratch, b->point_offset, sizeof *b->point_offset, b->count, orders[k]);
			permute(scratch, b->rest, sizeof(float), b->count, orders[k]);
			permute(scratch, b->compliance_tension, sizeof(float), b->count, orders[k]);
			permute(scratch, b->compliance_compression, sizeof(float), b->count, orders[k]);
			permute(scratch, b->lambda, sizeof(float), b->count, orders[k]);
			plait_colouring_clear(&b->colouring, a);
			b->colouring = colourings[k];
			b->colouring.batch_layout = layouts[k];
			layouts[k] = NULL;
			plait_find_batch_layouts(b, b->colouring.batch_layout);
			/* Without the memory for them, no segments: only the columns go. */
			int found = plait_find_segments(b, NULL);
			b->colouring.segments = found > 0 ? plait_alloc(a, sizeof(plait_segment) * (size_t)found) : NULL;
			if (b->colouring.segments != NULL) {
				b->colouring.segment_count = plait_find_segments(b, b->colouring.segments);
				segment_count += found;
			} else if (found > 0) {
				segment_count = INT_MAX / 16;
			}
		}
		choose_columns(sim, segment_count);
		sim->bands_agree = bands_agree(sim, distance, DISTANCE_BLOCKS);
		reserve_wave_plan(sim, distance, DISTANCE_BLOCKS);
		const int *order = orders[DISTANCE_BLOCKS];
		permute(scratch, bend->quad, sizeof *bend->quad, bend->count, order);
		permute(scratch, bend->rest_angle, sizeof(float), bend->count, order);
		permute(scratch, bend->compliance, sizeof(float), bend->count, order);
		permute(scratch, bend->lambda, sizeof(float), bend->count, order);
		plait_colouring_clear(&bend->colouring, a);
		bend->colouring = colourings[DISTANCE_BLOCKS];
		sim->colouring_dirty = false;
	} else {
		for (int k = 0; k < BLOCKS; ++k) {
			plait_colouring_clear(&colourings[k], a);
		}
	}
	for (int k = 0; k < DISTANCE_BLOCKS; ++k) {
		plait_free(a, layouts[k]);
	}
	for (int k = 0; k < BLOCKS; ++k) {
		plait_free(a, orders[k]);
	}
	plait_free(a, scratch);
	return ok;
}
