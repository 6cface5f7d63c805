/* The smooth reach of a rigid mesh's corners and edges (smooth_reach.h). */
#include "collision/smooth_reach.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "collision/closest.h"
#include "core/parallel.h"
#include "topology/topology.h"

/* Radians: a face this steep against a feature's reference normal ends its smooth reach. */
#define SMOOTH_STEEPEST 1.0f
/* Its cosine, raised a little: a face turned this far or more is taken for a wall by the bound
 * below (the rounding of acosf must not let through one that the measured faces stop at). */
#define BOUND_STEEP_COS (0.54030231f + 1e-4f)
/* Distance bins of that bound. */
#define BOUND_BINS 32

/* A face in reach of a feature: a lower bound on its distance (its ball's gap, for the faces
 * not measured yet: candidates) or its measured distance and its angle (samples). */
typedef struct face_sample {
	float distance; /* from the feature, scene units (a lower bound); never negative */
	union {
		float angle;  /* samples: against the feature's reference normal, radians */
		int triangle; /* candidates */
	};
} face_sample;

typedef struct feature_query {
	const plait_mesh_shape *shape;
	const bool *open;       /* per triangle: an edge of it is not shared by exactly two */
	const vec3 *centre;     /* per triangle: the centre of a ball that holds it */
	const float *radius;    /* and its radius, rounded up */
	vec3 a, b;              /* a corner (b == a) or an edge */
	int vertex_a, vertex_b; /* their mesh vertices (the same for a corner) */
	bool corner;
	vec3 normal; /* unit reference normal */
	float range;
	float budget;
	/* Room for every triangle each (a query meets each at most once): the faces whose ball is
	 * in range, and those of them measured. */
	face_sample *candidates;
	face_sample *samples;
	int candidate_count, sample_count;
	/* The bound (bound_reaches_range): per bin of BOUND_BINS over [0, range], the least cosine
	 * against the normal of the faces whose ball comes that near; whether it already failed (a
	 * wall in range, or one face enough to lift F past the budget). */
	float bin_cos[BOUND_BINS];
	float bins_per_unit;
	bool bound_failed;
} feature_query;

/* Sorts by distance, through `scratch` (room for count). Distances are never negative, so their
 * bits order as they do: a radix sort, a byte at a time from the lowest (bytes all share are
 * skipped); insertion sort for a few. The reach takes every face within a distance at once, so
 * the order of equal distances does not matter. */
static void sort_by_distance(face_sample *s, face_sample *scratch, int count)
{
	if (count <= 32) {
		for (int i = 1; i < count; ++i) {
			face_sample x = s[i];
			int j = i;
			for (; j > 0 && s[j - 1].distance > x.distance; --j) {
				s[j] = s[j - 1];
			}
			s[j] = x;
		}
		return;
	}
	face_sample *from = s, *to = scratch;
	for (int shift = 0; shift < 32; shift += 8) {
		int start[257] = {0};
		for (int i = 0; i < count; ++i) {
			uint32_t bits;
			memcpy(&bits, &from[i].distance, sizeof bits);
			start[((bits >> shift) & 0xffu) + 1] += 1;
		}
		uint32_t first_bits;
		memcpy(&first_bits, &from[0].distance, sizeof first_bits);
		if (start[((first_bits >> shift) & 0xffu) + 1] == count) {
			continue; /* every sample has this byte */
		}
		for (int b = 0; b < 256; ++b) {
			start[b + 1] += start[b];
		}
		for (int i = 0; i < count; ++i) {
			uint32_t bits;
			memcpy(&bits, &from[i].distance, sizeof bits);
			to[start[(bits >> shift) & 0xffu]++] = from[i];
		}
		face_sample *swap = from;
		from = to;
		to = swap;
	}
	if (from != s) {
		memcpy(s, from, sizeof *s * (size_t)count);
	}
}

/* The distance from a corner or edge to a triangle (an edge through the triangle is at 0). */
static float feature_triangle_distance(vec3 a, vec3 b, bool corner, const vec3 *t)
{
	int region;
	float d = v3_length(v3_sub(a, plait_closest_point_on_triangle(a, t[0], t[1], t[2], &region, NULL)));
	if (corner) {
		return d;
	}
	d = plait_minf(d,
	               v3_length(v3_sub(b, plait_closest_point_on_triangle(b, t[0], t[1], t[2], &region, NULL))));
	for (int k = 0; k < 3; ++k) {
		float s, u;
		d = plait_minf(d, sqrtf(plait_closest_segments(a, b, t[k], t[(k + 1) % 3], &s, &u)));
	}
	vec3 n = v3_cross(v3_sub(t[1], t[0]), v3_sub(t[2], t[0]));
	float da = v3_dot(v3_sub(a, t[0]), n), db = v3_dot(v3_sub(b, t[0]), n);
	if ((da < 0.0f) != (db < 0.0f)) {
		/* Where the edge meets the triangle's plane: inside it, the distance is 0. */
		vec3 x = v3_lerp(a, b, da / (da - db));
		d = plait_minf(
		    d, v3_length(v3_sub(x, plait_closest_point_on_triangle(x, t[0], t[1], t[2], &region, NULL))));
	}
	return d;
}

