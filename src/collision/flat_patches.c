#include "collision/flat_patches.h"

#include <math.h>
#include <string.h>

#include "core/lanes.h"

#include "topology/topology.h"

/* Nodes with fewer triangles are never tested: their pairs with themselves cost less to walk. */
#define FLAT_MIN_TRIANGLES 16

/* A patch is flat below this cone angle (radians, about 85 degrees): the rest of a right angle
 * holds the cones' rounding many times over. */
#define FLAT_ANGLE 1.48f

/* No cone under a right angle. */
#define NO_CONE 4.0f

#define HALF_PI 1.5707963f

void plait_flat_patches_destroy(plait_flat_patches *fp, const plait_allocator *allocator)
{
	plait_free(allocator, fp->triangles);
	plait_free(allocator, fp->contour_first);
	plait_free(allocator, fp->contour);
	plait_free(allocator, fp->notch_first);
	plait_free(allocator, fp->notch);
	plait_free(allocator, fp->patch_cone);
	plait_free(allocator, fp->centre);
	plait_free(allocator, fp->node_begin);
	plait_free(allocator, fp->node_end);
	plait_free(allocator, fp->order);
	memset(fp, 0, sizeof *fp);
}

/* ---- Building the patches -------------------------------------------------------------------- */

/* Scratch of the build. */
typedef struct patch_build {
	const plait_element_tree *tree;
	const int (*triangles)[3];
	int *twin;        /* per triangle corner (3 t + k): the corner across its edge; -1 border, -2 odd */
	int *position;    /* per triangle: its index in tree->order */
	int *begin, *end; /* per node: its range of tree->order */
	int *notch_stamp; /* per triangle: node + 1 when a notch of that node */
	int *visit_stamp; /* per triangle: node + 1 when reached by the connectivity walk */
	int *stack;       /* per triangle */
	int *out_stamp, *out_next; /* per particle: the border edge leaving it (node + 1 when set) */
	int *seen_stamp;           /* per particle */
	int *contour, contour_count, contour_capacity;
	int *notch, notch_count, notch_capacity;
	const vec3 *rest;           /* per particle: the rest shape the centres are chosen in */
	plait_patch_centre *centre; /* per node */
	float (*kernel)[2], (*clipped)[2], (*flat)[2]; /* scratch of choose_centre, kernel_capacity each */
	int kernel_capacity;
	const plait_allocator *allocator;
	bool failed;
} patch_build;

static bool push(patch_build *b, int **array, int *count, int *capacity, int value)
{
	if (*count == *capacity) {
		int grown = *capacity < 1024 ? 1024 : 2 * *capacity;
		int *bigger = plait_alloc_grow(b->allocator, *array, sizeof(int), *count, grown);
		if (bigger == NULL) {
			b->failed = true;
			return false;
		}
		*array = bigger;
		*capacity = grown;
	}
	(*array)[(*count)++] = value;
	return true;
}

/* Each corner's twin: the corner of the other triangle on its edge, run the other way. */
static bool find_twins(patch_build *b, int count)
{
	plait_triangle_edge *edges = plait_alloc_zero(b->allocator, (size_t)(3 * count), sizeof *edges);
	if (edges == NULL) {
		return false;
	}
	for (int t = 0; t < count; ++t) {
		for (int k = 0; k < 3; ++k) {
			int i = b->triangles[t][k], j = b->triangles[t][(k + 1) % 3];
			edges[3 * t + k] = (plait_triangle_edge){i < j ? i : j, i < j ? j : i, t, k};
			b->twin[3 * t + k] = i == j ? -2 : -1;
		}
	}
	plait_sort_triangle_edges(edges, 3 * count);
	for (int first = 0; first < 3 * count;) {
		int last = first + 1;
		while (last < 3 * count && edges[last].low == edges[first].low &&
		       edges[last].high == edges[first].high) {
			++last;
		}
		if (last - first == 2) {
			const plait_triangle_edge *e0 = &edges[first], *e1 = &edges[first + 1];
			int c0 = 3 * e0->triangle + e0->corner, c1 = 3 * e1->triangle + e1->corner;
			bool opposite = (b->triangles[e0->triangle][e0->corner] == e0->low) !=
			                (b->triangles[e1->triangle][e1->corner] == e1->low);
			if (b->twin[c0] == -1 && b->twin[c1] == -1) {
				b->twin[c0] = opposite ? c1 : -2;
				b->twin[c1] = opposite ? c0 : -2;
			}
		} else if (last - first > 2) {
			for (int k = first; k < last; ++k) {
				b->twin[3 * edges[k].triangle + edges[k].corner] = -2; /* more than two triangles */
			}
		}
		first = last;
	}
	plait_free(b->allocator, edges);
	return true;
}

static bool in_node(const patch_build *b, int node, int t)
{
	return b->position[t] >= b->begin[node] && b->position[t] < b->end[node];
}

static bool in_patch(const patch_build *b, int node, int t)
{
	return in_node(b, node, t) || b->notch_stamp[t] == node + 1;
}

/* The patch's k-th triangle: the node's own, then its notches from notch[notch_start]. */
static int patch_triangle(const patch_build *b, int node, int notch_start, int k)
{
	int own = b->end[node] - b->begin[node];
	return k < own ? b->tree->order[b->begin[node] + k] : b->notch[notch_start + k - own];
}

/* Clips the convex polygon k[0..n) to the left of the line from a to b (2D); returns the new
 * count (out holds it). */
