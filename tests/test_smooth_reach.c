/* Smooth reaches of a rigid mesh's corners and edges (collision/smooth_reach.h): what they are
 * on meshes whose answer is known, and the same on any number of workers. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "collision/closest.h"
#include "collision/smooth_reach.h"
#include "core/float_mode.h"
#include "core/parallel.h"
#include "thread_pool.h"

static const plait_allocator heap = {NULL, NULL, NULL};

typedef struct test_mesh {
	plait_vec3 *x;
	int *indices;
	int *sizes;
	int vertex_count, triangle_count;
} test_mesh;

static void test_mesh_free(test_mesh *m)
{
	free(m->x);
	free(m->indices);
	free(m->sizes);
}

static void add_triangle(test_mesh *m, int a, int b, int c)
{
	int t = m->triangle_count++;
	m->indices[3 * t] = a;
	m->indices[3 * t + 1] = b;
	m->indices[3 * t + 2] = c;
	m->sizes[t] = 3;
}

/* A closed UV sphere of radius r, outward faces; bumps > 0 ripples its radius. */
static test_mesh sphere(int slices, int stacks, float r, float bumps)
{
	test_mesh m = {0};
	int rings = stacks - 1;
	m.x = malloc(sizeof *m.x * (size_t)(rings * slices + 2));
	m.indices = malloc(sizeof(int) * 3 * (size_t)(2 * slices * stacks));
	m.sizes = malloc(sizeof(int) * (size_t)(2 * slices * stacks));
	for (int i = 0; i < rings; ++i) {
		float theta = 3.14159265f * (float)(i + 1) / (float)stacks;
		for (int j = 0; j < slices; ++j) {
			float phi = 6.2831853f * (float)j / (float)slices;
			float radius = r * (1.0f + bumps * sinf(3.0f * phi) * sinf(4.0f * theta));
			m.x[i * slices + j] = (plait_vec3){radius * sinf(theta) * cosf(phi), radius * cosf(theta),
			                                   radius * sinf(theta) * sinf(phi)};
		}
	}
	int top = rings * slices, bottom = top + 1;
	m.x[top] = (plait_vec3){0.0f, r, 0.0f};
	m.x[bottom] = (plait_vec3){0.0f, -r, 0.0f};
	m.vertex_count = rings * slices + 2;
	for (int j = 0; j < slices; ++j) {
		int k = (j + 1) % slices;
		add_triangle(&m, top, k, j);
		for (int i = 0; i + 1 < rings; ++i) {
			int a = i * slices + j, b = i * slices + k, c = (i + 1) * slices + j, d = (i + 1) * slices + k;
			add_triangle(&m, a, b, d);
			add_triangle(&m, a, d, c);
		}
		add_triangle(&m, bottom, (rings - 1) * slices + j, (rings - 1) * slices + k);
	}
	return m;
}

/* An n x n grid of unit cells in the XZ plane, folded up by `fold_deg` along x = fold_at. */
static test_mesh folded_grid(int n, float cell, int fold_at, float fold_deg)
{
	test_mesh m = {0};
	m.x = malloc(sizeof *m.x * (size_t)(n * n));
	m.indices = malloc(sizeof(int) * 3 * (size_t)(2 * n * n));
	m.sizes = malloc(sizeof(int) * (size_t)(2 * n * n));
	float turn = fold_deg * 3.14159265f / 180.0f;
	for (int i = 0; i < n; ++i) {
		for (int j = 0; j < n; ++j) {
			float u = (float)(i - fold_at) * cell;
			plait_vec3 p = {u, 0.0f, (float)j * cell};
			if (u > 0.0f) {
				p.x = u * cosf(turn);
				p.y = u * sinf(turn);
			}
			m.x[i * n + j] = p;
		}
	}
	m.vertex_count = n * n;
	for (int i = 0; i + 1 < n; ++i) {
		for (int j = 0; j + 1 < n; ++j) {
			int a = i * n + j, b = a + 1, c = a + n, d = c + 1;
			add_triangle(&m, a, b, d);
			add_triangle(&m, a, d, c);
		}
	}
	return m;
}

typedef struct reaches {
	plait_mesh_shape shape;
	float *vertex;
	float *edge;
	vec3 *vertex_normal; /* the normal each reach holds with */
	vec3 *edge_normal;
} reaches;