/* A lower bound on the distance from q's feature to a triangle: to the centre of its ball, less
 * its radius (less an allowance for the rounding of both measures). */
static float ball_gap(const feature_query *q, int triangle)
{
	vec3 c = q->centre[triangle], ab = v3_sub(q->b, q->a);
	float length_sq = v3_dot(ab, ab);
	float s =
	    length_sq > 0.0f ? plait_minf(plait_maxf(v3_dot(v3_sub(c, q->a), ab) / length_sq, 0.0f), 1.0f) : 0.0f;
	float scale =
	    1.0f + v3_largest_abs(c) + v3_largest_abs(q->a) + v3_largest_abs(q->b) + q->radius[triangle];
	return v3_length(v3_sub(c, v3_mul_add(q->a, s, ab))) - q->radius[triangle] - 4e-6f * scale;
}

/* The cosine of a face against q's normal; -1 (a wall) for an open or degenerate face. */
static float face_cos(const feature_query *q, int triangle)
{
	vec3 n = q->shape->normals[triangle];
	return !q->open[triangle] && v3_length_sq(n) > 0.0f ? v3_dot(n, q->normal) : -1.0f;
}

/* A face whose ball is in range becomes a candidate, keyed by a bound on its distance that its
 * measure (measure_face) never falls below: the ball's gap, less the 1e-6 that measure takes
 * off. It also goes into the bound's bins. */
static void collect_face(int triangle, void *context)
{
	feature_query *q = context;
	float gap = ball_gap(q, triangle);
	if (gap > q->range + 1e-6f) {
		return;
	}
	float key = gap - 2e-6f;
	q->candidates[q->candidate_count++] =
	    (face_sample){.distance = key > 0.0f ? key : 0.0f, .triangle = triangle};
	if (q->bound_failed) {
		return;
	}
	float c = face_cos(q, triangle);
	if (!(c > BOUND_STEEP_COS)) {
		q->bound_failed = true;
		return;
	}
	/* Alone, from where it comes in to the range's end, this face may already lift F past the
	 * budget: then the bound fails. */
	float slope = sqrtf(plait_maxf(0.0f, 1.0f - c * c)) / c;
	if (slope * (q->range - plait_maxf(gap, q->budget)) >= 0.99f * q->budget) {
		q->bound_failed = true;
		return;
	}
	int bin = gap > 0.0f ? (int)(gap * q->bins_per_unit) : 0;
	bin = bin < BOUND_BINS ? bin : BOUND_BINS - 1;
	q->bin_cos[bin] = plait_minf(q->bin_cos[bin], c);
}

/* Whether the feature reaches the whole range by the bound, which measures no face: each is
 * taken to be as near as its ball's gap rounded down to its bin's start and to turn at least
 * as far, so that its F grows no slower than the measured faces' and stays under the budget
 * (with a margin for rounding) only where theirs does. On a mesh smooth at the range's scale
 * it passes most features; their faces' distances (closest points) are most of the cost. */
static bool bound_reaches_range(const feature_query *q)
{
	if (q->bound_failed) {
		return false;
	}
	/* The faces of bin b come in at t = b w - budget; F is the integral of the steepest slope
	 * so far, up to D = range - budget. */
	float width = q->range / (float)BOUND_BINS, end_of_range = q->range - q->budget;
	float t = 0.0f, fall = 0.0f, least_cos = 1.0f;
	for (int b = 0; b < BOUND_BINS && t < end_of_range; ++b) {
		least_cos = plait_minf(least_cos, q->bin_cos[b]);
		float until = plait_minf(end_of_range, (float)(b + 1) * width - q->budget);
		if (until > t) {
			float slope = sqrtf(plait_maxf(0.0f, 1.0f - least_cos * least_cos)) / least_cos;
			fall += (1.001f * slope + 1e-6f) * (until - t);
			t = until;
		}
	}
	return fall < 0.99f * q->budget;
}

/* Measures candidate c: a sample unless farther than the range. A face with a vertex of the
 * feature is at 0 (what the measure gives, but for rounding on needles: never more); the others
 * less a rounding allowance, the distance must not be overstated. A face with two vertices at
 * one point has no closest point (0 / 0): its ball's gap stands for its distance. Samples from
 * index `sorted` on are kept in order of distance (the new one is put in its place). */
