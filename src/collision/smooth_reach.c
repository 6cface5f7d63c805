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

typedef struct face_sample {
	float distance; /* from the feature, scene units (a lower bound) */
	float angle;    /* against the feature's reference normal, radians */
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
	float first_share;    /* of the range, sampled first (smooth_reach) */
	face_sample *samples; /* room for every triangle: a query meets each at most once */
	face_sample *scratch; /* as much again, for the sort */
	int count;
} feature_query;

/* Sorts samples by distance. The reach takes every face within a distance at once, so the order
 * of equal distances does not matter and any sort gives the same reaches. Distances are never
 * negative, so their bits order as they do: a radix sort, a byte at a time from the lowest
 * (bytes all samples share are skipped), through `scratch` (room for count); insertion sort
 * for a few. It was a fifth of a large smooth collider's set-up as a quicksort. */
static void sort_samples(face_sample *s, face_sample *scratch, int count)
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

static float largest_abs(vec3 v)
{
	return plait_maxf(fabsf(v.x), plait_maxf(fabsf(v.y), fabsf(v.z)));
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

static void sample_face(int triangle, void *context)
{
	feature_query *q = context;
	/* Faces whose ball is out of range are passed over before their distance: the distance
	 * from the feature to the ball's centre, less its radius, bounds theirs from below (less
	 * an allowance for the rounding of both measures). */
	vec3 c = q->centre[triangle], ab = v3_sub(q->b, q->a);
	float length_sq = v3_dot(ab, ab);
	float s =
	    length_sq > 0.0f ? plait_minf(plait_maxf(v3_dot(v3_sub(c, q->a), ab) / length_sq, 0.0f), 1.0f) : 0.0f;
	float scale = 1.0f + largest_abs(c) + largest_abs(q->a) + largest_abs(q->b) + q->radius[triangle];
	float beyond = v3_length(v3_sub(c, v3_mul_add(q->a, s, ab))) - q->radius[triangle] - 4e-6f * scale;
	if (beyond > q->range + 1e-6f) {
		return;
	}
	const int *tri = q->shape->triangles[triangle];
	vec3 t[3] = {q->shape->positions[tri[0]], q->shape->positions[tri[1]], q->shape->positions[tri[2]]};
	/* A face with a vertex of the feature is at 0 (what the measure gives, but for rounding on
	 * needles: never more); the others less a rounding allowance, the distance must not be
	 * overstated. A face with two vertices at one point has no closest point (0 / 0): its
	 * ball's bound stands for its distance. */
	bool touches = false;
	for (int k = 0; k < 3; ++k) {
		touches = touches || tri[k] == q->vertex_a || tri[k] == q->vertex_b;
	}
	float distance = 0.0f;
	if (!touches) {
		float measured = feature_triangle_distance(q->a, q->b, q->corner, t);
		distance = plait_maxf((isnan(measured) ? beyond : measured) - 1e-6f, 0.0f);
	}
	if (distance > q->range) {
		return;
	}
	vec3 n = q->shape->normals[triangle];
	float angle = SMOOTH_STEEPEST; /* open or degenerate: a wall */
	if (!q->open[triangle] && v3_length_sq(n) > 0.0f) {
		angle = acosf(plait_maxf(-1.0f, plait_minf(1.0f, v3_dot(n, q->normal))));
	}
	q->samples[q->count++] = (face_sample){distance, angle};
}

/* The longest cloth edge D for which F(D) < budget (M above), for the feature of q with its
 * faces within q->range sampled; at most q->range - budget (farther faces are not known). */
static float reach_within(feature_query *q, float budget, float range)
{
	vec3 lower = v3_min(q->a, q->b), upper = v3_max(q->a, q->b);
	vec3 grow = v3(range, range, range);
	q->count = 0;
	float full = q->range;
	q->range = range;
	plait_mesh_shape_visit(q->shape, v3_sub(lower, grow), v3_add(upper, grow), true, sample_face, q);
	q->range = full;
	sort_samples(q->samples, q->scratch, q->count);
	/* A(t) steps up as faces come within t + budget; F grows by tan A over each step. */
	float t = 0.0f, fall = 0.0f, steepest = 0.0f;
	int k = 0;
	for (;;) {
		while (k < q->count && q->samples[k].distance - budget <= t) {
			steepest = plait_maxf(steepest, q->samples[k].angle);
			++k;
		}
		if (steepest >= SMOOTH_STEEPEST) {
			return t;
		}
		float next = k < q->count ? q->samples[k].distance - budget : range - budget;
		float slope = tanf(steepest);
		if (fall + slope * (next - t) >= budget) {
			return t + (budget - fall) / slope;
		}
		if (k >= q->count) {
			return next;
		}
		fall += slope * (next - t);
		t = next;
	}
}

/* The same over q->range, sampled in widening rounds: on a sharp mesh most reaches end well
 * inside it. A reach that ends inside a round's range is the whole range's (the faces beyond
 * come after it), so the rounds change only the cost: where the last feature's reach went
 * past a quarter of the range (a smooth mesh, its reaches long), the next starts with the whole
 * range. Chunks of features start afresh at fixed features (SHARE_BLOCK), so that no result can
 * depend on how the features were cut for the workers. */
static float smooth_reach(feature_query *q, float budget)
{
	float quarter = 0.25f * (q->range - budget);
	float range = budget + q->first_share * (q->range - budget);
	for (;;) {
		float reach = reach_within(q, budget, range);
		if (reach < 0.999f * (range - budget) || range >= q->range) {
			q->first_share = reach >= 0.999f * quarter ? 1.0f : 0.25f;
			return reach;
		}
		range = plait_minf(q->range, budget + 2.0f * (range - budget));
	}
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

/* Features measured in a row from a fresh start (smooth_reach); chunks hold whole blocks. */
#define SHARE_BLOCK 64

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
	q.samples = job->samples + (size_t)(begin / job->grain) * 2 * room;
	q.scratch = q.samples + room;
	return q;
}

static void edge_reaches(void *context, int begin, int end)
{
	const reach_job *job = context;
	feature_query q = chunk_query(job, begin);
	const plait_mesh_shape *shape = q.shape;
	float range = q.range;
	for (int r = begin; r < end; ++r) {
		q.first_share = r % SHARE_BLOCK == 0 ? 0.25f : q.first_share;
		const plait_triangle_edge *edge = &job->edges[job->runs[r]];
		q.a = shape->positions[edge[0].low];
		q.b = shape->positions[edge[0].high];
		q.vertex_a = edge[0].low;
		q.vertex_b = edge[0].high;
		q.corner = false;
		q.normal =
		    reference_normal(v3_add(shape->normals[edge[0].triangle], shape->normals[edge[1].triangle]), 2);
		q.range = capped_range(range, job->budget, v3_dot(q.normal, shape->normals[edge[0].triangle]));
		job->edge_reach[job->runs[r]] = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q, job->budget) : -1.0f;
	}
}

