/* Solving tethers (long-range attachments, seed 004). A particle may have several tethers (to
 * its nearest pins, world/tethers.c): it must end within every one's reach, so it is moved to
 * the nearest point of the intersection of their balls, found exactly rather than by repeated
 * projection. Repeated projection crawls where two balls barely overlap (a vertex halfway
 * between two pins, on the line joining them, is held at the single point where they touch),
 * and left such vertices 0.7% past their tether after eight rounds. */
#include "dynamics/constraints.h"

#include "core/dvec3.h"
#include "dynamics/tether_kernel.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define TETHER_GRAIN 2048
_Static_assert(PLAIT_TETHER_ANCHORS <= 8, "a particle's tethers must fit a chunk's slack (MAX_ROW)");
#define MAX_ROW 8             /* tethers of one particle handled exactly; more are projected in turn */
#define INSIDE_TOLERANCE 1e-6 /* relative to a ball's radius, for rounding in the candidates */

/* The candidates are found in double precision (core/dvec3.h): the circle where two spheres
 * meet comes from a difference of squares that loses most of a float's digits when the circle
 * is small. */
typedef struct ball {
	dvec3 centre;
	double radius;
} ball;

static bool inside_all(dvec3 q, const ball *balls, int count)
{
	for (int k = 0; k < count; ++k) {
		double reach = balls[k].radius * (1.0 + INSIDE_TOLERANCE);
		dvec3 d = d3_sub(q, balls[k].centre);
		if (d3_dot(d, d) > reach * reach) {
			return false;
		}
	}
	return true;
}

/* Keeps q as the best candidate when it lies in every ball and nearer p than the best so far. */
static void consider(dvec3 p, dvec3 q, const ball *balls, int count, dvec3 *best, double *best_distance_sq)
{
	dvec3 d = d3_sub(q, p);
	double distance_sq = d3_dot(d, d);
	if (distance_sq < *best_distance_sq && inside_all(q, balls, count)) {
		*best = q;
		*best_distance_sq = distance_sq;
	}
}

/* The circle where the spheres of balls a and b meet: centre, unit axis, radius. False when
 * they do not meet (or are concentric). A tangent pair gives a circle of radius zero. */
static bool meeting_circle(ball a, ball b, dvec3 *centre, dvec3 *axis, double *radius)
{
	dvec3 d = d3_sub(b.centre, a.centre);
	double separation = d3_length(d);
	if (separation <= 0.0) {
		return false;
	}
	*axis = d3_scale(d, 1.0 / separation);
	double along = 0.5 * (separation + (a.radius * a.radius - b.radius * b.radius) / separation);
	double radius_sq = a.radius * a.radius - along * along;
	if (radius_sq < -2.0 * INSIDE_TOLERANCE * a.radius * a.radius) {
		return false;
	}
	*centre = d3_add(a.centre, d3_scale(*axis, along));
	*radius = sqrt(radius_sq > 0.0 ? radius_sq : 0.0);
	return true;
}

/* A unit vector perpendicular to the unit vector n. */
static dvec3 perpendicular(dvec3 n)
{
	dvec3 other = fabs(n.x) < 0.6 ? (dvec3){1.0, 0.0, 0.0} : (dvec3){0.0, 1.0, 0.0};
	dvec3 c = d3_cross(n, other);
	return d3_scale(c, 1.0 / d3_length(c));
}

/* The nearest point to p in the intersection of the balls. The nearest point lies on the
 * boundary of one, two or three of them (more only in degenerate cases), so the candidates
 * are: p's projection onto each ball, its nearest point on the circle where each two meet,
 * and the points where each three meet; the nearest candidate inside every ball wins. False
 * when no candidate is (the balls have no common point, as when pins are pulled apart). */