static int clip_left(const float (*k)[2], int n, const float *a, const float *b, float (*out)[2])
{
	float dx = b[0] - a[0], dy = b[1] - a[1];
	int m = 0;
	for (int i = 0; i < n; ++i) {
		const float *p = k[i], *q = k[(i + 1) % n];
		float sp = dx * (p[1] - a[1]) - dy * (p[0] - a[0]), sq = dx * (q[1] - a[1]) - dy * (q[0] - a[0]);
		if (sp >= 0.0f) {
			out[m][0] = p[0];
			out[m++][1] = p[1];
		}
		if ((sp >= 0.0f) != (sq >= 0.0f)) {
			float t = sp / (sp - sq);
			out[m][0] = p[0] + t * (q[0] - p[0]);
			out[m++][1] = p[1] + t * (q[1] - p[1]);
		}
	}
	return m;
}

/* The patch's centre for its star test: in the rest shape, seen along its triangles' mean
 * normal, the centroid of its contour's kernel (the points every border edge turns forward
 * round), held as a point of one of its triangles so that it moves with them. None (triangle
 * -1: the test takes the contour's mean) when the kernel is empty or no triangle holds it. */
static void choose_centre(patch_build *b, int node, int notch_start, int faces, int contour_start)
{
	b->centre[node] = (plait_patch_centre){-1, {0.0f, 0.0f, 0.0f}};
	if (b->rest == NULL) {
		return;
	}
	vec3 n = {0.0f, 0.0f, 0.0f};
	for (int k = 0; k < faces; ++k) {
		const int *v = b->triangles[patch_triangle(b, node, notch_start, k)];
		n = v3_add(n, v3_cross(v3_sub(b->rest[v[1]], b->rest[v[0]]), v3_sub(b->rest[v[2]], b->rest[v[0]])));
	}
	float length = v3_length(n);
	if (!(length > 0.0f)) {
		return;
	}
	n = v3_scale(n, 1.0f / length);
	vec3 u = v3_cross(n, fabsf(n.x) < 0.6f ? v3(1.0f, 0.0f, 0.0f) : v3(0.0f, 1.0f, 0.0f));
	u = v3_scale(u, 1.0f / v3_length(u));
	vec3 w = v3_cross(n, u);
	int count = b->contour_count - contour_start;
	if (b->kernel_capacity < count + 8) {
		int grown = 2 * (count + 8);
		plait_free(b->allocator, b->kernel);
		plait_free(b->allocator, b->clipped);
		plait_free(b->allocator, b->flat);
		b->kernel = plait_alloc_zero(b->allocator, (size_t)grown, sizeof *b->kernel);
		b->clipped = plait_alloc_zero(b->allocator, (size_t)grown, sizeof *b->clipped);
		b->flat = plait_alloc_zero(b->allocator, (size_t)grown, sizeof *b->flat);
		b->kernel_capacity = grown;
		if (b->kernel == NULL || b->clipped == NULL || b->flat == NULL) {
			b->kernel_capacity = 0;
			b->failed = true;
			return;
		}
	}
	/* The contour seen along n; the kernel starts as its bounding box, clipped by every edge. */
	float(*points)[2] = b->flat;
	float lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
	for (int k = 0; k < count; ++k) {
		vec3 x = b->rest[b->contour[contour_start + k]];
		points[k][0] = v3_dot(x, u);
		points[k][1] = v3_dot(x, w);
		for (int q = 0; q < 2; ++q) {
			lo[q] = fminf(lo[q], points[k][q]);
			hi[q] = fmaxf(hi[q], points[k][q]);
		}
	}
	float(*kernel)[2] = b->kernel, (*spare)[2] = b->clipped;
	float box[4][2] = {{lo[0], lo[1]}, {hi[0], lo[1]}, {hi[0], hi[1]}, {lo[0], hi[1]}};
	memcpy(kernel, box, sizeof box);
	int m = 4;
	for (int k = 0; k < count && m > 0; ++k) {
		m = clip_left((const float(*)[2])kernel, m, points[k], points[(k + 1) % count], spare);
		float(*swap)[2] = kernel;
		kernel = spare;
		spare = swap;
	}
	if (m < 3) {
		return;
	}
	float cx = 0.0f, cy = 0.0f;
	for (int k = 0; k < m; ++k) {
		cx += kernel[k][0];
		cy += kernel[k][1];
	}
	cx /= (float)m;
	cy /= (float)m;
	/* The triangle holding it, and its weights there. */
	for (int k = 0; k < faces; ++k) {
		int t = patch_triangle(b, node, notch_start, k);
		const int *v = b->triangles[t];
		float x[3], y[3];
		for (int q = 0; q < 3; ++q) {
			x[q] = v3_dot(b->rest[v[q]], u);
			y[q] = v3_dot(b->rest[v[q]], w);
		}
		float area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
		if (!(area > 0.0f)) {
			continue;
		}
		float w1 = ((cx - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (cy - y[0])) / area;
		float w2 = ((x[1] - x[0]) * (cy - y[0]) - (cx - x[0]) * (y[1] - y[0])) / area;
		if (w1 >= 0.0f && w2 >= 0.0f && w1 + w2 <= 1.0f) {
			b->centre[node] = (plait_patch_centre){t, {1.0f - w1 - w2, w1, w2}};
			return;
		}
	}
}

/* Node `node`'s notches and contour appended to b's lists; false (and nothing appended) when its
 * patch is no disk. */
static bool build_patch(patch_build *b, int node)
{
	int stamp = node + 1, notch_start = b->notch_count, contour_start = b->contour_count;
	/* Notches: triangles outside sharing two edges with the node's. */
	for (int k = b->begin[node]; k < b->end[node]; ++k) {
		int t = b->tree->order[k];
		for (int c = 0; c < 3; ++c) {
			int across = b->twin[3 * t + c];
			if (across == -2) {
				return false;
			}
			int u = across / 3;
			if (across < 0 || in_node(b, node, u) || b->notch_stamp[u] == stamp) {
				continue;
			}
			int shared = 0;
			for (int m = 0; m < 3; ++m) {
				int other = b->twin[3 * u + m];
				shared += other >= 0 && in_node(b, node, other / 3);
			}
			if (shared >= 2) {
				b->notch_stamp[u] = stamp;
				if (!push(b, &b->notch, &b->notch_count, &b->notch_capacity, u)) {
					return false;
				}
			}
		}
	}
	int faces = b->end[node] - b->begin[node] + (b->notch_count - notch_start);
	/* Border edges (each vertex leaves by one at most), vertices. */
	int border = 0, vertices = 0, start = -1;
	bool ok = true;
	for (int k = 0; k < faces && ok; ++k) {
		int t = patch_triangle(b, node, notch_start, k);
		for (int c = 0; c < 3 && ok; ++c) {
			int across = b->twin[3 * t + c], v = b->triangles[t][c];
			ok = across != -2;
			if (b->seen_stamp[v] != stamp) {
				b->seen_stamp[v] = stamp;
				vertices += 1;
			}
			if (ok && (across < 0 || !in_patch(b, node, across / 3))) {
				ok = b->out_stamp[v] != stamp;
				b->out_stamp[v] = stamp;
				b->out_next[v] = b->triangles[t][(c + 1) % 3];
				border += 1;
				start = v;
			}
		}
	}
	/* A disk: one piece, Euler characteristic 1, one border loop through every border edge. */
	int edges = (3 * faces + border) / 2;
	ok = ok && border > 0 && vertices - edges + faces == 1;
	for (int v = start, steps = 0; ok; ++steps) {
		if (steps == border) {
			ok = v == start;
			break;
		}
		if (b->out_stamp[v] != stamp || (steps > 0 && v == start) ||
		    !push(b, &b->contour, &b->contour_count, &b->contour_capacity, v)) {
			ok = false;
			break;
		}
		v = b->out_next[v];
	}
	if (ok) {
		int top = 0, reached = 1, first = patch_triangle(b, node, notch_start, 0);
		b->visit_stamp[first] = stamp;
		b->stack[top++] = first;
		while (top > 0) {
			int t = b->stack[--top];
			for (int c = 0; c < 3; ++c) {
				int across = b->twin[3 * t + c];
				if (across >= 0 && in_patch(b, node, across / 3) && b->visit_stamp[across / 3] != stamp) {
					b->visit_stamp[across / 3] = stamp;
					b->stack[top++] = across / 3;
					reached += 1;
				}
			}
		}
		ok = reached == faces;
	}
	if (ok) {
		choose_centre(b, node, notch_start, faces, contour_start);
	}
	if (!ok) {
		b->contour_count = contour_start;
		b->notch_count = notch_start;
	}
	return ok;
}

bool plait_flat_patches_build(plait_flat_patches *fp, const plait_allocator *allocator,
                              const plait_element_tree *tree, const int (*triangles)[3], int triangle_count,
                              const vec3 *rest)
{
	plait_flat_patches_destroy(fp, allocator);
	int nodes = tree->node_count, count = triangle_count;
	if (nodes == 0 || count == 0) {
		return true;
	}
	int particles = 0;
	for (int t = 0; t < count; ++t) {
		for (int k = 0; k < 3; ++k) {
			particles = triangles[t][k] >= particles ? triangles[t][k] + 1 : particles;
		}
	}
	patch_build b = {.tree = tree, .triangles = triangles, .allocator = allocator, .rest = rest};
	b.twin = plait_alloc_zero(allocator, (size_t)(3 * count), sizeof(int));
	b.position = plait_alloc_zero(allocator, (size_t)count, sizeof(int));
	b.begin = plait_alloc_zero(allocator, (size_t)nodes, sizeof(int));
	b.end = plait_alloc_zero(allocator, (size_t)nodes, sizeof(int));
	b.notch_stamp = plait_alloc_zero(allocator, (size_t)count, sizeof(int));
	b.visit_stamp = plait_alloc_zero(allocator, (size_t)count, sizeof(int));
	b.stack = plait_alloc_zero(allocator, (size_t)count, sizeof(int));
	b.out_stamp = plait_alloc_zero(allocator, (size_t)particles, sizeof(int));
	b.out_next = plait_alloc_zero(allocator, (size_t)particles, sizeof(int));
	b.seen_stamp = plait_alloc_zero(allocator, (size_t)particles, sizeof(int));
	fp->triangles = plait_alloc_zero(allocator, (size_t)count, sizeof *fp->triangles);
	fp->contour_first = plait_alloc_zero(allocator, (size_t)nodes + 1, sizeof(int));
	fp->notch_first = plait_alloc_zero(allocator, (size_t)nodes + 1, sizeof(int));
	fp->patch_cone = plait_alloc_zero(allocator, (size_t)nodes, sizeof(plait_cone));
	fp->centre = plait_alloc_zero(allocator, (size_t)nodes, sizeof(plait_patch_centre));
	fp->node_begin = plait_alloc_zero(allocator, (size_t)nodes, sizeof(int));
	fp->node_end = plait_alloc_zero(allocator, (size_t)nodes, sizeof(int));
	fp->order = plait_alloc_zero(allocator, (size_t)count, sizeof(int));
	bool ok = b.twin != NULL && b.position != NULL && b.begin != NULL && b.end != NULL &&
	          b.notch_stamp != NULL && b.visit_stamp != NULL && b.stack != NULL && b.out_stamp != NULL &&
	          b.out_next != NULL && b.seen_stamp != NULL && fp->triangles != NULL &&
	          fp->contour_first != NULL && fp->notch_first != NULL && fp->patch_cone != NULL &&
	          fp->centre != NULL && fp->node_begin != NULL && fp->node_end != NULL && fp->order != NULL;
	if (ok) {
		memcpy(fp->triangles, triangles, sizeof *fp->triangles * (size_t)count);
		ok = find_twins(&b, count);
	}
	if (ok) {
		for (int k = 0; k < count; ++k) {
			b.position[tree->order[k]] = k;
		}
		/* Children come after their parents. */
		for (int n = nodes - 1; n >= 0; --n) {
			const plait_tree_node *node = &tree->nodes[n];
			b.begin[n] = node->count > 0 ? node->first : b.begin[node->first];
			b.end[n] = node->count > 0 ? node->first + node->count : b.end[node->first + 1];
		}
		b.centre = fp->centre;
		for (int n = 0; n < nodes && !b.failed; ++n) {
			fp->centre[n].triangle = -1;
			fp->contour_first[n] = b.contour_count;
			fp->notch_first[n] = b.notch_count;
			if (b.end[n] - b.begin[n] >= FLAT_MIN_TRIANGLES) {
				(void)build_patch(&b, n);
			}
		}
		fp->contour_first[nodes] = b.contour_count;
		memcpy(fp->node_begin, b.begin, sizeof(int) * (size_t)nodes);
		memcpy(fp->node_end, b.end, sizeof(int) * (size_t)nodes);
		memcpy(fp->order, tree->order, sizeof(int) * (size_t)count);
		fp->notch_first[nodes] = b.notch_count;
		ok = !b.failed;
	}
	plait_free(allocator, b.twin);
	plait_free(allocator, b.position);
	plait_free(allocator, b.begin);
	plait_free(allocator, b.end);
	plait_free(allocator, b.notch_stamp);
	plait_free(allocator, b.visit_stamp);
	plait_free(allocator, b.stack);
	plait_free(allocator, b.out_stamp);
	plait_free(allocator, b.out_next);
	plait_free(allocator, b.seen_stamp);
	plait_free(allocator, b.kernel);
	plait_free(allocator, b.clipped);
	plait_free(allocator, b.flat);
	fp->contour = b.contour;
	fp->notch = b.notch;
	if (!ok) {
		plait_flat_patches_destroy(fp, allocator);
		return false;
	}
	fp->node_count = nodes;
	fp->triangle_count = count;
	return true;
}

/* ---- Cones ------------------------------------------------------------------------------------ */

/* The arctangent of x in [0, 1] by a polynomial (error under 2e-6 radians; tests/test_flat_patches.c
 * checks); every angle built from it gets ANGLE_SLACK added, well above that and rounding. */
static float atan_unit(float x)
{
	float x2 = x * x;
	return x * (0.99997726f +
	            x2 * (-0.33262347f +
	                  x2 * (0.19354346f + x2 * (-0.11643287f + x2 * (0.05265332f + x2 * -0.01172120f)))));
}

#define ANGLE_SLACK 1e-4f

/* atan2(y, x) for y >= 0, in [0, pi]. */
static float angle_of(float y, float x)
{
	float ax = fabsf(x);
	if (!(y > 0.0f) && !(ax > 0.0f)) {
		return 0.0f;
	}
	float angle = ax >= y ? atan_unit(y / ax) : HALF_PI - atan_unit(ax / y);
	return x < 0.0f ? 2.0f * HALF_PI - angle : angle;
}

float plait_flat_patches_atan2(float y, float x)
{
	return angle_of(y, x);
}

static plait_cone no_cone(void)
{
	return (plait_cone){{0.0f, 0.0f, 1.0f}, NO_CONE};
}

static float angle_between(vec3 a, vec3 b)
{
	return angle_of(v3_length(v3_cross(a, b)), v3_dot(a, b));
}

plait_cone plait_cone_merge(plait_cone a, plait_cone b)
{
	if (a.angle >= HALF_PI || b.angle >= HALF_PI) {
		return no_cone();
	}
	float between = angle_between(a.axis, b.axis) + ANGLE_SLACK;
	if (between + b.angle <= a.angle) {
		return a;
	}
	if (between + a.angle <= b.angle) {
		return b;
	}
	float angle = 0.5f * (between + a.angle + b.angle);
	if (angle >= HALF_PI) {
		return no_cone();
	}
	/* An axis between the two (normalised lerp toward the smallest cone's), then the angle that
	 * holds both cones round it, measured. */
	float t = (angle - a.angle) / between;
	vec3 axis = v3_add(v3_scale(a.axis, 1.0f - t), v3_scale(b.axis, t));
	float length = v3_length(axis);
	if (!(length > 1e-6f)) {
		return no_cone();
	}
	axis = v3_scale(axis, 1.0f / length);
	float reach = fmaxf(angle_between(axis, a.axis) + a.angle, angle_between(axis, b.axis) + b.angle);
	return (plait_cone){axis, reach + ANGLE_SLACK};
}

static float guard(const plait_patch_paths *paths, int i)
{
	return paths->guard != NULL ? paths->guard[i] : 0.0f;
}

static vec3 path_start(const plait_patch_paths *paths, int i)
{
	return paths->motion != NULL ? v3_mul_add(paths->at[i], -paths->back, paths->motion[i]) : paths->at[i];
}

static vec3 path_end(const plait_patch_paths *paths, int i)
{
	return paths->motion != NULL ? v3_mul_add(paths->at[i], paths->on, paths->motion[i]) : paths->at[i];
}

/* A triangle's normal over the paths (plait_triangle_normals). */
typedef plait_triangle_normals triangle_normals;

static triangle_normals triangle_normals_of(const plait_patch_paths *paths, const int *v)
{
	if (paths->motion == NULL) {
		vec3 e1 = v3_sub(paths->at[v[1]], paths->at[v[0]]), e2 = v3_sub(paths->at[v[2]], paths->at[v[0]]);
		vec3 n = v3_cross(e1, e2);
		float g0 = guard(paths, v[0]), s1 = g0 + guard(paths, v[1]), s2 = g0 + guard(paths, v[2]);
		float l1 = v3_length(e1), l2 = v3_length(e2);
		return (triangle_normals){{n, n, n}, s1 * l2 + l1 * s2 + s1 * s2 + 1e-6f * l1 * l2};
	}
	vec3 a[3], b[3];
	for (int k = 0; k < 3; ++k) {
		a[k] = path_start(paths, v[k]);
		b[k] = path_end(paths, v[k]);
	}
	vec3 e1a = v3_sub(a[1], a[0]), e2a = v3_sub(a[2], a[0]);
	vec3 e1b = v3_sub(b[1], b[0]), e2b = v3_sub(b[2], b[0]);
	triangle_normals t = {{v3_cross(e1a, e2a), v3_scale(v3_add(v3_cross(e1a, e2b), v3_cross(e1b, e2a)), 0.5f),
	                       v3_cross(e1b, e2b)},
	                      0.0f};
	float e1_sq = fmaxf(v3_length_sq(e1a), v3_length_sq(e1b));
	float e2_sq = fmaxf(v3_length_sq(e2a), v3_length_sq(e2b));
	if (paths->guard == NULL) {
		/* The rounding alone, e1 e2 bounded by (e1^2 + e2^2) / 2: no square roots. */
		t.rho = 0.5e-6f * (e1_sq + e2_sq);
		return t;
	}
	float e1 = sqrtf(e1_sq), e2 = sqrtf(e2_sq);
	float g0 = guard(paths, v[0]), s1 = g0 + guard(paths, v[1]), s2 = g0 + guard(paths, v[2]);
	/* (e1 + d1) x (e2 + d2) - e1 x e2, with |d1| <= s1, |d2| <= s2; and the rounding. */
	t.rho = s1 * e2 + e1 * s2 + s1 * s2 + 1e-6f * e1 * e2;
	return t;
}

/* The cone round `axis` (unit) of some triangles' normals over the paths. Each normal has an
 * along-axis part of at least m (its least coefficient's) and a part across at most tan(widest)
 * times that, before the guards' rho: tan of its angle is at most (m tan + rho) / (m - rho). */
static plait_cone cone_round(vec3 axis, const triangle_normals *t, int count)
{
	/* tan^2 of each coefficient's angle, |n x axis|^2 / (n . axis)^2: one square root at the
	 * end rather than one per coefficient. */
	float widest_sq = 0.0f;
	for (int k = 0; k < count; ++k) {
		for (int m = 0; m < 3; ++m) {
			float along = v3_dot(t[k].n[m], axis);
			if (!(along > 0.0f)) {
				return no_cone(); /* at or past a right angle (or the triangle collapses) */
			}
			float ratio = v3_length_sq(v3_cross(t[k].n[m], axis)) / (along * along);
			if (!(ratio < INFINITY)) {
				return no_cone(); /* overflowed (absurd coordinates): bounds nothing */
			}
			widest_sq = fmaxf(widest_sq, ratio);
		}
	}
	float widest = sqrtf(widest_sq);
	float tangent = 0.0f;
	for (int k = 0; k < count; ++k) {
		float least = fminf(v3_dot(t[k].n[0], axis), fminf(v3_dot(t[k].n[1], axis), v3_dot(t[k].n[2], axis)));
		if (!(t[k].rho < least)) {
			return no_cone();
		}
		tangent = fmaxf(tangent, (least * widest + t[k].rho) / (least - t[k].rho));
	}
	return (plait_cone){axis, angle_of(tangent, 1.0f) + ANGLE_SLACK};
}

#if defined(PLAIT_HAVE_LANES)
/* triangle_normals_of for four triangles on paths without guards, lane k for triangle v[k]. */
typedef struct triangle_normals4 {
	lanes3 n[3];
	__m128 rho;
} triangle_normals4;

static triangle_normals4 triangle_normals4_of(const plait_patch_paths *paths, const int *const v[4])
{
	lanes3 a[3], b[3];
	const __m128 back = _mm_set1_ps(-paths->back), on = _mm_set1_ps(paths->on);
	for (int m = 0; m < 3; ++m) {
		int corner[4] = {v[0][m], v[1][m], v[2][m], v[3][m]};
		lanes3 at = lanes3_gather(paths->at, corner), motion = lanes3_gather(paths->motion, corner);
		a[m] = lanes3_mul_add(at, back, motion);
		b[m] = lanes3_mul_add(at, on, motion);
	}
	lanes3 e1a = lanes3_sub(a[1], a[0]), e2a = lanes3_sub(a[2], a[0]);
	lanes3 e1b = lanes3_sub(b[1], b[0]), e2b = lanes3_sub(b[2], b[0]);
	__m128 e1_sq = _mm_max_ps(lanes3_dot(e1a, e1a), lanes3_dot(e1b, e1b));
	__m128 e2_sq = _mm_max_ps(lanes3_dot(e2a, e2a), lanes3_dot(e2b, e2b));
	return (triangle_normals4){
	    {lanes3_cross(e1a, e2a),
	     lanes3_scale(lanes3_add(lanes3_cross(e1a, e2b), lanes3_cross(e1b, e2a)), _mm_set1_ps(0.5f)),
	     lanes3_cross(e1b, e2b)},
	    _mm_mul_ps(_mm_set1_ps(0.5e-6f), _mm_add_ps(e1_sq, e2_sq))};
}

/* Whether the paths can take the fast lanes: moving (or still) vertices, no guards. */
static bool lanes_fit(const plait_patch_paths *paths)
{
	return paths->motion != NULL && paths->guard == NULL;
}

/* triangles_cone for one to four triangles on paths without guards (the gather's guess: every
 * leaf's cone at every gather, a tenth of hang-self's frame), the triangles in lanes: the
 * operations of triangle_normals_of and cone_round, lane by lane, so the same cone to the bit.
 * Lanes past count repeat the first triangle, which changes no least or largest. The lanes'
 * max and min differ from fmaxf and fminf only on a NaN operand; a NaN there comes from a NaN
 * normal, which ends in no cone on both paths (a failed "in front" test). */
static plait_cone triangles_cone4(const plait_patch_paths *paths, const int (*triangles)[3], const int *which,
                                  int count)
{
	if (count <= 0) {
		return no_cone(); /* as triangles_cone: no normal to sum */
	}
	triangle_normals4 t;
	if (paths->normals != NULL) {
		const triangle_normals *c[4];
		for (int k = 0; k < 4; ++k) {
			c[k] = &paths->normals[which[k < count ? k : 0]];
		}
		for (int m = 0; m < 3; ++m) {
			t.n[m] = (lanes3){_mm_setr_ps(c[0]->n[m].x, c[1]->n[m].x, c[2]->n[m].x, c[3]->n[m].x),
			                  _mm_setr_ps(c[0]->n[m].y, c[1]->n[m].y, c[2]->n[m].y, c[3]->n[m].y),
			                  _mm_setr_ps(c[0]->n[m].z, c[1]->n[m].z, c[2]->n[m].z, c[3]->n[m].z)};
		}
		t.rho = _mm_setr_ps(c[0]->rho, c[1]->rho, c[2]->rho, c[3]->rho);
	} else {
		const int *v[4];
		for (int k = 0; k < 4; ++k) {
			v[k] = triangles[which[k < count ? k : 0]];
		}
		t = triangle_normals4_of(paths, v);
	}
	lanes3 *n = t.n;
	__m128 rho = t.rho;
	/* The axis: the normals' sum, triangle by triangle in order, as triangles_cone adds it. */
	vec3 each[4];
	lanes3_store(lanes3_add(n[0], lanes3_add(n[1], n[2])), each);
	vec3 sum = {0.0f, 0.0f, 0.0f};
	for (int k = 0; k < count; ++k) {
		sum = v3_add(sum, each[k]);
	}
	float length = v3_length(sum);
	if (!(length > 0.0f)) {
		return no_cone();
	}
	vec3 axis = v3_scale(sum, 1.0f / length);
	lanes3 axes = {_mm_set1_ps(axis.x), _mm_set1_ps(axis.y), _mm_set1_ps(axis.z)};
	/* cone_round: every coefficient in front of the axis, tan^2 of the widest. */
	__m128 along[3], widest_sq = _mm_setzero_ps();
	int behind = 0, overflow = 0;
	for (int m = 0; m < 3; ++m) {
		along[m] = lanes3_dot(n[m], axes);
		behind |= _mm_movemask_ps(_mm_cmpngt_ps(along[m], _mm_setzero_ps()));
		lanes3 across = lanes3_cross(n[m], axes);
		__m128 ratio = _mm_div_ps(lanes3_dot(across, across), _mm_mul_ps(along[m], along[m]));
		overflow |= _mm_movemask_ps(_mm_cmpnlt_ps(ratio, _mm_set1_ps(INFINITY)));
		widest_sq = _mm_max_ps(widest_sq, ratio);
	}
	if (behind != 0 || overflow != 0) {
		return no_cone();
	}
	_Alignas(16) float w[4];
	_mm_store_ps(w, widest_sq);
	float widest = sqrtf(plait_maxf(plait_maxf(w[0], w[1]), plait_maxf(w[2], w[3])));
	__m128 least = _mm_min_ps(along[0], _mm_min_ps(along[1], along[2]));
	if (_mm_movemask_ps(_mm_cmpnlt_ps(rho, least)) != 0) {
		return no_cone();
	}
	__m128 tangents =
	    _mm_div_ps(_mm_add_ps(_mm_mul_ps(least, _mm_set1_ps(widest)), rho), _mm_sub_ps(least, rho));
	_Alignas(16) float lane_tangent[4];
	_mm_store_ps(lane_tangent, tangents);
	float tangent = plait_maxf(plait_maxf(plait_maxf(0.0f, lane_tangent[0]), lane_tangent[1]),
	                           plait_maxf(lane_tangent[2], lane_tangent[3]));
	return (plait_cone){axis, angle_of(tangent, 1.0f) + ANGLE_SLACK};
}
#endif

/* The cone of `count` triangles (at most a leaf's) round their normals' mean. */
static plait_cone triangles_cone(const plait_patch_paths *paths, const int (*triangles)[3], const int *which,
                                 int count)
{
#if defined(PLAIT_HAVE_LANES)
	if (count <= 4 && lanes_fit(paths)) {
		return triangles_cone4(paths, triangles, which, count);
	}
#endif
	triangle_normals t[8];
	if (count > 8) {
		int half = count / 2;
		return plait_cone_merge(triangles_cone(paths, triangles, which, half),
		                        triangles_cone(paths, triangles, which + half, count - half));
	}
	vec3 sum = {0.0f, 0.0f, 0.0f};
	for (int k = 0; k < count; ++k) {
		t[k] = paths->normals != NULL ? paths->normals[which[k]]
		                              : triangle_normals_of(paths, triangles[which[k]]);
		sum = v3_add(sum, v3_add(t[k].n[0], v3_add(t[k].n[1], t[k].n[2])));
	}
	float length = v3_length(sum);
	if (!(length > 0.0f)) {
		return no_cone();
	}
	return cone_round(v3_scale(sum, 1.0f / length), t, count);
}

void plait_flat_patches_normals(const plait_flat_patches *fp, const plait_patch_paths *paths, int begin,
                                int end, plait_triangle_normals *out)
{
	const int(*triangles)[3] = (const int(*)[3])fp->triangles;
	int t = begin;
#if defined(PLAIT_HAVE_LANES)
	if (lanes_fit(paths)) {
		for (; t + 4 <= end; t += 4) {
			const int *v[4] = {triangles[t], triangles[t + 1], triangles[t + 2], triangles[t + 3]};
			triangle_normals4 four = triangle_normals4_of(paths, v);
			vec3 n[3][4];
			for (int m = 0; m < 3; ++m) {
				lanes3_store(four.n[m], n[m]);
			}
			_Alignas(16) float rho[4];
			_mm_store_ps(rho, four.rho);
			for (int k = 0; k < 4; ++k) {
				out[t + k] = (triangle_normals){{n[0][k], n[1][k], n[2][k]}, rho[k]};
			}
		}
	}
#endif
	for (; t < end; ++t) {
		out[t] = triangle_normals_of(paths, triangles[t]);
	}
}

static void fit_under(plait_flat_patches *fp, const plait_element_tree *tree, const plait_patch_paths *paths,
                      int n)
{
	const plait_tree_node *node = &tree->nodes[n];
	if (node->count > 0) {
		fp->patch_cone[n] =
		    triangles_cone(paths, (const int(*)[3])fp->triangles, tree->order + node->first, node->count);
		return;
	}
	fit_under(fp, tree, paths, node->first);
	fit_under(fp, tree, paths, node->first + 1);
	fp->patch_cone[n] = plait_cone_merge(fp->patch_cone[node->first], fp->patch_cone[node->first + 1]);
}

void plait_flat_patches_fit_subtree(plait_flat_patches *fp, const plait_element_tree *tree,
                                    const plait_patch_paths *paths, int root)
{
	if (fp->node_count > 0) {
		fit_under(fp, tree, paths, root);
	}
}

static void fit_above(plait_flat_patches *fp, const plait_element_tree *tree, int n, int levels)
{
	const plait_tree_node *node = &tree->nodes[n];
	if (levels == 0 || node->count > 0) {
		return;
	}
	fit_above(fp, tree, node->first, levels - 1);
	fit_above(fp, tree, node->first + 1, levels - 1);
	fp->patch_cone[n] = plait_cone_merge(fp->patch_cone[node->first], fp->patch_cone[node->first + 1]);
}

void plait_flat_patches_fit_above(plait_flat_patches *fp, const plait_element_tree *tree, int levels)
{
	if (fp->node_count > 0) {
		fit_above(fp, tree, 0, levels);
	}
}

void plait_flat_patches_fit(plait_flat_patches *fp, const plait_element_tree *tree,
                            const plait_patch_paths *paths)
{
	plait_flat_patches_fit_subtree(fp, tree, paths, 0);
}

/* ---- The contour ------------------------------------------------------------------------------ */

/* Whether the contour turns forward round a centre along d all along the paths, once round:
 * the centre chosen in the rest shape, else (or failing that) the contour's mean. */
static bool star_round(const plait_flat_patches *fp, int node, vec3 d, const plait_patch_paths *paths,
                       bool chosen);

static bool star_contour(const plait_flat_patches *fp, int node, vec3 d, const plait_patch_paths *paths)
{
	if (fp->contour_first[node + 1] - fp->contour_first[node] < 3) {
		return false;
	}
	bool chosen = fp->centre[node].triangle >= 0;
	return star_round(fp, node, d, paths, chosen) || (chosen && star_round(fp, node, d, paths, false));
}

static bool star_round(const plait_flat_patches *fp, int node, vec3 d, const plait_patch_paths *paths,
                       bool chosen)
{
	const int *contour = fp->contour + fp->contour_first[node];
	int count = fp->contour_first[node + 1] - fp->contour_first[node];
	/* The centre c moves straight like the vertices it is made of (no guard: it is only a
	 * reference point). */
	vec3 ca = {0.0f, 0.0f, 0.0f}, cb = ca, c0 = ca;
	if (chosen) {
		const plait_patch_centre *centre = &fp->centre[node];
		const int *v = fp->triangles[centre->triangle];
		for (int k = 0; k < 3; ++k) {
			ca = v3_mul_add(ca, centre->weight[k], path_start(paths, v[k]));
			cb = v3_mul_add(cb, centre->weight[k], path_end(paths, v[k]));
			c0 = v3_mul_add(c0, centre->weight[k], paths->at[v[k]]);
		}
	} else {
		for (int k = 0; k < count; ++k) {
			ca = v3_add(ca, path_start(paths, contour[k]));
			cb = v3_add(cb, path_end(paths, contour[k]));
			c0 = v3_add(c0, paths->at[contour[k]]);
		}
		float inverse = 1.0f / (float)count;
		ca = v3_scale(ca, inverse);
		cb = v3_scale(cb, inverse);
		c0 = v3_scale(c0, inverse);
	}
	/* A direction across d, to count the contour's turns round c at `at`. */
	vec3 across = fabsf(d.x) < 0.6f ? v3(1.0f, 0.0f, 0.0f) : v3(0.0f, 1.0f, 0.0f);
	vec3 side = v3_cross(d, across);
	bool still = paths->motion == NULL;
	int crossings = 0;
	int i = contour[count - 1];
	vec3 pa = v3_sub(path_start(paths, i), ca), pb = v3_sub(path_end(paths, i), cb);
	float p_side = v3_dot(v3_sub(paths->at[i], c0), side);
	for (int k = 0; k < count; ++k) {
		int j = contour[k];
		vec3 qa = v3_sub(path_start(paths, j), ca), qb = v3_sub(path_end(paths, j), cb);
		/* Edge i-j turns round c the way of d throughout: d . (p x q), quadratic in time, by its
		 * Bernstein coefficients, less what the guards may take off it. */
		float least = v3_dot(d, v3_cross(pa, qa));
		if (!still) {
			float o1 = 0.5f * v3_dot(d, v3_add(v3_cross(pa, qb), v3_cross(pb, qa)));
			least = fminf(least, fminf(o1, v3_dot(d, v3_cross(pb, qb))));
		}
		float p = fmaxf(v3_length(pa), v3_length(pb)), q = fmaxf(v3_length(qa), v3_length(qb));
		float gi = guard(paths, i), gj = guard(paths, j);
		float loss = gi * q + p * gj + gi * gj + 1e-6f * p * q;
		if (!(least > loss)) {
			return false;
		}
		float q_side = v3_dot(v3_sub(paths->at[j], c0), side);
		crossings += p_side < 0.0f && q_side >= 0.0f;
		i = j;
		pa = qa;
		pb = qb;
		p_side = q_side;
	}
	/* Every edge turns forward round c, so the contour winds round it a whole number of times,
	 * the same all along the paths: once is a star-shaped loop. */
	return crossings == 1;
}

bool plait_flat_patches_flat(const plait_flat_patches *fp, int node, const plait_patch_paths *paths,
                             vec3 *axis)
{
	if (fp->node_count == 0 || fp->patch_cone[node].angle >= FLAT_ANGLE ||
	    fp->contour_first[node + 1] == fp->contour_first[node]) {
		return false;
	}
	plait_cone cone = fp->patch_cone[node];
	for (int k = fp->notch_first[node]; k < fp->notch_first[node + 1] && cone.angle < FLAT_ANGLE; ++k) {
		cone =
		    plait_cone_merge(cone, triangles_cone(paths, (const int(*)[3])fp->triangles, &fp->notch[k], 1));
	}
	if (cone.angle >= FLAT_ANGLE || !star_contour(fp, node, cone.axis, paths)) {
		return false;
	}
	if (axis != NULL) {
		*axis = cone.axis;
	}
	return true;
}

/* Whether every coefficient of a triangle's normal over the paths, less its guards' rho, is
 * along d. */
static bool faces(const plait_patch_paths *paths, const int *v, vec3 d)
{
	triangle_normals t = triangle_normals_of(paths, v);
	return v3_dot(t.n[0], d) > t.rho && v3_dot(t.n[1], d) > t.rho && v3_dot(t.n[2], d) > t.rho;
}

/* Whether every triangle triangles[list[k]], k < count, faces d along the paths (faces). */
static bool all_face(const plait_patch_paths *paths, const int (*triangles)[3], const int *list, int count,
                     vec3 d)
{
	int k = 0;
#if defined(PLAIT_HAVE_LANES)
	if (lanes_fit(paths)) {
		lanes3 axis = {_mm_set1_ps(d.x), _mm_set1_ps(d.y), _mm_set1_ps(d.z)};
		for (; k < count; k += 4) {
			const int *v[4];
			for (int lane = 0; lane < 4; ++lane) {
				v[lane] = triangles[list[k + lane < count ? k + lane : k]];
			}
			triangle_normals4 t = triangle_normals4_of(paths, v);
			__m128 front = _mm_and_ps(_mm_cmpgt_ps(lanes3_dot(t.n[0], axis), t.rho),
			                          _mm_and_ps(_mm_cmpgt_ps(lanes3_dot(t.n[1], axis), t.rho),
			                                     _mm_cmpgt_ps(lanes3_dot(t.n[2], axis), t.rho)));
			if (_mm_movemask_ps(front) != 0xF) {
				return false;
			}
		}
		return true;
	}
#endif
	for (; k < count; ++k) {
		if (!faces(paths, triangles[list[k]], d)) {
			return false;
		}
	}
	return true;
}

bool plait_flat_patches_keeps_flat(const plait_flat_patches *fp, int node, vec3 axis,
                                   const plait_patch_paths *paths)
{
	if (fp->node_count == 0 || fp->contour_first[node + 1] == fp->contour_first[node]) {
		return false;
	}
	const int(*triangles)[3] = (const int(*)[3])fp->triangles;
	return all_face(paths, triangles, fp->order + fp->node_begin[node],
	                fp->node_end[node] - fp->node_begin[node], axis) &&
	       all_face(paths, triangles, fp->notch + fp->notch_first[node],
	                fp->notch_first[node + 1] - fp->notch_first[node], axis) &&
	       star_contour(fp, node, axis, paths);
}