static void measure_face(feature_query *q, int c, int sorted)
{
	int triangle = q->candidates[c].triangle;
	const int *tri = q->shape->triangles[triangle];
	float distance = 0.0f;
	if (tri[0] != q->vertex_a && tri[1] != q->vertex_a && tri[2] != q->vertex_a && tri[0] != q->vertex_b &&
	    tri[1] != q->vertex_b && tri[2] != q->vertex_b) {
		vec3 t[3] = {q->shape->positions[tri[0]], q->shape->positions[tri[1]], q->shape->positions[tri[2]]};
		float measured = feature_triangle_distance(q->a, q->b, q->corner, t);
		distance = plait_maxf((isnan(measured) ? ball_gap(q, triangle) : measured) - 1e-6f, 0.0f);
	}
	if (distance > q->range) {
		return;
	}
	float angle = acosf(plait_maxf(-1.0f, plait_minf(1.0f, face_cos(q, triangle)))); /* a wall: pi */
	int j = q->sample_count++;
	for (; j > sorted && q->samples[j - 1].distance > distance; --j) {
		q->samples[j] = q->samples[j - 1];
	}
	q->samples[j] = (face_sample){.distance = distance, .angle = angle};
}

/* The longest cloth edge D for which F(D) < budget (M above), at most range - budget (farther
 * faces are not looked at), or 0 from the first wall. Walks out from the feature as the faces
 * come within t + budget, measuring them only as far as the walk needs: candidates in order of
 * their keys, each a bound on its distance, so that once the next candidate's key is past a
 * distance every face within it is a sample. Where the reach ends short of the range (a mesh
 * curved at the cloth's scale) the faces beyond are never measured. */
static float walk_out(feature_query *q)
{
	float budget = q->budget;
	int next = 0, k = 0; /* the next candidate to measure, the next sample to come in */
	float t = 0.0f, fall = 0.0f, steepest = 0.0f;
	for (;;) {
		/* Every face within t + budget measured: */
		while (next < q->candidate_count && q->candidates[next].distance - budget <= t) {
			measure_face(q, next++, k);
		}
		while (k < q->sample_count && q->samples[k].distance - budget <= t) {
			steepest = plait_maxf(steepest, q->samples[k].angle);
			++k;
		}
		if (steepest >= SMOOTH_STEEPEST) {
			return t;
		}
		/* The next face to come in: the nearest sample left once no candidate could be nearer
		 * (measuring one may put a nearer sample first). */
		for (;;) {
			if (k < q->sample_count && next < q->candidate_count &&
			    q->candidates[next].distance <= q->samples[k].distance) {
				measure_face(q, next++, k);
			} else if (k == q->sample_count && next < q->candidate_count) {
				measure_face(q, next++, k);
			} else {
				break;
			}
		}
		float end = q->range - budget;
		float step_to = k < q->sample_count ? q->samples[k].distance - budget : end;
		float slope = tanf(steepest);
		if (fall + slope * (step_to - t) >= budget) {
			return t + (budget - fall) / slope;
		}
		if (k >= q->sample_count) {
			return step_to;
		}
		fall += slope * (step_to - t);
		t = step_to;
	}
}

/* The smooth reach of q's feature: faces in range collected once (a box query), then the bound,
 * then, where it fails, the walk. */
static float smooth_reach(feature_query *q)
{
	vec3 lower = v3_min(q->a, q->b), upper = v3_max(q->a, q->b);
	vec3 grow = v3(q->range, q->range, q->range);
	q->candidate_count = 0;
	for (int b = 0; b < BOUND_BINS; ++b) {
		q->bin_cos[b] = 1.0f;
	}
	q->bins_per_unit = (float)BOUND_BINS / q->range;
	q->bound_failed = false;
	plait_mesh_shape_visit(q->shape, v3_sub(lower, grow), v3_add(upper, grow), true, collect_face, q);
	if (bound_reaches_range(q)) {
		return q->range - q->budget;
	}
	sort_by_distance(q->candidates, q->samples, q->candidate_count); /* none measured yet */
	q->sample_count = 0;
	return walk_out(q);
}

/* ---- Clusters ------------------------------------------------------------------------------ */

/* Where a mesh is fine against the range (a limb in 20,000 triangles under a cloth of 16 mm
 * triangles), a feature's faces within its reach are hundreds, and measuring them for every
 * feature costs with the square of the density. There, features are taken together: the reach
 * of a cluster, a node of the mesh's tree whose box is small against the range, holds for every
 * corner and edge in it. The argument (mesh_contact_features.c) holds at any point x of the
 * box with the cluster's mean normal for n0 (the argument asks only that the faces turn less
 * than a radian from it), counting faces from where their balls come within t + M of the box:
 * all those within t + M of x come in no later. No closest point is measured. Such a reach is
 * shorter than the feature's own by about the box's width, so a cluster whose reach ends short
 * of the range and is wide against it is measured in halves instead (CLUSTER_REFINE), down to
 * CLUSTER_LEAST triangles: on a ball of radius 5 cm in 19,800 triangles, edges reach 83% of
 * their own reaches on the mean, set up 54 times faster. An edge in two clusters takes the longer
 * of their reaches, a corner the longest of its triangles'. Coarser meshes, whose nodes of
 * CLUSTER_LEAST triangles are wider than CLUSTER_WIDEST of the range, keep the features' own
 * reaches (every bench scene's sphere, and a smooth ball in 80,000 triangles: most of its
 * features pass the bound above anyway). */