/* The mesh's reaches with `workers` workers of a thread pool (1: none, the calling thread). */
static reaches measure(const test_mesh *m, float budget, float range, int workers)
{
	reaches r = {0};
	plait_mesh_def def = {m->x, m->vertex_count, m->sizes, m->triangle_count, m->indices};
	plait_error error;
	cr_assert_eq(plait_mesh_shape_build(&r.shape, &heap, &def, &error), PLAIT_OK, "%s", error.message);
	r.vertex = malloc(sizeof(float) * (size_t)m->vertex_count);
	r.edge = malloc(sizeof(float) * 3 * (size_t)r.shape.triangle_count);
	r.vertex_normal = malloc(sizeof(vec3) * (size_t)m->vertex_count);
	r.edge_normal = malloc(sizeof(vec3) * 3 * (size_t)r.shape.triangle_count);
	plait_thread_pool *pool = workers > 1 ? plait_thread_pool_create(workers) : NULL;
	plait_parallel parallel;
	plait_parallel_init(&parallel, pool != NULL ? plait_thread_pool_enqueue : NULL,
	                    pool != NULL ? plait_thread_pool_finish : NULL, pool, workers);
	plait_float_mode saved = plait_float_mode_enter(); /* as in a step: the workers' mode */
	plait_parallel_begin(&parallel);
	bool ok = plait_mesh_smooth_reaches_with_normals(&r.shape, &heap, workers > 1 ? &parallel : NULL, budget,
	                                                 range, r.vertex, r.edge, r.vertex_normal, r.edge_normal);
	plait_parallel_end(&parallel);
	plait_float_mode_leave(saved);
	if (pool != NULL) {
		plait_thread_pool_destroy(pool);
	}
	cr_assert(ok);
	return r;
}

static void reaches_free(reaches *r)
{
	plait_mesh_shape_destroy(&r->shape, &heap);
	free(r->vertex);
	free(r->edge);
	free(r->vertex_normal);
	free(r->edge_normal);
}

/* The flat grid with vertex (20, 20) moved onto (20, 21): the faces with both have two vertices
 * at one point (no normal, no closest point), and some round it turn over. */
static test_mesh collapsed_grid(void)
{
	test_mesh m = folded_grid(40, 0.01f, 20, 0.0f);
	m.x[20 * 40 + 20] = m.x[20 * 40 + 21];
	return m;
}

Test(smooth_reach, the_same_on_any_number_of_workers)
{
	/* A rippled sphere: reaches of every length, and features that cost unevenly. */
	test_mesh m = sphere(36, 24, 0.5f, 0.03f);
	reaches one = measure(&m, 0.002f, 0.08f, 1);
	int spread = 0;
	for (int v = 0; v < m.vertex_count; ++v) {
		spread += one.vertex[v] > 0.0f && one.vertex[v] < 0.08f - 0.002f;
	}
	cr_assert_gt(spread, m.vertex_count / 4, "only %d corners have reaches inside the range", spread);
	for (int workers = 2; workers <= 8; workers *= 4) {
		reaches many = measure(&m, 0.002f, 0.08f, workers);
		cr_expect(memcmp(one.vertex, many.vertex, sizeof(float) * (size_t)m.vertex_count) == 0,
		          "corner reaches differ on %d workers", workers);
		cr_expect(memcmp(one.edge, many.edge, sizeof(float) * 3 * (size_t)one.shape.triangle_count) == 0,
		          "edge reaches differ on %d workers", workers);
		reaches_free(&many);
	}
	reaches_free(&one);
	test_mesh_free(&m);
	test_mesh collapsed = collapsed_grid();
	reaches alone = measure(&collapsed, 0.002f, 0.05f, 1), shared = measure(&collapsed, 0.002f, 0.05f, 8);
	cr_expect(memcmp(alone.vertex, shared.vertex, sizeof(float) * (size_t)collapsed.vertex_count) == 0);
	cr_expect(memcmp(alone.edge, shared.edge, sizeof(float) * 3 * (size_t)alone.shape.triangle_count) == 0);
	reaches_free(&alone);
	reaches_free(&shared);
	test_mesh_free(&collapsed);
}

