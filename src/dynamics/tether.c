/* Solving tethers (long-range attachments, seed 004). A particle may have several tethers (to
 * its nearest pins, world/tethers.c): it must end within every one's reach, so it is moved to
 * the nearest point of the intersection of their balls, found exactly rather than by repeated
 * projection. Repeated projection crawls where two balls barely overlap (a vertex halfway
 * between two pins, on the line joining them, is held at the single point where they touch),
 * and left such vertices 0.7% past their tether after eight rounds. */
#include "dynamics/constraints.h"

#include "core/dvec3.h"

#include <math.h>
#include <stdint.h>

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

/* Pulls a particle back within tether c's length of its anchor; returns whether it moved. */
static bool project_tether(const plait_tether_block *block, plait_point *points, int c)
{
	plait_point *p = &points[block->pair[c][0]], *anchor = &points[block->pair[c][1]];
	float w_sum = p->w + anchor->w;
	if (w_sum == 0.0f) {
		return false;
	}
	vec3 d = v3_sub(p->x, anchor->x);
	float length = sqrtf(v3_length_sq(d));
	float excess = length - block->length[c];
	if (excess <= 0.0f) {
		return false;
	}
	vec3 correction = v3_scale(d, block->stiffness[c] * excess / (length * w_sum));
	p->x = v3_mul_add(p->x, -p->w, correction);
	if (anchor->w != 0.0f) {
		anchor->x = v3_mul_add(anchor->x, anchor->w, correction);
	}
	return true;
}