#define CLUSTER_LEAST 8      /* triangles */
#define CLUSTER_WIDEST 0.25f /* of the range: a cluster box's diagonal at most */
#define CLUSTER_REFINE 0.5f  /* of its reach: a cluster wider is measured in halves */
/* A reach not measured yet (reaches are -1 or more). */
#define UNMEASURED (-3.0f)

typedef struct cluster {
	int node;
	vec3 lower, upper; /* its node's box */
	int first, count;  /* its slots */
} cluster;

/* The slots under each node: [first[node], end[node]). */
static void node_slots(const plait_mesh_shape *shape, int node, int *first, int *end)
{
	const plait_bvh_node *n = &shape->nodes[node];
	if (n->count > 0) {
		first[node] = n->first;
		end[node] = n->first + n->count;
		return;
	}
	node_slots(shape, n->first, first, end);
	node_slots(shape, n->first + 1, first, end);
	first[node] = first[n->first];
	end[node] = end[n->first + 1];
}

/* The highest nodes whose box fits `widest` (a diagonal) and that hold at least CLUSTER_LEAST
 * triangles, in tree order; returns how many (out has room for a triangle count's). */
static int find_clusters(const plait_mesh_shape *shape, float widest, const int *first, const int *end,
                         int *stack, cluster *out)
{
	int count = 0, depth = 0;
	stack[depth++] = 0;
	while (depth > 0) {
		int node = stack[--depth];
		const plait_bvh_node *n = &shape->nodes[node];
		if (v3_length(v3_sub(n->upper, n->lower)) <= widest) {
			if (end[node] - first[node] >= CLUSTER_LEAST) {
				out[count++] = (cluster){node, n->lower, n->upper, first[node], end[node] - first[node]};
			}
			continue;
		}
		if (n->count == 0) {
			stack[depth++] = n->first + 1;
			stack[depth++] = n->first;
		}
	}
	return count;
}

/* A candidate of a cluster: a lower bound on its distance from the box [q->a, q->b], from the
 * box to its ball. */
static void collect_for_cluster(int triangle, void *context)
{
	feature_query *q = context;
	vec3 c = q->centre[triangle];
	vec3 nearest = v3_min(v3_max(c, q->a), q->b);
	float scale = 1.0f + v3_largest_abs(c) + v3_largest_abs(nearest) + q->radius[triangle];
	float gap = v3_length(v3_sub(c, nearest)) - q->radius[triangle] - 4e-6f * scale;
	if (gap > q->range + 1e-6f) {
		return;
	}
	q->candidates[q->candidate_count++] =
	    (face_sample){.distance = gap > 0.0f ? gap : 0.0f, .triangle = triangle};
}

/* The reach over candidates sorted by their distance bounds, each taken as near as its bound
 * and with its angle against `normal` (a wall: pi), those past `range` not looked at: the walk
 * of walk_out over faces that are not measured. */
static float walk_bounds(const feature_query *q, vec3 normal, float range)
{
	const face_sample *s = q->candidates;
	int count = q->candidate_count;
	float budget = q->budget, t = 0.0f, fall = 0.0f, steepest = 0.0f;
	int k = 0;
	for (;;) {
		while (k < count && s[k].distance <= range && s[k].distance - budget <= t) {
			vec3 n = q->shape->normals[s[k].triangle];
			float c = !q->open[s[k].triangle] && v3_length_sq(n) > 0.0f ? v3_dot(n, normal) : -1.0f;
			steepest = plait_maxf(steepest, acosf(plait_maxf(-1.0f, plait_minf(1.0f, c))));
			++k;
		}
		if (steepest >= SMOOTH_STEEPEST) {
			return t;
		}
		bool more = k < count && s[k].distance <= range;
		float step_to = more ? s[k].distance - budget : range - budget;
		float slope = tanf(steepest);
		if (fall + slope * (step_to - t) >= budget) {
			return t + (budget - fall) / slope;
		}
		if (!more) {
			return step_to;
		}
		fall += slope * (step_to - t);
		t = step_to;
	}
}

/* Collects and sorts a cluster's candidates (q->range out from its box) and returns the reach
 * of the cluster as a whole, with its mean normal (-1 where its normals cancel out). */