/* Faces with two vertices at one point are walls where they are: corners round them reach up to
 * them, not nowhere (a closest point of 0 / 0 once made them walls at 0 for every corner whose
 * search met them). */
Test(smooth_reach, a_collapsed_face_is_a_wall_where_it_is)
{
	float budget = 0.002f, range = 0.08f;
	test_mesh m = collapsed_grid();
	reaches s = measure(&m, budget, range, 1);
	int looked = 0;
	for (int i = 8; i <= 32; ++i) {
		for (int j = 8; j <= 32; ++j) {
			/* Every face that moved lies within 0.03 of the moved vertex's old place. */
			float rho = 0.01f * sqrtf((float)((i - 20) * (i - 20) + (j - 20) * (j - 20)));
			if (rho < 0.04f || rho > range) {
				continue;
			}
			float reach = s.vertex[i * 40 + j];
			cr_expect(reach >= rho - 0.03f - budget - 1e-5f && reach <= rho + 0.01f,
			          "corner (%d, %d), %g from the collapsed faces' middle, reaches %g", i, j, (double)rho,
			          (double)reach);
			looked += 1;
		}
	}
	cr_assert_gt(looked, 50);
	reaches_free(&s);
	test_mesh_free(&m);
}

/* The reach of a corner (b == a) or an edge by the definition, without shortcuts: every face
 * within range, its exact distance and its angle against `normal`, taken nearest first. */
typedef struct sample {
	float distance, angle;
} sample;

static int by_distance(const void *a, const void *b)
{
	const sample *x = a, *y = b;
	return x->distance < y->distance ? -1 : x->distance > y->distance;
}

static float point_triangle_distance(vec3 p, const vec3 *t)
{
	int region;
	return v3_length(v3_sub(p, plait_closest_point_on_triangle(p, t[0], t[1], t[2], &region, NULL)));
}

static float feature_distance(vec3 a, vec3 b, const vec3 *t)
{
	float d = fminf(point_triangle_distance(a, t), point_triangle_distance(b, t));
	for (int k = 0; k < 3; ++k) {
		float s, u;
		d = fminf(d, sqrtf(plait_closest_segments(a, b, t[k], t[(k + 1) % 3], &s, &u)));
	}
	vec3 n = v3_cross(v3_sub(t[1], t[0]), v3_sub(t[2], t[0]));
	float da = v3_dot(v3_sub(a, t[0]), n), db = v3_dot(v3_sub(b, t[0]), n);
	if ((da < 0.0f) != (db < 0.0f)) {
		d = fminf(d, point_triangle_distance(v3_lerp(a, b, da / (da - db)), t));
	}
	return d;
}

/* Each triangle edge's other face (across[3 t + k], for the edge from corner k to k + 1; -1 if
 * none has it the other way round), and whether a triangle has an edge no other triangle
 * shares (open: the reach takes it for a wall). By sorted edges, for meshes of any size. */
typedef struct adjacency {
	int *across;
	bool *open;
} adjacency;

typedef struct directed_edge {
	int low, high, triangle, corner;
} directed_edge;

static int by_vertices(const void *a, const void *b)
{
	const directed_edge *x = a, *y = b;
	if (x->low != y->low) {
		return x->low < y->low ? -1 : 1;
	}
	return x->high < y->high ? -1 : x->high > y->high;
}

static adjacency adjacency_of(const plait_mesh_shape *shape)
{
	int nt = shape->triangle_count;
	adjacency adj = {malloc(sizeof(int) * 3 * (size_t)nt), calloc((size_t)nt, sizeof(bool))};
	directed_edge *edges = malloc(sizeof *edges * 3 * (size_t)nt);
	for (int t = 0; t < nt; ++t) {
		for (int k = 0; k < 3; ++k) {
			int a = shape->triangles[t][k], b = shape->triangles[t][(k + 1) % 3];
			edges[3 * t + k] = (directed_edge){a < b ? a : b, a < b ? b : a, t, k};
			adj.across[3 * t + k] = -1;
		}
	}
	qsort(edges, 3 * (size_t)nt, sizeof *edges, by_vertices);
	for (int i = 0; i < 3 * nt;) {
		int j = i + 1;
		while (j < 3 * nt && by_vertices(&edges[i], &edges[j]) == 0) {
			++j;
		}
		for (int x = i; x < j; ++x) {
			const directed_edge *e = &edges[x];
			adj.open[e->triangle] = adj.open[e->triangle] || j - i == 1;
			int from = shape->triangles[e->triangle][e->corner];
			for (int y = i; y < j; ++y) {
				const directed_edge *f = &edges[y];
				/* The other face has the edge the other way round. */
				if (y != x && shape->triangles[f->triangle][f->corner] != from) {
					adj.across[3 * e->triangle + e->corner] = f->triangle;
				}
			}
		}
		i = j;
	}
	free(edges);
	return adj;
}