/* The tethers [first, end) of one particle, with anchors that do not move (pins). */
/* Kept out of line: the common case in project_row stays small. */
static __attribute__((noinline)) void project_row_exactly(const plait_tether_block *block,
                                                          plait_point *points, int first, int end)
{
	plait_point *p = &points[block->pair[first][0]];
	ball balls[MAX_ROW];
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

/* Particles with two tethers (a cloth hung from two pins: nearly all of them) are solved a
 * batch at a time, lane by lane over coordinate arrays with selects instead of branches, which
 * the compiler vectorises. As project_row: the projection onto the worst tether if it lies
 * within the other's reach; else, in float, the projection onto the other if it lies within the
 * first's, else the nearest point of the circle where the two spheres meet; each kept only if
 * it checks out within both reaches (a thin lens, a small circle from a difference of squares,
 * loses too many digits in float). A lane none of whose candidates checks out goes to
 * project_row_exactly afterwards. */
enum { PAIR_BATCH = 160 };

typedef struct pair_batch {
	int first[PAIR_BATCH]; /* the row's first tether */
	float px[PAIR_BATCH], py[PAIR_BATCH], pz[PAIR_BATCH];
	float ax[2][PAIR_BATCH], ay[2][PAIR_BATCH], az[2][PAIR_BATCH], length[2][PAIR_BATCH];
	float stiffness[PAIR_BATCH];
	/* Results: the new position, and whether it was found (else: the exact search). */
	float qx[PAIR_BATCH], qy[PAIR_BATCH], qz[PAIR_BATCH];
	int found[PAIR_BATCH];
} pair_batch;

PLAIT_VECTOR_CLONES static void solve_pair_batch(pair_batch *restrict batch, int count)
{
	for (int k = 0; k < count; ++k) {
		vec3 p = {batch->px[k], batch->py[k], batch->pz[k]};
		vec3 a0 = {batch->ax[0][k], batch->ay[0][k], batch->az[0][k]};
		vec3 a1 = {batch->ax[1][k], batch->ay[1][k], batch->az[1][k]};
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
		/* nearest_in_two_balls: the projection onto the other, then the circle. */
		vec3 from_o = v3_select(first_worst, d1, d0);
		float o_distance_sq = plait_select(first_worst, d1_sq, d0_sq);
		vec3 onto_o = v3_mul_add(o, o_length / plait_select(first_worst, r1, r0), from_o);
		int onto_o_fits = (o_distance_sq > o_length * o_length) & within_reach(onto_o, w, w_length);
		vec3 axis = v3_sub(o, w);
		float axis_sq = v3_length_sq(axis);
		float safe_axis_sq = plait_select(axis_sq > 0.0f, axis_sq, 1.0f);
		float along = 0.5f * (1.0f + (w_length * w_length - o_length * o_length) / safe_axis_sq);
		float radius_sq = w_length * w_length - along * along * safe_axis_sq;
		vec3 centre = v3_mul_add(w, along, axis);
		vec3 offset = v3_sub(p, centre);
		vec3 in_plane = v3_mul_add(offset, -v3_dot(offset, axis) / safe_axis_sq, axis);
		float in_plane_length = v3_length(in_plane);
		float safe_length = plait_select(in_plane_length > 1e-12f, in_plane_length, 1.0f);
		vec3 on_circle = v3_mul_add(
		    centre, sqrtf(plait_select(radius_sq > 0.0f, radius_sq, 0.0f)) / safe_length, in_plane);
		int circle_fits = (axis_sq > 0.0f) & (radius_sq > 0.0f) & (in_plane_length > 1e-12f) &
		                  within_reach(on_circle, w, w_length) & within_reach(on_circle, o, o_length);
		vec3 q = v3_select(within, projected, v3_select(onto_o_fits, onto_o, on_circle));
		q = v3_select(none, p, v3_lerp(p, q, batch->stiffness[k]));
		batch->qx[k] = q.x;
		batch->qy[k] = q.y;
		batch->qz[k] = q.z;
		batch->found[k] = none | within | onto_o_fits | circle_fits;
	}
}

static void finish_pair_batch(const plait_tether_block *block, plait_point *points, pair_batch *batch,
                              int count)
{
	solve_pair_batch(batch, count);
	for (int k = 0; k < count; ++k) {
		int first = batch->first[k];
		if (batch->found[k]) {
			points[block->pair[first][0]].x = v3(batch->qx[k], batch->qy[k], batch->qz[k]);
		} else {
			project_row_exactly(block, points, first, first + 2);
		}
	}
}

typedef struct tether_job {
	plait_tether_block *block;
	plait_point *points;
	bool fixed_anchors;
} tether_job;

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
	pair_batch pair_lanes; /* a chunk holds at most (CHUNK + MAX_ROW) / 2 rows of two */
	int pairs = 0;
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
			int row_end = c + 1;
			while (row_end < chunk_end && block->pair[row_end][0] == particle) {
				++row_end;
			}
			if (row_end - first == 2) {
				if (points[particle].w != 0.0f) {
					int lane = pairs++;
					pair_lanes.first[lane] = first;
					vec3 x = points[particle].x;
					pair_lanes.px[lane] = x.x;
					pair_lanes.py[lane] = x.y;
					pair_lanes.pz[lane] = x.z;
					for (int m = 0; m < 2; ++m) {
						vec3 a = points[block->pair[first + m][1]].x;
						pair_lanes.ax[m][lane] = a.x;
						pair_lanes.ay[m][lane] = a.y;
						pair_lanes.az[m][lane] = a.z;
						pair_lanes.length[m][lane] = block->length[first + m];
					}
					pair_lanes.stiffness[lane] = block->stiffness[first];
				}
			} else if (row_end - first == 1 || row_end - first > MAX_ROW) {
				for (int k = first; k < row_end; ++k) {
					project_tether(block, points, k);
				}
			} else {
				project_row(block, points, first, row_end);
			}
			c = row_end - 1;
		}
		if (pairs > 0) {
			finish_pair_batch(block, points, &pair_lanes, pairs);
			pairs = 0;
		}
	}
}

void plait_tethers_begin_frame(plait_tether_block *block, const plait_particles *particles)
{
	bool fixed_anchors = true;
	for (int c = 0; c < block->count && fixed_anchors; ++c) {
		fixed_anchors = particles->point[block->pair[c][1]].w == 0.0f;
	}
	block->fixed_anchors = fixed_anchors;
}

void plait_solve_tethers(plait_tether_block *block, plait_particles *particles, plait_parallel *parallel)
{
	/* Tethers are anchored at pins: then each particle's tethers write that particle only and
	 * particles can run side by side. An anchor set free since (its pin released) is written
	 * too, and then they run in order, each tether on its own. */
	tether_job job = {block, particles->point, block->fixed_anchors};
	if (block->fixed_anchors) {
		plait_parallel_for(parallel, tether_range, &job, 0, block->count, TETHER_GRAIN);
	} else {
		tether_range(&job, 0, block->count);
	}
}