static float collect_cluster(feature_query *q, const cluster *c, vec3 *normal)
{
	const plait_mesh_shape *shape = q->shape;
	vec3 sum = v3(0.0f, 0.0f, 0.0f);
	for (int k = c->first; k < c->first + c->count; ++k) {
		sum = v3_add(sum, shape->normals[shape->triangle_order[k]]);
	}
	q->a = c->lower;
	q->b = c->upper;
	q->candidate_count = 0;
	vec3 grow = v3(q->range, q->range, q->range);
	plait_mesh_shape_visit(shape, v3_sub(c->lower, grow), v3_add(c->upper, grow), true, collect_for_cluster,
	                       q);
	sort_by_distance(q->candidates, q->samples, q->candidate_count);
	float length = v3_length(sum);
	*normal = length > 0.5f * (float)c->count ? v3_scale(sum, 1.0f / length) : v3(0.0f, 0.0f, 0.0f);
	return v3_length_sq(*normal) > 0.0f ? walk_bounds(q, *normal, q->range) : -1.0f;
}

/* How far a feature's faces need sampling: F(D) >= D tan A(0), and A(0) is at least the angle
 * of its own faces against its normal (cosine `own`), so its reach stays under budget / tan of
 * that. (Sampling less only lowers reaches.) */
static float capped_range(float range, float budget, float own)
{
	float angle = acosf(plait_maxf(-1.0f, plait_minf(1.0f, own)));
	if (angle >= SMOOTH_STEEPEST) {
		return budget; /* reach 0 */
	}
	float slope = tanf(angle);
	return slope > 0.0f ? plait_minf(range, budget + 1.01f * budget / slope) : range;
}

/* The mean of unit normals, made unit; zero when they cancel out (no side to stand on). */
static vec3 reference_normal(vec3 sum, int count)
{
	float length = v3_length(sum);
	return length > 0.5f * (float)count ? v3_scale(sum, 1.0f / length) : v3(0.0f, 0.0f, 0.0f);
}

/* Features are measured side by side on the workers, a chunk each with its own samples (each
 * feature's reach depends only on the shape, so the results are the same on any number). */
typedef struct reach_job {
	feature_query base; /* shape, open, centres and radii, range */
	float budget;
	const plait_triangle_edge *edges;
	const int *runs;     /* edges: the first key of each manifold edge's run */
	const vec3 *normals; /* corners: each vertex's summed face normals */
	const int *star;
	const float *star_cos;
	float *edge_reach;    /* by first key */
	float *vertex_reach;  /* corners: in (the least of its edges'), out */
	face_sample *samples; /* room for twice a triangle count per chunk */
	int grain;
	const cluster *clusters;
	const int *node_end;       /* past the last slot under each node */
	float *triangle_reach;     /* per triangle: its cluster's reach, or UNMEASURED */
	vec3 *triangle_normal;     /* and that cluster's normal */
	const float *corner_reach; /* per vertex: the longest of its triangles' clusters', or UNMEASURED */
	const vec3 *corner_normal; /* and that cluster's normal */
	vec3 *edge_normal_out;     /* by first key: the normal its reach holds with (or NULL) */
	vec3 *vertex_normal_out;   /* per vertex: that of its own reach (or NULL) */
} reach_job;

static feature_query chunk_query(const reach_job *job, int begin)
{
	feature_query q = job->base;
	size_t room = (size_t)job->base.shape->triangle_count;
	q.candidates = job->samples + (size_t)(begin / job->grain) * 2 * room;
	q.samples = q.candidates + room;
	return q;
}

/* A cluster's reach with its normal, written to its triangles. Where it ends short of the
 * range and the cluster is wide against it, its two halves are measured instead (each a
 * cluster when it holds enough triangles), so that the box's width takes off little of it. */
static void refine_cluster(const reach_job *job, feature_query *q, const cluster *c)
{
	const plait_mesh_shape *shape = q->shape;
	vec3 normal;
	float reach = collect_cluster(q, c, &normal);
	const plait_bvh_node *n = &shape->nodes[c->node];
	float width = v3_length(v3_sub(c->upper, c->lower));
	if (reach >= 0.0f && reach < 0.999f * (q->range - q->budget) && n->count == 0 &&
	    width > CLUSTER_REFINE * reach) {
		int left = n->first, right = n->first + 1;
		int split = job->node_end[left];
		if (split - c->first >= CLUSTER_LEAST && c->first + c->count - split >= CLUSTER_LEAST) {
			const plait_bvh_node *l = &shape->nodes[left], *r = &shape->nodes[right];
			cluster halves[2] = {{left, l->lower, l->upper, c->first, split - c->first},
			                     {right, r->lower, r->upper, split, c->first + c->count - split}};
			refine_cluster(job, q, &halves[0]);
			refine_cluster(job, q, &halves[1]);
			return;
		}
	}
	for (int k = c->first; k < c->first + c->count; ++k) {
		int t = shape->triangle_order[k];
		job->triangle_reach[t] = reach >= 0.0f ? reach : UNMEASURED;
		job->triangle_normal[t] = normal;
	}
}