static void adjacency_free(adjacency *adj)
{
	free(adj->across);
	free(adj->open);
}

static float reference_reach(const plait_mesh_shape *shape, const adjacency *adj, vec3 a, vec3 b, vec3 normal,
                             float budget, float range)
{
	sample *samples = malloc(sizeof *samples * (size_t)shape->triangle_count);
	int count = 0;
	for (int t = 0; t < shape->triangle_count; ++t) {
		const int *tri = shape->triangles[t];
		vec3 x[3] = {shape->positions[tri[0]], shape->positions[tri[1]], shape->positions[tri[2]]};
		/* Faces whose box is farther than the range along an axis are (the one shortcut). */
		vec3 lower = v3_min(x[0], v3_min(x[1], x[2])), upper = v3_max(x[0], v3_max(x[1], x[2]));
		vec3 from = v3_min(a, b), to = v3_max(a, b);
		if (lower.x - to.x > 2.0f * range || from.x - upper.x > 2.0f * range ||
		    lower.y - to.y > 2.0f * range || from.y - upper.y > 2.0f * range ||
		    lower.z - to.z > 2.0f * range || from.z - upper.z > 2.0f * range) {
			continue;
		}
		float distance = fmaxf(feature_distance(a, b, x) - 1e-6f, 0.0f);
		if (distance <= range) {
			float cosine = fmaxf(-1.0f, fminf(1.0f, v3_dot(shape->normals[t], normal)));
			samples[count++] = (sample){distance, adj->open[t] ? 1.0f : acosf(cosine)};
		}
	}
	qsort(samples, (size_t)count, sizeof *samples, by_distance);
	float t = 0.0f, fall = 0.0f, steepest = 0.0f, reach = range - budget;
	for (int k = 0;;) {
		while (k < count && samples[k].distance - budget <= t) {
			steepest = fmaxf(steepest, samples[k++].angle);
		}
		if (steepest >= 1.0f) {
			reach = t;
			break;
		}
		float next = k < count ? samples[k].distance - budget : range - budget;
		float slope = tanf(steepest);
		if (fall + slope * (next - t) >= budget) {
			reach = t + (budget - fall) / slope;
			break;
		}
		if (k >= count) {
			reach = next;
			break;
		}
		fall += slope * (next - t);
		t = next;
	}
	free(samples);
	return reach;
}

static vec3 unit(vec3 v)
{
	return v3_scale(v, 1.0f / v3_length(v));
}

/* What expect_reaches_as_defined_every found: of the features it checked, how many reach less
 * than the definition allows (measured with a cluster of a fine mesh, smooth_reach.c), and over
 * the edges checked, the sums of their reaches and of the reaches the definition gives them
 * with their own normals. */
typedef struct reach_check {
	int checked, shorter;
	double reach_sum, own_sum;
} reach_check;

/* The library's reaches against the definition (on closed or open meshes whose features all
 * have a side), every `stride`th triangle's edges and every (stride + 2)th corner: each edge's
 * is its own, each corner's the shorter of its own and its edges' (a corner is kept whenever an
 * edge of it is). Each reach holds with the normal the library reports for it (the argument's
 * n0: a feature's own, or its cluster's): it is never longer than the definition gives with
 * that normal. Measured on its own, a feature reaches just that; measured with a cluster,
 * shorter (counted). */