static bool nearest_in_balls(vec3 point, const ball *balls, int count, vec3 *out)
{
	dvec3 p = d3(point), best = p;
	double best_distance_sq = INFINITY;
	for (int i = 0; i < count; ++i) {
		dvec3 d = d3_sub(p, balls[i].centre);
		double length = d3_length(d);
		if (length > balls[i].radius) {
			consider(p, d3_add(balls[i].centre, d3_scale(d, balls[i].radius / length)), balls, count, &best,
			         &best_distance_sq);
		}
	}
	for (int i = 0; i < count; ++i) {
		for (int j = i + 1; j < count; ++j) {
			dvec3 centre, axis;
			double radius;
			if (!meeting_circle(balls[i], balls[j], &centre, &axis, &radius)) {
				continue;
			}
			dvec3 offset = d3_sub(p, centre);
			dvec3 in_plane = d3_sub(offset, d3_scale(axis, d3_dot(offset, axis)));
			double length = d3_length(in_plane);
			dvec3 direction = length > 1e-300 ? d3_scale(in_plane, 1.0 / length) : perpendicular(axis);
			consider(p, d3_add(centre, d3_scale(direction, radius)), balls, count, &best, &best_distance_sq);
			if (radius <= 0.0 || count < 3) {
				continue;
			}
			/* Where a third sphere crosses this circle: centre + radius (cos t e1 + sin t e2)
			 * at distance r_k from c_k gives A cos t + B sin t = C. */
			dvec3 e1 = perpendicular(axis), e2 = d3_cross(axis, e1);
			/* Every third ball, not only later ones: a small circle amplifies rounding, and
			 * the same point found from a larger one survives it. */
			for (int k = 0; k < count; ++k) {
				if (k == i || k == j) {
					continue;
				}
				dvec3 v = d3_sub(balls[k].centre, centre);
				double a = d3_dot(v, e1), b = d3_dot(v, e2);
				double c =
				    (radius * radius + d3_dot(v, v) - balls[k].radius * balls[k].radius) / (2.0 * radius);
				double norm = sqrt(a * a + b * b);
				/* Spheres whose centres lie in one plane with a common point on it touch
				 * there only (|C| = norm): rounding must not lose that point. */
				if (norm <= 0.0 || fabs(c) > norm + INSIDE_TOLERANCE * balls[k].radius) {
					continue;
				}
				double cosine = c / norm > 1.0 ? 1.0 : c / norm < -1.0 ? -1.0 : c / norm;
				double base = atan2(b, a), spread = acos(cosine);
				for (int sign = -1; sign <= 1; sign += 2) {
					double t = base + sign * spread;
					dvec3 q =
					    d3_add(centre, d3_add(d3_scale(e1, radius * cos(t)), d3_scale(e2, radius * sin(t))));
					consider(p, q, balls, count, &best, &best_distance_sq);
				}
			}
		}
	}
	*out = v3((float)best.x, (float)best.y, (float)best.z);
	return best_distance_sq < INFINITY;
}

/* Pulls p back within `length` of anchor, by `stiffness` of the excess; returns whether it
 * moved. */
static bool pull_within(plait_point *p, plait_point *anchor, float length, float stiffness)
{
	float w_sum = p->w + anchor->w;
	if (w_sum == 0.0f) {
		return false;
	}
	vec3 d = v3_sub(p->x, anchor->x);
	float distance = sqrtf(v3_length_sq(d));
	float excess = distance - length;
	if (excess <= 0.0f) {
		return false;
	}
	vec3 correction = v3_scale(d, stiffness * excess / (distance * w_sum));
	p->x = v3_mul_add(p->x, -p->w, correction);
	if (anchor->w != 0.0f) {
		anchor->x = v3_mul_add(anchor->x, anchor->w, correction);
	}
	return true;
}

/* Pulls a particle back within tether c's length of its anchor; returns whether it moved. */
static bool project_tether(const plait_tether_block *block, plait_point *points, int c)
{
	return pull_within(&points[block->pair[c][0]], &points[block->pair[c][1]], block->length[c],
	                   block->stiffness[c]);
}

/* The tethers [first, end) of one particle, with anchors that do not move (pins). */
/* Kept out of line: the common case in project_row stays small. */
static __attribute__((noinline)) void project_row_exactly(const plait_tether_block *block,
                                                          plait_point *points, int first, int end)
{
	plait_point *p = &points[block->pair[first][0]];
	ball balls[MAX_ROW] = {0}; /* only the first count, written below, are read */
	int count = 0;
	for (int c = first; c < end; ++c) {
		balls[count++] = (ball){d3(points[block->pair[c][1]].x), block->length[c]};
	}
	vec3 target;
	if (nearest_in_balls(p->x, balls, count, &target)) {
		p->x = v3_lerp(p->x, target, block->stiffness[first]);
	} else {
		/* No common point: each in turn, the nearest pin (last) holding. */
		for (int c = first; c < end; ++c) {
			project_tether(block, points, c);
		}
	}
}

/* project_row_exactly for a row of two in the lanes, from the lanes' own copy of it: the
 * block's arrays, read at rows scattered over them, cost a cache miss each at hang-512. The
 * same balls in the same order, so the same bits. */
static __attribute__((noinline)) void project_pair_exactly(plait_point *points, int particle,
                                                           const int anchor[2], float length0, float length1,
                                                           float stiffness)
{
	plait_point *p = &points[particle];
	ball balls[2] = {{d3(points[anchor[0]].x), length0}, {d3(points[anchor[1]].x), length1}};
	vec3 target;
	if (nearest_in_balls(p->x, balls, 2, &target)) {
		p->x = v3_lerp(p->x, target, stiffness);
	} else {
		/* A row's tethers share their cloth's stiffness. */
		pull_within(p, &points[anchor[0]], length0, stiffness);
		pull_within(p, &points[anchor[1]], length1, stiffness);
	}
}

/* Whether q lies within a tether's reach, up to the rounding tolerance. */
static inline int within_reach(vec3 q, vec3 anchor, float length)
{
	float reach = length * (1.0f + (float)INSIDE_TOLERANCE);
	return v3_length_sq(v3_sub(q, anchor)) <= reach * reach;
}