static void corner_reaches(void *context, int begin, int end)
{
	const reach_job *job = context;
	feature_query q = chunk_query(job, begin);
	const plait_mesh_shape *shape = q.shape;
	float range = q.range;
	for (int v = begin; v < end; ++v) {
		q.first_share = v % SHARE_BLOCK == 0 ? 0.25f : q.first_share;
		if (job->star[v] == 0 || !(job->vertex_reach[v] > 0.0f)) {
			continue;
		}
		q.a = q.b = shape->positions[v];
		q.vertex_a = q.vertex_b = v;
		q.corner = true;
		q.normal = reference_normal(job->normals[v], job->star[v]);
		q.range = capped_range(range, job->budget, job->star_cos[v]);
		float reach = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q, job->budget) : -1.0f;
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

/* Features [0, count) cut into at most `chunks` chunks of whole blocks. */
static int block_grain(int count, int chunks)
{
	int per_chunk = (count + chunks - 1) / chunks;
	int blocks = (per_chunk + SHARE_BLOCK - 1) / SHARE_BLOCK;
	return (blocks > 0 ? blocks : 1) * SHARE_BLOCK;
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
		                          .first_share = 0.25f},
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
		job.grain = block_grain(run_count, chunks);
		run_chunks(parallel, edge_reaches, &job, run_count, job.grain);
		for (int r = 0; r < run_count; ++r) {
			const plait_triangle_edge *edge = &edges[runs[r]];
			vertex_reach[edge->low] = plait_minf(vertex_reach[edge->low], edge_reach[runs[r]]);
			vertex_reach[edge->high] = plait_minf(vertex_reach[edge->high], edge_reach[runs[r]]);
		}
		job.grain = block_grain(nv, chunks);
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