static reach_check expect_reaches_as_defined_every(const test_mesh *m, float budget, float range, int stride)
{
	reaches s = measure(m, budget, range, 2);
	const plait_mesh_shape *shape = &s.shape;
	adjacency adj = adjacency_of(shape);
	float tolerance = 1e-5f * range;
	reach_check check = {0};
	for (int t = 0; t < shape->triangle_count; t += stride) {
		for (int k = 0; k < 3; ++k) {
			int a = shape->triangles[t][k], b = shape->triangles[t][(k + 1) % 3];
			int across = adj.across[3 * t + k]; /* the other face of the edge */
			if (across < 0) {
				continue; /* a border: no reach */
			}
			float reach = s.edge[3 * t + k];
			float reference = reference_reach(shape, &adj, shape->positions[a], shape->positions[b],
			                                  s.edge_normal[3 * t + k], budget, range);
			cr_expect(reach <= reference + tolerance, "edge %d-%d reaches %g, by definition %g", a, b,
			          (double)reach, (double)reference);
			bool shorter = reach < reference - tolerance;
			vec3 own = unit(v3_add(shape->normals[t], shape->normals[across]));
			check.checked += 1;
			check.shorter += shorter;
			check.reach_sum += reach;
			check.own_sum += shorter ? reference_reach(shape, &adj, shape->positions[a], shape->positions[b],
			                                           own, budget, range)
			                         : reach;
		}
	}
	for (int v = 0; v < m->vertex_count; v += stride + 2) {
		float edges = range - budget;
		bool border = false;
		for (int t = 0; t < shape->triangle_count; ++t) {
			for (int k = 0; k < 3; ++k) {
				int a = shape->triangles[t][k], b = shape->triangles[t][(k + 1) % 3];
				if (a == v || b == v) {
					edges = fminf(edges, s.edge[3 * t + k]);
					border = border || s.edge[3 * t + k] < 0.0f;
				}
			}
		}
		if (border) {
			continue;
		}
		float own = reference_reach(shape, &adj, shape->positions[v], shape->positions[v], s.vertex_normal[v],
		                            budget, range);
		float expected = fminf(own, edges);
		cr_expect(s.vertex[v] <= expected + tolerance, "corner %d reaches %g: its own %g, its edges' %g", v,
		          (double)s.vertex[v], (double)own, (double)edges);
		check.checked += 1;
		check.shorter += s.vertex[v] < expected - tolerance;
	}
	adjacency_free(&adj);
	reaches_free(&s);
	return check;
}

/* Every fifth triangle's edges and every seventh corner. */
static void expect_reaches_as_defined(const test_mesh *m, float budget, float range)
{
	reach_check check = expect_reaches_as_defined_every(m, budget, range, 5);
	cr_expect_eq(check.shorter, 0, "%d of %d features reach less than defined", check.shorter, check.checked);
}

Test(smooth_reach, edges_and_corners_reach_as_defined)
{
	test_mesh bumpy = sphere(36, 24, 0.5f, 0.03f);
	expect_reaches_as_defined(&bumpy, 0.002f, 0.08f);
	test_mesh_free(&bumpy);
	test_mesh fold = folded_grid(24, 0.01f, 12, 40.0f);
	expect_reaches_as_defined(&fold, 0.002f, 0.05f);
	test_mesh_free(&fold);
}

/* Where reaches end just short of the range or just past it, a bound that takes some features
 * for reaching the whole range unmeasured (smooth_reach.c) must take none that do not: over
 * ranges either side of a sphere's reach, every feature's reach is as defined. */
Test(smooth_reach, reaches_near_the_range_are_as_defined)
{
	float r = 0.5f, budget = 0.002f;
	float smooth = sqrtf(budget * budget + 2.0f * r * budget) - budget;
	test_mesh m = sphere(96, 64, r, 0.0f);
	for (int k = 0; k < 5; ++k) {
		float range = budget + (0.6f + 0.1f * (float)k) * smooth;
		cr_expect_eq(expect_reaches_as_defined_every(&m, budget, range, 7).shorter, 0);
	}
	test_mesh_free(&m);
	/* A fine flat sheet folded by 10 degrees: the faces past the fold come in at t = x - M for a
	 * feature x from it, so it reaches D = 18.5 mm, the whole range, from x = 9.2 mm on. The
	 * features on the 2 mm lattice nearest that, 8 and 10 mm from the fold, fall either side
	 * of it by about a millimetre; a bound that let a face come in a millimetre late would take
	 * the nearer ones for reaching the whole range. */
	test_mesh fold = folded_grid(60, 0.002f, 30, 10.0f);
	cr_expect_eq(expect_reaches_as_defined_every(&fold, budget, 0.0205f, 2).shorter, 0);
	test_mesh_free(&fold);
}