static inline void project_row(const plait_tether_block *block, plait_point *points, int first, int end)
{
	plait_point *p = &points[block->pair[first][0]];
	if (p->w == 0.0f) {
		return;
	}
	/* Most often one tether is taut and the projection onto it lies within the others' reach:
	 * that is then the nearest point, found in float without the candidates. */
	int worst = -1;
	float worst_excess = 0.0f;
	for (int c = first; c < end; ++c) {
		float distance_sq = v3_length_sq(v3_sub(p->x, points[block->pair[c][1]].x));
		if (distance_sq <= block->length[c] * block->length[c]) {
			continue; /* slack, as most are: no square root */
		}
		float excess = sqrtf(distance_sq) - block->length[c];
		if (excess > worst_excess) {
			worst_excess = excess;
			worst = c;
		}
	}
	if (worst < 0) {
		return;
	}
	vec3 anchor = points[block->pair[worst][1]].x;
	vec3 d = v3_sub(p->x, anchor);
	vec3 projected = v3_mul_add(anchor, block->length[worst] / v3_length(d), d);
	bool within = true;
	for (int c = first; c < end && within; ++c) {
		within = c == worst || within_reach(projected, points[block->pair[c][1]].x, block->length[c]);
	}
	if (within) {
		/* One stiffness per cloth: the row's tethers share it. */
		p->x = v3_lerp(p->x, projected, block->stiffness[first]);
	} else {
		project_row_exactly(block, points, first, end);
	}
}

/* The tethers regrouped for the solver when every anchor is a pin. Rows of two tethers (every
 * free vertex of a cloth hung from two pins) are grouped by their pair of anchors, in runs: a
 * run reads its two anchors once, and its rows are solved whole in vector lanes, without a
 * test of which are taut first (a slack row comes out unchanged, to the bit). The other rows
 * are copied into a block of their own, solved as before. */
typedef struct tether_run {
	int anchor[2];
	float stiffness; /* its rows' (their cloth's) */
	int begin, end;  /* its rows */
} tether_run;

typedef struct plait_tether_lanes {
	int count; /* rows of two */
	int *particle;
	float *length[2];
	int run_count;
	tether_run *runs;
	plait_tether_block others; /* the rows not of two (no lanes of its own) */
	bool others_in_order;      /* others' particles never decrease (plait_tethers_by_particle) */
	int anchor_count;          /* the distinct anchors, for the checks at each frame's start */
	int *anchors;
} plait_tether_lanes;

void plait_tether_lanes_destroy(plait_tether_block *block, const plait_allocator *allocator)
{
	plait_tether_lanes *lanes = block->lanes;
	if (lanes == NULL) {
		return;
	}
	plait_free(allocator, lanes->particle);
	plait_free(allocator, lanes->length[0]);
	plait_free(allocator, lanes->length[1]);
	plait_free(allocator, lanes->runs);
	plait_free(allocator, lanes->others.pair);
	plait_free(allocator, lanes->others.length);
	plait_free(allocator, lanes->others.stiffness);
	plait_free(allocator, lanes->anchors);
	plait_free(allocator, lanes);
	block->lanes = NULL;
}

/* Rows of two are sorted by anchor pair, then particle: a run's particles lie near each other
 * in memory. */
typedef struct row_key {
	int anchor[2], particle, first;
} row_key;

static int compare_rows(const void *a, const void *b)
{
	const row_key *x = a, *y = b;
	if (x->anchor[0] != y->anchor[0]) {
		return x->anchor[0] < y->anchor[0] ? -1 : 1;
	}
	if (x->anchor[1] != y->anchor[1]) {
		return x->anchor[1] < y->anchor[1] ? -1 : 1;
	}
	return x->particle < y->particle ? -1 : x->particle > y->particle;
}

static int compare_ints(const void *a, const void *b)
{
	int x = *(const int *)a, y = *(const int *)b;
	return x < y ? -1 : x > y;
}

static int row_end(const plait_tether_block *block, int first)
{
	int end = first + 1;
	while (end < block->count && block->pair[end][0] == block->pair[first][0]) {
		++end;
	}
	return end;
}

/* Most anchors for the rows' counting sort (their pairs are its buckets); more take qsort. */
#define BUCKETED_ANCHORS 256

/* Sorts the rows as compare_rows does: by anchor pair, then particle. Keys are unique, so the
 * order is too: when each pair's rows come in particle order already (the tethers are stored
 * particle by particle), a stable counting sort by pair gives it in linear time (qsort took
 * most of a 512 x 512 cloth's lanes). rank[anchor]: its place among the sorted distinct
 * anchors, of which there are anchor_count. */