static void cluster_reaches(void *context, int begin, int end)
{
	const reach_job *job = context;
	feature_query q = chunk_query(job, begin);
	for (int k = begin; k < end; ++k) {
		refine_cluster(job, &q, &job->clusters[k]);
	}
}

static void edge_reaches(void *context, int begin, int end)
{
	const reach_job *job = context;
	feature_query q = chunk_query(job, begin);
	const plait_mesh_shape *shape = q.shape;
	float range = q.range;
	for (int r = begin; r < end; ++r) {
		const plait_triangle_edge *edge = &job->edges[job->runs[r]];
		/* In a cluster's box (either triangle's), it takes the longer of their reaches. */
		int t = job->triangle_reach[edge[0].triangle] >= job->triangle_reach[edge[1].triangle]
		            ? edge[0].triangle
		            : edge[1].triangle;
		if (job->triangle_reach[t] != UNMEASURED) {
			job->edge_reach[job->runs[r]] = job->triangle_reach[t];
			if (job->edge_normal_out != NULL) {
				job->edge_normal_out[job->runs[r]] = job->triangle_normal[t];
			}
			continue;
		}
		q.a = shape->positions[edge[0].low];
		q.b = shape->positions[edge[0].high];
		q.vertex_a = edge[0].low;
		q.vertex_b = edge[0].high;
		q.corner = false;
		q.normal =
		    reference_normal(v3_add(shape->normals[edge[0].triangle], shape->normals[edge[1].triangle]), 2);
		q.range = capped_range(range, job->budget, v3_dot(q.normal, shape->normals[edge[0].triangle]));
		job->edge_reach[job->runs[r]] = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q) : -1.0f;
		if (job->edge_normal_out != NULL) {
			job->edge_normal_out[job->runs[r]] = q.normal;
		}
	}
}

static void corner_reaches(void *context, int begin, int end)
{
	const reach_job *job = context;
	feature_query q = chunk_query(job, begin);
	const plait_mesh_shape *shape = q.shape;
	float range = q.range;
	for (int v = begin; v < end; ++v) {
		if (job->star[v] == 0 || !(job->vertex_reach[v] > 0.0f)) {
			continue;
		}
		/* In clusters' boxes, it takes the longest of their reaches (corner_cluster). */
		if (job->corner_reach[v] != UNMEASURED) {
			job->vertex_reach[v] = plait_minf(job->vertex_reach[v], job->corner_reach[v]);
			if (job->vertex_normal_out != NULL) {
				job->vertex_normal_out[v] = job->corner_normal[v];
			}
			continue;
		}
		q.a = q.b = shape->positions[v];
		q.vertex_a = q.vertex_b = v;
		q.corner = true;
		q.normal = reference_normal(job->normals[v], job->star[v]);
		q.range = capped_range(range, job->budget, job->star_cos[v]);
		float reach = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q) : -1.0f;
		job->vertex_reach[v] = plait_minf(job->vertex_reach[v], reach);
		if (job->vertex_normal_out != NULL) {
			job->vertex_normal_out[v] = q.normal;
		}
	}
}

static void run_chunks(plait_parallel *parallel, plait_range_fn *fn, void *context, int count, int grain)
{
	if (count > 0 && parallel != NULL) {
		plait_parallel_for(parallel, fn, context, 0, count, grain);
	} else if (count > 0) {
		fn(context, 0, count);
	}
}

/* Chunks per worker: enough for an even share when features cost unevenly; at most
 * MOST_CHUNKS, each with room for a sample of every triangle. */
#define CHUNKS_PER_WORKER 4
#define MOST_CHUNKS 64

/* Features [0, count) cut into at most `chunks` chunks. */
static int chunk_grain(int count, int chunks)
{
	int per_chunk = (count + chunks - 1) / chunks;
	return per_chunk > 0 ? per_chunk : 1;
}