/* A ball of radius 5 cm in fine triangles (3-4 mm) under a range of 5 cm: a limb under a cloth
 * of 2.4 cm triangles. Measured feature by feature its set-up cost grows with the square of the
 * density (17 s on one thread in 19,800 triangles); its features are measured in clusters
 * instead. Every reach holds by the definition with the normal it reports, and the clusters
 * take off less than a fifth of what the features would reach on their own. */
Test(smooth_reach, a_fine_curved_mesh_is_measured_in_clusters_that_reach_no_farther_than_its_features)
{
	float budget = 0.002f, range = 0.05f;
	test_mesh m = sphere(80, 54, 0.05f, 0.0f);
	reach_check check = expect_reaches_as_defined_every(&m, budget, range, 17);
	cr_assert_gt(check.shorter, check.checked / 2, "only %d of %d features measured with clusters",
	             check.shorter, check.checked);
	cr_expect_gt(check.reach_sum, 0.7 * check.own_sum,
	             "edges reach %g m in all, on their own they would %g m", check.reach_sum, check.own_sum);
	/* The same reaches on any number of workers. */
	reaches one = measure(&m, budget, range, 1), many = measure(&m, budget, range, 8);
	cr_expect(memcmp(one.vertex, many.vertex, sizeof(float) * (size_t)m.vertex_count) == 0);
	cr_expect(memcmp(one.edge, many.edge, sizeof(float) * 3 * (size_t)one.shape.triangle_count) == 0);
	reaches_free(&one);
	reaches_free(&many);
	test_mesh_free(&m);
}

/* On a sphere of radius R the faces within t turn by about t / R, so F(D) = (D^2 / 2 + M D) / R
 * and the reach is sqrt(M^2 + 2 R M) - M. A UV sphere's flat faces turn in steps (by about
 * h / R over faces of size h, some of it at 0): reaches fall short of that, never beyond. */
Test(smooth_reach, a_sphere_reaches_no_farther_than_its_curvature_allows)
{
	float r = 0.5f, budget = 0.002f, range = 0.12f;
	test_mesh m = sphere(96, 64, r, 0.0f);
	reaches s = measure(&m, budget, range, 2);
	float smooth = sqrtf(budget * budget + 2.0f * r * budget) - budget;
	int near_equator = 0;
	for (int v = 0; v < m.vertex_count; ++v) {
		if (fabsf(m.x[v].y) < 0.1f) {
			near_equator += 1;
			cr_expect(s.vertex[v] > 0.4f * smooth && s.vertex[v] < smooth,
			          "corner %d reaches %g m, a smooth sphere %g", v, (double)s.vertex[v], (double)smooth);
		}
	}
	cr_assert_gt(near_equator, 100);
	reaches_free(&s);
	test_mesh_free(&m);
}

/* A flat sheet reaches as far as it is looked at; a right-angled fold has no reach along it,
 * and corners farther from it than the range do not see it. */
Test(smooth_reach, a_fold_ends_the_reach_of_what_sees_it)
{
	float cell = 0.01f, budget = 0.002f, range = 0.05f;
	test_mesh m = folded_grid(40, cell, 20, 90.0f);
	reaches s = measure(&m, budget, range, 1);
	int n = 40;
	for (int i = 1; i + 1 < n; ++i) {
		for (int j = 1; j + 1 < n; ++j) {
			float from_fold = fabsf((float)(i - 20)) * cell;
			float from_border =
			    fminf(fminf((float)i, (float)(n - 1 - i)), fminf((float)j, (float)(n - 1 - j))) * cell;
			float reach = s.vertex[i * n + j];
			if (from_fold > range + 0.01f && from_border > range + 0.02f) { /* open faces are walls */
				cr_expect(fabsf(reach - (range - budget)) < 1e-5f * range,
				          "corner (%d, %d), flat around, reaches %.9g", i, j, (double)reach);
			}
			if (i == 20) {
				cr_expect(reach < budget, "corner (%d, %d) on the fold reaches %g", i, j, (double)reach);
			}
		}
	}
	reaches_free(&s);
	test_mesh_free(&m);
}