static void sort_rows(row_key *keys, int rows, const int *rank, int anchor_count, const plait_allocator *a)
{
	int buckets = anchor_count * anchor_count;
	int *start =
	    anchor_count <= BUCKETED_ANCHORS ? plait_alloc_zero(a, (size_t)buckets + 1, sizeof(int)) : NULL;
	row_key *sorted = start != NULL ? plait_alloc(a, sizeof *sorted * (size_t)(rows > 0 ? rows : 1)) : NULL;
	bool done = false;
	if (sorted != NULL) {
		for (int r = 0; r < rows; ++r) {
			start[rank[keys[r].anchor[0]] * anchor_count + rank[keys[r].anchor[1]] + 1] += 1;
		}
		for (int b = 0; b < buckets; ++b) {
			start[b + 1] += start[b];
		}
		for (int r = 0; r < rows; ++r) {
			sorted[start[rank[keys[r].anchor[0]] * anchor_count + rank[keys[r].anchor[1]]]++] = keys[r];
		}
		done = true;
		for (int r = 1; r < rows && done; ++r) {
			done = compare_rows(&sorted[r - 1], &sorted[r]) < 0;
		}
		if (done) {
			memcpy(keys, sorted, sizeof *keys * (size_t)rows);
		}
	}
	plait_free(a, sorted);
	plait_free(a, start);
	if (!done) {
		qsort(keys, (size_t)rows, sizeof *keys, compare_rows);
	}
}

static bool derive_lanes(plait_tether_block *block, int particle_count, const plait_allocator *a)
{
	plait_tether_lanes_destroy(block, a);
	int rows = 0, runs = 0, other_tethers = 0;
	for (int first = 0, end; first < block->count; first = end) {
		end = row_end(block, first);
		if (end - first == 2) {
			++rows;
		} else {
			other_tethers += end - first;
		}
	}
	plait_tether_lanes *lanes = plait_alloc_zero(a, 1, sizeof *lanes);
	if (lanes == NULL) {
		return false;
	}
	block->lanes = lanes;
	size_t n = (size_t)(rows > 0 ? rows : 1), m = (size_t)(other_tethers > 0 ? other_tethers : 1);
	row_key *keys = plait_alloc_zero(a, n, sizeof *keys);
	lanes->particle = plait_alloc_zero(a, n, sizeof(int));
	lanes->length[0] = plait_alloc_zero(a, n, sizeof(float));
	lanes->length[1] = plait_alloc_zero(a, n, sizeof(float));
	lanes->runs = plait_alloc_zero(a, n, sizeof(tether_run));
	lanes->others.pair = plait_alloc_zero(a, m, sizeof *lanes->others.pair);
	lanes->others.length = plait_alloc_zero(a, m, sizeof(float));
	lanes->others.stiffness = plait_alloc_zero(a, m, sizeof(float));
	lanes->anchors = plait_alloc_zero(a, (size_t)(block->count > 0 ? block->count : 1), sizeof(int));
	if (lanes->anchors == NULL || keys == NULL || lanes->particle == NULL || lanes->length[0] == NULL ||
	    lanes->length[1] == NULL || lanes->runs == NULL || lanes->others.pair == NULL ||
	    lanes->others.length == NULL || lanes->others.stiffness == NULL) {
		plait_free(a, keys);
		plait_tether_lanes_destroy(block, a);
		return false;
	}
	rows = 0;
	plait_tether_block *others = &lanes->others;
	for (int first = 0, end; first < block->count; first = end) {
		end = row_end(block, first);
		if (end - first == 2) {
			keys[rows++] =
			    (row_key){{block->pair[first][1], block->pair[first + 1][1]}, block->pair[first][0], first};
			continue;
		}
		for (int c = first; c < end; ++c) {
			int k = others->count++;
			others->pair[k][0] = block->pair[c][0];
			others->pair[k][1] = block->pair[c][1];
			others->length[k] = block->length[c];
			others->stiffness[k] = block->stiffness[c];
		}
	}
	others->capacity = others->count;
	/* The distinct anchors, ascending: marked by particle, then the few sorted. */
	int *rank = plait_alloc(a, sizeof(int) * (size_t)(particle_count > 0 ? particle_count : 1));
	if (rank == NULL) {
		plait_free(a, keys);
		plait_tether_lanes_destroy(block, a);
		return false;
	}
	memset(rank, 0xff, sizeof(int) * (size_t)particle_count);
	for (int c = 0; c < block->count; ++c) {
		int anchor = block->pair[c][1];
		if (rank[anchor] < 0) {
			rank[anchor] = 0;
			lanes->anchors[lanes->anchor_count++] = anchor;
		}
	}
	qsort(lanes->anchors, (size_t)lanes->anchor_count, sizeof(int), compare_ints);
	for (int k = 0; k < lanes->anchor_count; ++k) {
		rank[lanes->anchors[k]] = k;
	}
	lanes->others_in_order = true;
	for (int c = 1; c < others->count; ++c) {
		lanes->others_in_order = lanes->others_in_order && others->pair[c][0] >= others->pair[c - 1][0];
	}
	sort_rows(keys, rows, rank, lanes->anchor_count, a);
	plait_free(a, rank);
	for (int r = 0; r < rows; ++r) {
		int first = keys[r].first;
		lanes->particle[r] = keys[r].particle;
		lanes->length[0][r] = block->length[first];
		lanes->length[1][r] = block->length[first + 1];
		/* A run's rows share their anchors and their stiffness (a cloth's pins tether only
		 * that cloth, whose tethers share one stiffness; rows that did not would start a run). */
		float stiffness = block->stiffness[first];
		if (r == 0 || keys[r].anchor[0] != keys[r - 1].anchor[0] ||
		    keys[r].anchor[1] != keys[r - 1].anchor[1] || stiffness != lanes->runs[runs - 1].stiffness) {
			lanes->runs[runs++] = (tether_run){{keys[r].anchor[0], keys[r].anchor[1]}, stiffness, r, r};
		}
		lanes->runs[runs - 1].end = r + 1;
	}
	lanes->count = rows;
	lanes->run_count = runs;
	plait_free(a, keys);
	return true;
}

