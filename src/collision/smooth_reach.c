/* The smooth reach of a rigid mesh's corners and edges (smooth_reach.h). */
#include "collision/smooth_reach.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "collision/closest.h"
#include "topology/topology.h"

/* Radians: a face this steep against a feature's reference normal ends its smooth reach. */
#define SMOOTH_STEEPEST 1.0f

typedef struct face_sample {
	float distance; /* from the feature, scene units (a lower bound) */
	float angle;    /* against the feature's reference normal, radians */
} face_sample;

typedef struct feature_query {
	const plait_allocator *allocator;
	const plait_mesh_shape *shape;
	const bool *open; /* per triangle: an edge of it is not shared by exactly two */
	vec3 a, b;        /* a corner (b == a) or an edge */
	bool corner;
	vec3 normal; /* unit reference normal */
	float range;
	face_sample *samples;
	int count, capacity;
	bool failed;
} feature_query;

static int compare_samples(const void *a, const void *b)
{
	const face_sample *x = a, *y = b;
	if (x->distance != y->distance) {
		return x->distance < y->distance ? -1 : 1;
	}
	return x->angle < y->angle ? -1 : x->angle > y->angle;
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
	const int *tri = q->shape->triangles[triangle];
	vec3 t[3] = {q->shape->positions[tri[0]], q->shape->positions[tri[1]], q->shape->positions[tri[2]]};
	/* Less a rounding allowance: the distance must not be overstated. */
	float distance = plait_maxf(feature_triangle_distance(q->a, q->b, q->corner, t) - 1e-6f, 0.0f);
	if (distance > q->range || q->failed) {
		return;
	}
	vec3 n = q->shape->normals[triangle];
	float angle = SMOOTH_STEEPEST; /* open or degenerate: a wall */
	if (!q->open[triangle] && v3_length_sq(n) > 0.0f) {
		angle = acosf(plait_maxf(-1.0f, plait_minf(1.0f, v3_dot(n, q->normal))));
	}
	if (q->count == q->capacity) {
		int capacity = q->capacity < 64 ? 64 : 2 * q->capacity;
		face_sample *bigger = plait_alloc(q->allocator, sizeof *bigger * (size_t)capacity);
		if (bigger == NULL) {
			q->failed = true;
			return;
		}
		if (q->count > 0) {
			memcpy(bigger, q->samples, sizeof *bigger * (size_t)q->count);
		}
		plait_free(q->allocator, q->samples);
		q->samples = bigger;
		q->capacity = capacity;
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
	if (q->failed) {
		return -1.0f;
	}
	qsort(q->samples, (size_t)q->count, sizeof *q->samples, compare_samples);
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

/* The same over q->range, sampled in widening rounds: most reaches end well inside it. */
static float smooth_reach(feature_query *q, float budget)
{
	float range = budget + 0.25f * (q->range - budget);
	for (;;) {
		float reach = reach_within(q, budget, range);
		if (reach < 0.999f * (range - budget) || range >= q->range) {
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

bool plait_mesh_smooth_reaches(const plait_mesh_shape *shape, const plait_allocator *a, float budget,
                               float range, float *vertex_reach_out, float *edge_reach_out)
{
	int nt = shape->triangle_count, nv = shape->vertex_count;
	plait_triangle_edge *edges = plait_alloc(a, sizeof *edges * (size_t)(3 * nt));
	int *edge_of = plait_alloc(a, sizeof(int) * (size_t)(3 * nt)); /* (t, k) -> first key of its run */
	bool *open = plait_alloc_zero(a, (size_t)nt, sizeof(bool));
	float *edge_reach = plait_alloc(a, sizeof(float) * (size_t)(3 * nt));
	float *vertex_reach = plait_alloc(a, sizeof(float) * (size_t)nv);
	vec3 *vertex_normal = plait_alloc_zero(a, (size_t)nv, sizeof(vec3));
	int *star = plait_alloc_zero(a, (size_t)nv, sizeof(int));
	float *star_cos = plait_alloc(a, sizeof(float) * (size_t)nv); /* of the steepest face of its star */
	feature_query q = {.allocator = a, .shape = shape, .open = open, .corner = true, .range = range};
	bool ok = edges != NULL && edge_of != NULL && open != NULL && edge_reach != NULL &&
	          vertex_reach != NULL && vertex_normal != NULL && star != NULL && star_cos != NULL;
	if (ok) {
		for (int t = 0; t < nt; ++t) {
			for (int k = 0; k < 3; ++k) {
				int i = shape->triangles[t][k], j = shape->triangles[t][(k + 1) % 3];
				edges[3 * t + k] = (plait_triangle_edge){i < j ? i : j, i < j ? j : i, t, k};
				vertex_normal[i] = v3_add(vertex_normal[i], shape->normals[t]);
				star[i] += 1;
			}
		}
		plait_sort_triangle_edges(edges, 3 * nt);
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
			start = end;
		}
		for (int v = 0; v < nv; ++v) {
			vertex_reach[v] = range - budget;
			star_cos[v] = 1.0f;
		}
		for (int t = 0; t < nt; ++t) {
			for (int k = 0; k < 3; ++k) {
				int v = shape->triangles[t][k];
				vec3 n0 = reference_normal(vertex_normal[v], star[v]);
				star_cos[v] = plait_minf(star_cos[v], v3_dot(n0, shape->normals[t]));
			}
		}
		/* Edges first: a corner is kept whenever an edge of it is. */
		for (int start = 0; start < 3 * nt && !q.failed;) {
			int end = start + 1;
			while (end < 3 * nt && edges[end].low == edges[start].low &&
			       edges[end].high == edges[start].high) {
				++end;
			}
			float reach = -1.0f;
			if (end - start == 2) {
				q.a = shape->positions[edges[start].low];
				q.b = shape->positions[edges[start].high];
				q.corner = false;
				q.normal = reference_normal(
				    v3_add(shape->normals[edges[start].triangle], shape->normals[edges[start + 1].triangle]),
				    2);
				q.range =
				    capped_range(range, budget, v3_dot(q.normal, shape->normals[edges[start].triangle]));
				reach = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q, budget) : -1.0f;
			}
			edge_reach[start] = reach;
			vertex_reach[edges[start].low] = plait_minf(vertex_reach[edges[start].low], reach);
			vertex_reach[edges[start].high] = plait_minf(vertex_reach[edges[start].high], reach);
			start = end;
		}
		for (int v = 0; v < nv && !q.failed; ++v) {
			if (star[v] == 0 || !(vertex_reach[v] > 0.0f)) {
				continue;
			}
			q.a = q.b = shape->positions[v];
			q.corner = true;
			q.normal = reference_normal(vertex_normal[v], star[v]);
			q.range = capped_range(range, budget, star_cos[v]);
			float reach = v3_length_sq(q.normal) > 0.0f ? smooth_reach(&q, budget) : -1.0f;
			vertex_reach[v] = plait_minf(vertex_reach[v], reach);
		}
		ok = !q.failed;
	}
	if (ok) {
		memcpy(vertex_reach_out, vertex_reach, sizeof(float) * (size_t)nv);
		for (int t = 0; t < nt; ++t) {
			for (int k = 0; k < 3; ++k) {
				edge_reach_out[3 * t + k] = edge_reach[edge_of[3 * t + k]];
			}
		}
	}
	plait_free(a, q.samples);
	plait_free(a, edges);
	plait_free(a, edge_of);
	plait_free(a, open);
	plait_free(a, edge_reach);
	plait_free(a, vertex_reach);
	plait_free(a, vertex_normal);
	plait_free(a, star);
	plait_free(a, star_cos);
	return ok;
}