bool plait_mesh_smooth_reaches_with_normals(const plait_mesh_shape *shape, const plait_allocator *a,
                                            plait_parallel *parallel, float budget, float range,
                                            float *vertex_reach_out, float *edge_reach_out,
                                            vec3 *vertex_normal_out, vec3 *edge_normal_out)
{
	bool normals_out = vertex_normal_out != NULL && edge_normal_out != NULL;
	int nt = shape->triangle_count, nv = shape->vertex_count;
	int chunks = CHUNKS_PER_WORKER * (parallel != NULL ? parallel->worker_count : 1);
	chunks = chunks < MOST_CHUNKS ? chunks : MOST_CHUNKS;
	plait_triangle_edge *edges = plait_alloc(a, sizeof *edges * (size_t)(3 * nt + 1));
	int *edge_of = plait_alloc(a, sizeof(int) * (size_t)(3 * nt + 1)); /* (t, k) -> first key of its run */
	int *runs = plait_alloc(a, sizeof(int) * (size_t)(3 * nt + 1));
	bool *open = plait_alloc_zero(a, (size_t)nt + 1, sizeof(bool));
	float *edge_reach = plait_alloc(a, sizeof(float) * (size_t)(3 * nt + 1));
	float *vertex_reach = plait_alloc(a, sizeof(float) * (size_t)(nv + 1));
	vec3 *vertex_normal = plait_alloc_zero(a, (size_t)nv + 1, sizeof(vec3));
	int *star = plait_alloc_zero(a, (size_t)nv + 1, sizeof(int));
	float *star_cos = plait_alloc(a, sizeof(float) * (size_t)(nv + 1)); /* of the steepest face of its star */
	vec3 *centre = plait_alloc(a, sizeof(vec3) * (size_t)(nt + 1));
	float *radius = plait_alloc(a, sizeof(float) * (size_t)(nt + 1));
	face_sample *samples = plait_alloc(a, sizeof *samples * (size_t)chunks * 2 * (size_t)(nt + 1));
	int node_count = shape->node_count > 0 ? shape->node_count : 1;
	int *node_first = plait_alloc(a, sizeof(int) * (size_t)node_count);
	int *node_end = plait_alloc(a, sizeof(int) * (size_t)node_count);
	int *stack = plait_alloc(a, sizeof(int) * (size_t)node_count);
	cluster *clusters = plait_alloc(a, sizeof *clusters * (size_t)(nt / CLUSTER_LEAST + 1));
	float *triangle_reach = plait_alloc(a, sizeof(float) * (size_t)(nt + 1));
	vec3 *triangle_normal = plait_alloc(a, sizeof(vec3) * (size_t)(nt + 1));
	float *corner_reach = plait_alloc(a, sizeof(float) * (size_t)(nv + 1));
	vec3 *corner_normal = plait_alloc(a, sizeof(vec3) * (size_t)(nv + 1));
	vec3 *edge_normal = normals_out ? plait_alloc(a, sizeof(vec3) * (size_t)(3 * nt + 1)) : NULL;
	bool ok = edges != NULL && edge_of != NULL && runs != NULL && open != NULL && edge_reach != NULL &&
	          vertex_reach != NULL && vertex_normal != NULL && star != NULL && star_cos != NULL &&
	          centre != NULL && radius != NULL && samples != NULL && node_first != NULL && node_end != NULL &&
	          stack != NULL && clusters != NULL && triangle_reach != NULL && triangle_normal != NULL &&
	          corner_reach != NULL && corner_normal != NULL && (!normals_out || edge_normal != NULL);
	if (ok) {
		for (int t = 0; t < nt; ++t) {
			const int *tri = shape->triangles[t];
			vec3 p0 = shape->positions[tri[0]], p1 = shape->positions[tri[1]], p2 = shape->positions[tri[2]];
			vec3 c = v3_scale(v3_add(p0, v3_add(p1, p2)), 1.0f / 3.0f);
			float far_sq = plait_maxf(v3_length_sq(v3_sub(p0, c)),
			                          plait_maxf(v3_length_sq(v3_sub(p1, c)), v3_length_sq(v3_sub(p2, c))));
			centre[t] = c;
			radius[t] = 1.00001f * sqrtf(far_sq); /* rounded up: the ball must hold the face */
			for (int k = 0; k < 3; ++k) {
				int i = tri[k], j = tri[(k + 1) % 3];
				edges[3 * t + k] = (plait_triangle_edge){i < j ? i : j, i < j ? j : i, t, k};
				vertex_normal[i] = v3_add(vertex_normal[i], shape->normals[t]);
				star[i] += 1;
			}
		}
		for (int v = 0; v < nv; ++v) {
			vertex_reach[v] = range - budget;
			star_cos[v] = 1.0f;
		}
		plait_sort_triangle_edges(edges, 3 * nt);
		int run_count = 0;
		for (int start = 0; start < 3 * nt;) {
			int end = start + 1;
			while (end < 3 * nt && edges[end].low == edges[start].low &&
			       edges[end].high == edges[start].high) {
				++end;
			}
			for (int k = start; k < end; ++k) {
				edge_of[3 * edges[k].triangle + edges[k].corner] = start;
				open[edges[k].triangle] = open[edges[k].triangle] || end - start != 2;
			}
			if (end - start == 2) {
				edge_reach[start] = UNMEASURED;
				runs[run_count++] = start;
			} else {
				/* Open or shared by more than two: no reach, nor for its ends. */
				edge_reach[start] = -1.0f;
				vertex_reach[edges[start].low] = -1.0f;
				vertex_reach[edges[start].high] = -1.0f;
			}
			start = end;
		}
		for (int t = 0; t < nt; ++t) {
			for (int k = 0; k < 3; ++k) {
				int v = shape->triangles[t][k];
				vec3 n0 = reference_normal(vertex_normal[v], star[v]);
				star_cos[v] = plait_minf(star_cos[v], v3_dot(n0, shape->normals[t]));
			}
		}
		reach_job job = {.base = {.shape = shape,
		                          .open = open,
		                          .centre = centre,
		                          .radius = radius,
		                          .range = range,
		                          .budget = budget},
		                 .budget = budget,
		                 .edges = edges,
		                 .runs = runs,
		                 .normals = vertex_normal,
		                 .star = star,
		                 .star_cos = star_cos,
		                 .edge_reach = edge_reach,
		                 .vertex_reach = vertex_reach,
		                 .samples = samples};
		/* Clusters first, then the edges and corners outside them; edges before corners: a
		 * corner is kept whenever an edge of it is. */
		int cluster_count = 0;
		if (shape->node_count > 0) {
			node_slots(shape, 0, node_first, node_end);
			cluster_count =
			    find_clusters(shape, CLUSTER_WIDEST * range, node_first, node_end, stack, clusters);
		}
		for (int t = 0; t < nt; ++t) {
			triangle_reach[t] = UNMEASURED;
		}
		job.clusters = clusters;
		job.node_end = node_end;
		job.triangle_reach = triangle_reach;
		job.triangle_normal = triangle_normal;
		job.grain = chunk_grain(cluster_count, chunks);
		run_chunks(parallel, cluster_reaches, &job, cluster_count, job.grain);
		for (int v = 0; v < nv; ++v) {
			corner_reach[v] = UNMEASURED;
		}
		for (int t = 0; t < nt; ++t) {
			for (int c = 0; c < 3; ++c) {
				int v = shape->triangles[t][c];
				if (triangle_reach[t] > corner_reach[v]) {
					corner_reach[v] = triangle_reach[t];
					corner_normal[v] = triangle_normal[t];
				}
			}
		}
		job.corner_reach = corner_reach;
		job.corner_normal = corner_normal;
		job.edge_normal_out = edge_normal;
		job.vertex_normal_out = vertex_normal_out;
		if (normals_out) {
			for (int v = 0; v < nv; ++v) {
				vertex_normal_out[v] = reference_normal(vertex_normal[v], star[v]);
			}
		}
		job.grain = chunk_grain(run_count, chunks);
		run_chunks(parallel, edge_reaches, &job, run_count, job.grain);
		for (int r = 0; r < run_count; ++r) {
			const plait_triangle_edge *edge = &edges[runs[r]];
			vertex_reach[edge->low] = plait_minf(vertex_reach[edge->low], edge_reach[runs[r]]);
			vertex_reach[edge->high] = plait_minf(vertex_reach[edge->high], edge_reach[runs[r]]);
		}
		job.grain = chunk_grain(nv, chunks);
		run_chunks(parallel, corner_reaches, &job, nv, job.grain);
		memcpy(vertex_reach_out, vertex_reach, sizeof(float) * (size_t)nv);
		for (int t = 0; t < nt; ++t) {
			for (int k = 0; k < 3; ++k) {
				edge_reach_out[3 * t + k] = edge_reach[edge_of[3 * t + k]];
				if (normals_out) {
					edge_normal_out[3 * t + k] = edge_reach[edge_of[3 * t + k]] >= 0.0f
					                                 ? edge_normal[edge_of[3 * t + k]]
					                                 : v3(0.0f, 0.0f, 0.0f);
				}
			}
		}
	}
	plait_free(a, samples);
	plait_free(a, node_first);
	plait_free(a, node_end);
	plait_free(a, stack);
	plait_free(a, clusters);
	plait_free(a, triangle_reach);
	plait_free(a, triangle_normal);
	plait_free(a, corner_reach);
	plait_free(a, corner_normal);
	plait_free(a, edge_normal);
	plait_free(a, centre);
	plait_free(a, radius);
	plait_free(a, edges);
	plait_free(a, edge_of);
	plait_free(a, runs);
	plait_free(a, open);
	plait_free(a, edge_reach);
	plait_free(a, vertex_reach);
	plait_free(a, vertex_normal);
	plait_free(a, star);
	plait_free(a, star_cos);
	return ok;
}

bool plait_mesh_smooth_reaches(const plait_mesh_shape *shape, const plait_allocator *allocator,
                               plait_parallel *parallel, float budget, float range, float *vertex_reach,
                               float *edge_reach)
{
	return plait_mesh_smooth_reaches_with_normals(shape, allocator, parallel, budget, range, vertex_reach,
	                                              edge_reach, NULL, NULL);
}