/* A batch of rows of one run. First, over every row, which are taut (in a loop without
 * branches: slack rows come in patches the branch predictor cannot learn); then the taut ones,
 * packed, lane by lane over coordinate arrays with selects instead of branches, which the
 * compiler vectorises. As project_row: the projection onto the worst tether if it lies within
 * the other's reach; else, in float, the projection onto the other if it lies within the
 * first's, else the nearest point of the circle where the two spheres meet, or the point where
 * they touch (a vertex on the line between two pins, stretched as far as it goes). Each is kept
 * only if it checks out within both reaches: a thin lens, a small circle from a difference of
 * squares, loses too many digits in float. A lane none of whose candidates checks out goes to
 * project_row_exactly afterwards. */
enum { LANE_BATCH = 128 };

typedef struct lane_batch {
	float px[LANE_BATCH], py[LANE_BATCH], pz[LANE_BATCH], w[LANE_BATCH];
	int taut[LANE_BATCH];
	/* The taut rows, packed: which row, the position and lengths; results: the new position,
	 * and whether it was found (else: the exact search). */
	int row[LANE_BATCH];
	float tx[LANE_BATCH], ty[LANE_BATCH], tz[LANE_BATCH], length[2][LANE_BATCH], stiffness[LANE_BATCH];
	float qx[LANE_BATCH], qy[LANE_BATCH], qz[LANE_BATCH];
	int found[LANE_BATCH];
} lane_batch;

PLAIT_VECTOR_CLONES static void find_taut(lane_batch *restrict batch, vec3 a0, vec3 a1,
                                          const float *restrict length0, const float *restrict length1,
                                          int count)
{
	for (int k = 0; k < count; ++k) {
		vec3 p = {batch->px[k], batch->py[k], batch->pz[k]};
		float d0_sq = v3_length_sq(v3_sub(p, a0)), d1_sq = v3_length_sq(v3_sub(p, a1));
		batch->taut[k] =
		    ((d0_sq > length0[k] * length0[k]) | (d1_sq > length1[k] * length1[k])) & (batch->w[k] != 0.0f);
	}
}

PLAIT_VECTOR_CLONES static void solve_taut(lane_batch *restrict batch, vec3 a0, vec3 a1, int count)
{
	for (int k = 0; k < count; ++k) {
		vec3 p = {batch->tx[k], batch->ty[k], batch->tz[k]};
		float l0 = batch->length[0][k], l1 = batch->length[1][k];
		vec3 d0 = v3_sub(p, a0), d1 = v3_sub(p, a1);
		float d0_sq = v3_length_sq(d0), d1_sq = v3_length_sq(d1);
		/* Excess, <= 0 when slack (sqrt of a rounded square gives the length back). */
		float r0 = sqrtf(d0_sq), r1 = sqrtf(d1_sq);
		float e0 = r0 - l0, e1 = r1 - l1;
		/* project_row: the worst tether (the first on a tie), projected onto; none when both
		 * excesses round to zero. */
		int first_worst = (e0 > 0.0f) & (e0 >= e1);
		int none = (e0 <= 0.0f) & (e1 <= 0.0f);
		vec3 w = v3_select(first_worst, a0, a1), o = v3_select(first_worst, a1, a0);
		float w_length = plait_select(first_worst, l0, l1), o_length = plait_select(first_worst, l1, l0);
		vec3 d = v3_select(first_worst, d0, d1);
		vec3 projected = v3_mul_add(w, w_length / plait_select(first_worst, r0, r1), d); /* r: |d| */
		int within = within_reach(projected, o, o_length);
		/* nearest_in_balls for two: the projection onto the other, then the circle. */
		vec3 from_o = v3_select(first_worst, d1, d0);
		float o_distance_sq = plait_select(first_worst, d1_sq, d0_sq);
		vec3 onto_o = v3_mul_add(o, o_length / plait_select(first_worst, r1, r0), from_o);
		int onto_o_fits = (o_distance_sq > o_length * o_length) & within_reach(onto_o, w, w_length);
		vec3 axis = v3_sub(o, w);
		float axis_sq = v3_length_sq(axis);
		float inverse_axis_sq = 1.0f / plait_select(axis_sq > 0.0f, axis_sq, 1.0f);
		float along = 0.5f * (1.0f + (w_length * w_length - o_length * o_length) * inverse_axis_sq);
		float radius_sq = w_length * w_length - along * along * axis_sq;
		vec3 centre = v3_mul_add(w, along, axis);
		vec3 offset = v3_sub(p, centre);
		vec3 in_plane = v3_mul_add(offset, -v3_dot(offset, axis) * inverse_axis_sq, axis);
		float in_plane_length = v3_length(in_plane);
		float safe_length = plait_select(in_plane_length > 1e-12f, in_plane_length, 1.0f);
		/* Touching spheres (radius_sq <= 0 by rounding) meet at the centre. */
		float reach = plait_select((radius_sq > 0.0f) & (in_plane_length > 1e-12f),
		                           sqrtf(plait_maxf(radius_sq, 0.0f)) / safe_length, 0.0f);
		vec3 on_circle = v3_mul_add(centre, reach, in_plane);
		int circle_fits =
		    (axis_sq > 0.0f) & within_reach(on_circle, w, w_length) & within_reach(on_circle, o, o_length);
		vec3 q = v3_select(within, projected, v3_select(onto_o_fits, onto_o, on_circle));
		q = v3_select(none, p, v3_lerp(p, q, batch->stiffness[k]));
		batch->qx[k] = q.x;
		batch->qy[k] = q.y;
		batch->qz[k] = q.z;
		batch->found[k] = none | within | onto_o_fits | circle_fits;
	}
}

