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
	float scale = 1.0f + v3_largest_abs(c) + v3_largest_abs(q->a) + v3_largest_abs(q->b) + q->radius[triangle];
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
	q->sample_count = 0;
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
	return walk_out(q);
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
} reach_job;

static feature_query chunk_query(const reach_job *job, int begin)
{
	feature_query q = job->base;
	size_t room = (size_t)job->base.shape->triangle_count;
	q.candidates = job->samples + (size_t)(begin / job->grain) * 2 * room;
	q.samples = q.candidates + room;
	return q;
}

static void edge_reaches(void *context, int begin, int end)
{
	const reach_job *job = context;
	feature_query q = chunk_query(job, begin);
	const plait_mesh_shape *shape = q.shape;
	float range = q.range;
	for (int r = begin; r < end; ++r) {
		const plait_triangle_edge *edge = &job->edges[job->runs[r]];
		q.a = shape->positions[edge[0].low];
		q.b = shape->positions[edge[0].high];
		q.vertex_a = edge[0].low;
		q.vertex_b = edge[0].high;
		q.corner = false;
		q.normal =
		    reference_normal(v3_add(shape->normals[edge[0].triangle], shape->normals[edge[1].triangle]), 2);
		q.range = capped_range(range, job->budget, v3_dot(q.normal, shape->normals[edge[0].triangle]));
		job->edge_reach[job->runs[r]] = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q) : -1.0f;
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
		q.a = q.b = shape->positions[v];
		q.vertex_a = q.vertex_b = v;
		q.corner = true;
		q.normal = reference_normal(job->normals[v], job->star[v]);
		q.range = capped_range(range, job->budget, job->star_cos[v]);
		float reach = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q) : -1.0f;
		job->vertex_reach[v] = plait_minf(job->vertex_reach[v], reach);
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

bool plait_mesh_smooth_reaches(const plait_mesh_shape *shape, const plait_allocator *a,
                               plait_parallel *parallel, float budget, float range, float *vertex_reach_out,
                               float *edge_reach_out)
{
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
	bool ok = edges != NULL && edge_of != NULL && runs != NULL && open != NULL && edge_reach != NULL &&
	          vertex_reach != NULL && vertex_normal != NULL && star != NULL && star_cos != NULL &&
	          centre != NULL && radius != NULL && samples != NULL;
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
		/* Edges first: a corner is kept whenever an edge of it is. */
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
			}
		}
	}
	plait_free(a, samples);
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