typedef struct tether_job {
	plait_tether_block *block;
	plait_point *points;
	bool fixed_anchors;
	bool avx2;   /* lanes by plait_tether_rows_avx2 */
	bool avx512; /* or by plait_tether_rows_avx512 */
} tether_job;

/* Rows [begin, end) of the lanes; each writes its own particle only. */
static void lane_range(void *context, int begin, int end)
{
	tether_job *job = context;
	const plait_tether_block *block = job->block;
	const plait_tether_lanes *lanes = block->lanes;
	plait_point *points = job->points;
	int r = 0;
	while (lanes->runs[r].end <= begin) {
		++r; /* few runs: one per pair of pins that are some vertex's two nearest */
	}
	lane_batch batch;
	for (; r < lanes->run_count && lanes->runs[r].begin < end; ++r) {
		const tether_run *run = &lanes->runs[r];
		vec3 a0 = points[run->anchor[0]].x, a1 = points[run->anchor[1]].x;
		int run_begin = run->begin > begin ? run->begin : begin, run_end = run->end < end ? run->end : end;
#if PLAIT_X86_KERNELS
		if (job->avx2) {
			for (int b = run_begin; b < run_end; b += LANE_BATCH) {
				int count = run_end - b < LANE_BATCH ? run_end - b : LANE_BATCH;
				int unfound[LANE_BATCH];
				int missing =
				    job->avx512 ? plait_tether_rows_avx512(points, lanes->particle + b, lanes->length[0] + b,
				                                           lanes->length[1] + b, run->stiffness, a0, a1,
				                                           count, (float)INSIDE_TOLERANCE, unfound)
				                : plait_tether_rows_avx2(points, lanes->particle + b, lanes->length[0] + b,
				                                         lanes->length[1] + b, run->stiffness, a0, a1, count,
				                                         (float)INSIDE_TOLERANCE, unfound);
				for (int m = 0; m < missing; ++m) {
					int row = b + unfound[m];
					project_pair_exactly(points, lanes->particle[row], run->anchor, lanes->length[0][row],
					                     lanes->length[1][row], run->stiffness);
				}
			}
			continue;
		}
#endif
		for (int b = run_begin; b < run_end; b += LANE_BATCH) {
			int count = run_end - b < LANE_BATCH ? run_end - b : LANE_BATCH;
			const int *particle = lanes->particle + b;
			for (int k = 0; k < count; ++k) {
				plait_load_point(&points[particle[k]], &batch.px[k], &batch.py[k], &batch.pz[k], &batch.w[k]);
			}
			const float *length0 = lanes->length[0] + b, *length1 = lanes->length[1] + b;
			find_taut(&batch, a0, a1, length0, length1, count);
			int taut = 0;
			for (int k = 0; k < count; ++k) {
				/* Written for every row, kept for the taut: packing without branches. */
				batch.row[taut] = k;
				batch.tx[taut] = batch.px[k];
				batch.ty[taut] = batch.py[k];
				batch.tz[taut] = batch.pz[k];
				batch.length[0][taut] = length0[k];
				batch.length[1][taut] = length1[k];
				batch.stiffness[taut] = run->stiffness;
				taut += batch.taut[k];
			}
			solve_taut(&batch, a0, a1, taut);
			for (int t = 0; t < taut; ++t) {
				int k = batch.row[t];
				if (batch.found[t]) {
					plait_store_point(&points[particle[k]], batch.qx[t], batch.qy[t], batch.qz[t],
					                  batch.w[k]);
				} else {
					project_pair_exactly(points, particle[k], run->anchor, length0[k], length1[k],
					                     run->stiffness);
				}
			}
		}
	}
}

static void tether_range(void *context, int begin, int end)
{
	tether_job *job = context;
	const plait_tether_block *block = job->block;
	plait_point *points = job->points;
	/* A particle's tethers are consecutive and solved together, so a range takes the particles
	 * whose first tether lies in it, whole: ranges never share a particle. */
	while (begin > 0 && begin < end && block->pair[begin][0] == block->pair[begin - 1][0]) {
		++begin;
	}
	if (begin >= end) {
		return; /* inside one particle's row: the range holding its start takes it */
	}
	while (end < block->count && block->pair[end][0] == block->pair[end - 1][0]) {
		++end;
	}
	if (!job->fixed_anchors) {
		for (int c = begin; c < end; ++c) {
			project_tether(block, points, c);
		}
		return;
	}
	/* First which tethers are taut, in a loop without branches (most are slack, in patches the
	 * branch predictor cannot learn); then the particles with a taut one. Projecting a
	 * particle changes no other's test: anchors are pins. */
	enum { CHUNK = 256 };
	uint8_t taut[CHUNK + MAX_ROW];
	for (int chunk = begin, chunk_end; chunk < end; chunk = chunk_end) {
		/* Chunks end where a row does: each particle is tested and projected once. */
		chunk_end = chunk + CHUNK < end ? chunk + CHUNK : end;
		while (chunk_end < end && block->pair[chunk_end][0] == block->pair[chunk_end - 1][0]) {
			++chunk_end; /* at most MAX_ROW - 1 more: rows are that short */
		}
		for (int c = chunk; c < chunk_end; ++c) {
			vec3 d = v3_sub(points[block->pair[c][0]].x, points[block->pair[c][1]].x);
			taut[c - chunk] = v3_length_sq(d) > block->length[c] * block->length[c];
		}
		for (int c = chunk; c < chunk_end; ++c) {
			if (!taut[c - chunk]) {
				continue;
			}
			/* The particle's whole row; its later tethers are then skipped. */
			int particle = block->pair[c][0];
			int first = c;
			while (first > chunk && block->pair[first - 1][0] == particle) {
				--first;
			}
			int end_of_row = c + 1;
			while (end_of_row < chunk_end && block->pair[end_of_row][0] == particle) {
				++end_of_row;
			}
			if (end_of_row - first == 1 || end_of_row - first > MAX_ROW) {
				for (int k = first; k < end_of_row; ++k) {
					project_tether(block, points, k);
				}
			} else {
				project_row(block, points, first, end_of_row);
			}
			c = end_of_row - 1;
		}
	}
}

void plait_tethers_begin_frame(plait_tether_block *block, const plait_particles *particles,
                               const plait_allocator *allocator)
{
	/* Anchors are few and each is met by many tethers: once lanes are derived, their list of
	 * distinct anchors is checked instead of every tether's. */
	const plait_tether_lanes *lanes = block->lanes_stale ? NULL : block->lanes;
	int checks = lanes != NULL ? lanes->anchor_count : block->count;
	bool fixed_anchors = true, still_anchors = true, negative_zero = false;
	for (int c = 0; c < checks && fixed_anchors; ++c) {
		int anchor = lanes != NULL ? lanes->anchors[c] : block->pair[c][1];
		fixed_anchors = particles->point[anchor].w == 0.0f;
		/* Where it is, it stays over the frame (bit for bit: v3_lerp of equal ends is exact). */
		vec3 x = particles->point[anchor].x, a = particles->pin_start[anchor], b = particles->pin_end[anchor];
		still_anchors = still_anchors && memcmp(&x, &a, sizeof x) == 0 && memcmp(&a, &b, sizeof a) == 0;
		negative_zero = negative_zero || (x.x == 0.0f && signbit(x.x)) || (x.y == 0.0f && signbit(x.y)) ||
		                (x.z == 0.0f && signbit(x.z));
	}
	block->fixed_anchors = fixed_anchors;
	block->still_anchors = fixed_anchors && still_anchors;
	block->anchors_keep_bits = block->still_anchors && !negative_zero;
	if (block->lanes_stale || (fixed_anchors && block->lanes == NULL && block->count > 0)) {
		block->lanes_stale = false;
		if (!derive_lanes(block, particles->count, allocator)) {
			block->lanes = NULL; /* solved as stored, more slowly */
		}
	}
}

void plait_solve_tethers(plait_tether_block *block, plait_particles *particles, plait_simd simd,
                         plait_parallel *parallel)
{
	/* Tethers are anchored at pins: then each particle's tethers write that particle only and
	 * particles can run side by side. An anchor set free since (its pin released) is written
	 * too, and then they run in order, each tether on its own. */
	if (!block->fixed_anchors) {
		tether_job job = {block, particles->point, false, false, false};
		tether_range(&job, 0, block->count);
		return;
	}
	if (block->lanes == NULL) {
		tether_job job = {block, particles->point, true, false, false};
		plait_parallel_for(parallel, tether_range, &job, 0, block->count, TETHER_GRAIN);
		return;
	}
	plait_tether_lanes *lanes = block->lanes;
	tether_job rows = {block, particles->point, true, simd != PLAIT_SIMD_SCALAR, simd == PLAIT_SIMD_AVX512};
	plait_parallel_for(parallel, lane_range, &rows, 0, lanes->count, TETHER_GRAIN);
	tether_job others = {&lanes->others, particles->point, true, false, false};
	plait_parallel_for(parallel, tether_range, &others, 0, lanes->others.count, TETHER_GRAIN);
}

bool plait_tethers_by_particle(const plait_tether_block *block)
{
	return block->count == 0 ||
	       (block->still_anchors && block->lanes != NULL && block->lanes->others_in_order);
}

/* The first of values[first, last) (ascending) not below key. */
static int lower_bound(const int *values, int first, int last, int key)
{
	while (first < last) {
		int middle = first + (last - first) / 2;
		if (values[middle] < key) {
			first = middle + 1;
		} else {
			last = middle;
		}
	}
	return first;
}

/* The first of the others' tethers whose particle is not below key (rows are whole). */
static int others_bound(const plait_tether_block *others, int key)
{
	int first = 0, last = others->count;
	while (first < last) {
		int middle = first + (last - first) / 2;
		if (others->pair[middle][0] < key) {
			first = middle + 1;
		} else {
			last = middle;
		}
	}
	return first;
}

bool plait_tethers_on_columns(const plait_tether_block *block)
{
	return block->count == 0 || (plait_tethers_by_particle(block) && block->lanes->others.count == 0);
}

void plait_tether_anchors_to_columns(const plait_tether_block *block, const plait_particles *particles,
                                     const plait_columns *columns)
{
	const plait_tether_lanes *lanes = block->lanes;
	if (block->count == 0 || lanes == NULL) {
		return;
	}
	for (int a = 0; a < lanes->anchor_count; ++a) {
		int i = lanes->anchors[a];
		plait_column_set(columns, i, particles->point[i].x);
		columns->w[i] = particles->point[i].w;
	}
}

void plait_solve_tethers_of_particles_on_columns(plait_tether_block *block, const plait_columns *columns,
                                                 int begin, int end)
{
#if PLAIT_X86_KERNELS
	const plait_tether_lanes *lanes = block->lanes;
	if (block->count == 0 || lanes == NULL) {
		return;
	}
	for (int r = 0; r < lanes->run_count; ++r) {
		const tether_run *run = &lanes->runs[r];
		int first = lower_bound(lanes->particle, run->begin, run->end, begin);
		int last = lower_bound(lanes->particle, first, run->end, end);
		vec3 a0 = plait_column_point(columns, run->anchor[0]).x,
		     a1 = plait_column_point(columns, run->anchor[1]).x;
		for (int b = first; b < last; b += LANE_BATCH) {
			int count = last - b < LANE_BATCH ? last - b : LANE_BATCH;
			int unfound[LANE_BATCH];
			int missing = plait_tether_rows_columns_avx512(columns, lanes->particle + b, lanes->length[0] + b,
			                                               lanes->length[1] + b, run->stiffness, a0, a1,
			                                               count, (float)INSIDE_TOLERANCE, unfound);
			/* The exact search on copies of the row's three points (the anchors are pinned). */
			for (int m = 0; m < missing; ++m) {
				int row = b + unfound[m], i = lanes->particle[row];
				plait_point three[3] = {plait_column_point(columns, i),
				                        plait_column_point(columns, run->anchor[0]),
				                        plait_column_point(columns, run->anchor[1])};
				const int anchors[2] = {1, 2};
				project_pair_exactly(three, 0, anchors, lanes->length[0][row], lanes->length[1][row],
				                     run->stiffness);
				plait_column_set(columns, i, three[0].x);
			}
		}
	}
#else
	(void)block;
	(void)columns;
	(void)begin;
	(void)end;
#endif
}

void plait_solve_tethers_of_particles(plait_tether_block *block, plait_point *points, plait_simd simd,
                                      int begin, int end)
{
	const plait_tether_lanes *lanes = block->lanes;
	if (block->count == 0 || lanes == NULL) {
		return;
	}
	/* Each run's rows are in particle order (compare_rows): the range's rows of a run are one
	 * stretch of it. */
	tether_job rows = {block, points, true, simd != PLAIT_SIMD_SCALAR, simd == PLAIT_SIMD_AVX512};
	for (int r = 0; r < lanes->run_count; ++r) {
		const tether_run *run = &lanes->runs[r];
		int first = lower_bound(lanes->particle, run->begin, run->end, begin);
		int last = lower_bound(lanes->particle, first, run->end, end);
		if (first < last) {
			lane_range(&rows, first, last);
		}
	}
	plait_tether_block *others = (plait_tether_block *)&lanes->others;
	int first = others_bound(others, begin), last = others_bound(others, end);
	if (first < last) {
		tether_job job = {others, points, true, false, false};
		tether_range(&job, first, last);
	}
}
