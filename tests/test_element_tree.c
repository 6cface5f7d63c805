/* collision/element_tree.h and the mesh shape's box queries: every pair of boxes that meet is
 * reported once, and nothing else, whatever the leaves hold. A pair missed here is a contact the
 * gather never lists, so the traversals are compared with a test of every pair, on boxes that
 * touch exactly, lie a margin apart, are empty lanes' neighbours (leaves of 1 to 4), or have no
 * bounds at all (a frame gone non-finite). */
#include <criterion/criterion.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "collision/element_tree.h"
#include "collision/mesh_shape.h"
#include "test_support.h"

static const plait_allocator heap = {NULL, NULL, NULL};

/* The traversals as compiled without SSE2 (included at the end of this file): the portable
 * code every other build runs, to which the lanes must keep the visit order. */
void portable_tree_pairs(const plait_element_tree *tree, const vec3 *lower, const vec3 *upper,
                         plait_element_pair_visitor *visit, void *context);
void portable_tree_pairs_between(const plait_element_tree *tree_a, const vec3 *lower_a, const vec3 *upper_a,
                                 const plait_element_tree *tree_b, const vec3 *lower_b, const vec3 *upper_b,
                                 vec3 margin, const plait_node_skip *skip, plait_element_pair_visitor *visit,
                                 void *context);

/* A small deterministic generator (the test must not depend on the libc's rand). */
static float next_unit(unsigned *state)
{
	*state = *state * 1664525u + 1013904223u;
	return (float)(*state >> 8) / (float)(1u << 24);
}

/* `count` boxes scattered in a cube of side `spread`, sizes up to `size`; coordinates on a grid
 * of 1/64 so that many boxes touch exactly (lower of one == upper of another). */
static void random_boxes(unsigned seed, int count, float spread, float size, vec3 *lower, vec3 *upper,
                         vec3 *centre)
{
	unsigned state = seed;
	for (int e = 0; e < count; ++e) {
		float c[3], h[3];
		for (int k = 0; k < 3; ++k) {
			c[k] = floorf(next_unit(&state) * spread * 64.0f) / 64.0f;
			h[k] = floorf(next_unit(&state) * size * 64.0f) / 64.0f;
		}
		lower[e] = v3(c[0] - h[0], c[1] - h[1], c[2] - h[2]);
		upper[e] = v3(c[0] + h[0], c[1] + h[1], c[2] + h[2]);
		centre[e] = v3(c[0], c[1], c[2]);
	}
}

static bool meet(vec3 la, vec3 ua, vec3 lb, vec3 ub, vec3 margin)
{
	return la.x <= ub.x + margin.x && lb.x <= ua.x + margin.x && la.y <= ub.y + margin.y &&
	       lb.y <= ua.y + margin.y && la.z <= ub.z + margin.z && lb.z <= ua.z + margin.z;
}

typedef struct pair_record {
	int count_a, count_b;
	unsigned char *seen; /* count_a x count_b, how many times each pair was reported */
	int reported;
} pair_record;

static void record(int a, int b, void *context)
{
	pair_record *r = context;
	cr_assert(a >= 0 && a < r->count_a && b >= 0 && b < r->count_b, "pair (%d, %d) out of range", a, b);
	r->seen[a * r->count_b + b] += 1;
	r->reported += 1;
}

Test(element_tree, self_pairs_are_every_pair_that_meets_once)
{
	for (int count = 1; count <= 300; count += count < 12 ? 1 : 37) {
		vec3 *lower = malloc(sizeof *lower * (size_t)count), *upper = malloc(sizeof *upper * (size_t)count);
		vec3 *centre = malloc(sizeof *centre * (size_t)count);
		random_boxes(7u + (unsigned)count, count, 1.0f, 0.08f, lower, upper, centre);
		if (count % 3 == 0) {
			/* A frame gone non-finite: one box without bounds, which meets every other. */
			lower[count / 2] = v3(-INFINITY, -INFINITY, -INFINITY);
			upper[count / 2] = v3(INFINITY, INFINITY, INFINITY);
		}
		plait_element_tree tree = {0};
		cr_assert(plait_element_tree_build(&tree, &heap, centre, count));
		plait_element_tree_refit(&tree, lower, upper);
		pair_record r = {count, count, calloc((size_t)count * (size_t)count, 1), 0};
		plait_element_tree_pairs(&tree, lower, upper, record, &r);
		int expected = 0;
		for (int a = 0; a < count; ++a) {
			for (int b = a + 1; b < count; ++b) {
				bool should = meet(lower[a], upper[a], lower[b], upper[b], v3(0.0f, 0.0f, 0.0f));
				int times = r.seen[a * count + b] + r.seen[b * count + a];
				cr_assert_eq(times, should ? 1 : 0, "%d boxes: pair (%d, %d) reported %d times, meets: %d",
				             count, a, b, times, should);
				expected += should;
			}
			cr_assert_eq(r.seen[a * count + a], 0, "element %d paired with itself", a);
		}
		cr_assert_eq(r.reported, expected);
		free(r.seen);
		plait_element_tree_destroy(&tree, &heap);
		free(lower);
		free(upper);
		free(centre);
	}
}

Test(element_tree, pairs_between_trees_within_the_margin)
{
	const int count_a = 97, count_b = 61;
	vec3 la[97], ua[97], ca[97], lb[61], ub[61], cb[61];
	random_boxes(11u, count_a, 1.0f, 0.05f, la, ua, ca);
	random_boxes(23u, count_b, 1.0f, 0.05f, lb, ub, cb);
	la[40] = v3(-INFINITY, -INFINITY, -INFINITY); /* a box without bounds meets every other */
	ua[40] = v3(INFINITY, INFINITY, INFINITY);
	plait_element_tree a = {0}, b = {0};
	cr_assert(plait_element_tree_build(&a, &heap, ca, count_a));
	cr_assert(plait_element_tree_build(&b, &heap, cb, count_b));
	plait_element_tree_refit(&a, la, ua);
	plait_element_tree_refit(&b, lb, ub);
	/* Each axis its own margin too (a tree moving against the other along one axis). */
	const vec3 margins[] = {{0.0f, 0.0f, 0.0f},
	                        {1.0f / 64.0f, 1.0f / 64.0f, 1.0f / 64.0f},
	                        {0.1f, 0.1f, 0.1f},
	                        {0.0f, 0.2f, 0.0f},
	                        {0.05f, 0.0f, 0.15f}};
	for (int m = 0; m < 5; ++m) {
		pair_record r = {count_a, count_b, calloc((size_t)count_a * (size_t)count_b, 1), 0};
		plait_element_tree_pairs_between(&a, la, ua, &b, lb, ub, margins[m], NULL, record, &r);
		for (int i = 0; i < count_a; ++i) {
			for (int j = 0; j < count_b; ++j) {
				bool should = meet(la[i], ua[i], lb[j], ub[j], margins[m]);
				cr_assert_eq(r.seen[i * count_b + j], should ? 1 : 0,
				             "margins %d: pair (%d, %d) reported %d times", m, i, j, r.seen[i * count_b + j]);
			}
		}
		free(r.seen);
	}
	plait_element_tree_destroy(&a, &heap);
	plait_element_tree_destroy(&b, &heap);
}

/* A query reports every element whose box comes within the margin of the query box, along
 * each axis its own (the mending's queries between objects moving against each other along
 * one axis), once, and no other. */
static void mark_element(int e, void *context)
{
	unsigned char *seen = context;
	seen[e] += 1;
}

Test(element_tree, a_query_finds_every_box_within_its_margins)
{
	enum { COUNT = 211 };
	vec3 lower[COUNT], upper[COUNT], centre[COUNT];
	random_boxes(41u, COUNT, 1.0f, 0.05f, lower, upper, centre);
	plait_element_tree tree = {0};
	cr_assert(plait_element_tree_build(&tree, &heap, centre, COUNT));
	plait_element_tree_refit(&tree, lower, upper);
	const vec3 margins[] = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.25f, 0.0f}, {0.1f, 0.0f, 0.03f}};
	unsigned state = 3u;
	for (int q = 0; q < 60; ++q) {
		vec3 c = v3(next_unit(&state), next_unit(&state), next_unit(&state));
		float h = 0.1f * next_unit(&state);
		vec3 box_lower = v3_sub(c, v3(h, h, h)), box_upper = v3_add(c, v3(h, h, h));
		for (int m = 0; m < 3; ++m) {
			unsigned char seen[COUNT] = {0};
			plait_element_tree_query(&tree, lower, upper, box_lower, box_upper, margins[m], mark_element,
			                         seen);
			for (int e = 0; e < COUNT; ++e) {
				bool should = meet(lower[e], upper[e], box_lower, box_upper, margins[m]);
				cr_assert_eq(seen[e], should ? 1 : 0, "query %d, margins %d: element %d reported %d times", q,
				             m, e, seen[e]);
			}
		}
	}
	plait_element_tree_destroy(&tree, &heap);
}

/* The visits in order. */
typedef struct visit_log {
	int (*pairs)[2];
	int count, capacity;
} visit_log;

static void log_pair(int a, int b, void *context)
{
	visit_log *log = context;
	cr_assert_lt(log->count, log->capacity);
	log->pairs[log->count][0] = a;
	log->pairs[log->count++][1] = b;
}

static void expect_same_visits(const visit_log *got, const visit_log *want, const char *what)
{
	cr_assert_eq(got->count, want->count, "%s: %d visits, the portable code's %d", what, got->count,
	             want->count);
	for (int k = 0; k < got->count; ++k) {
		cr_assert(got->pairs[k][0] == want->pairs[k][0] && got->pairs[k][1] == want->pairs[k][1],
		          "%s: visit %d is (%d, %d), the portable code's (%d, %d)", what, k, got->pairs[k][0],
		          got->pairs[k][1], want->pairs[k][0], want->pairs[k][1]);
	}
}

/* The visit order feeds the order of the contact list, so of every result: the lanes must meet
 * the pairs in the portable code's order, or builds with and without SSE2 would part ways. */
Test(element_tree, visits_come_in_the_portable_codes_order)
{
	enum { COUNT = 203, OTHER = 77, ROOM = COUNT * COUNT };
	vec3 lower[COUNT], upper[COUNT], centre[COUNT], lb[OTHER], ub[OTHER], cb[OTHER];
	random_boxes(31u, COUNT, 1.0f, 0.09f, lower, upper, centre);
	random_boxes(37u, OTHER, 1.0f, 0.07f, lb, ub, cb);
	lower[100] = v3(-INFINITY, -INFINITY, -INFINITY);
	upper[100] = v3(INFINITY, INFINITY, INFINITY);
	plait_element_tree tree = {0}, other = {0};
	cr_assert(plait_element_tree_build(&tree, &heap, centre, COUNT));
	cr_assert(plait_element_tree_build(&other, &heap, cb, OTHER));
	plait_element_tree_refit(&tree, lower, upper);
	plait_element_tree_refit(&other, lb, ub);
	visit_log got = {malloc(sizeof *got.pairs * ROOM), 0, ROOM},
	          want = {malloc(sizeof *want.pairs * ROOM), 0, ROOM};
	plait_element_tree_pairs(&tree, lower, upper, log_pair, &got);
	portable_tree_pairs(&tree, lower, upper, log_pair, &want);
	expect_same_visits(&got, &want, "self");
	got.count = want.count = 0;
	plait_element_tree_pairs_between(&tree, lower, upper, &other, lb, ub, v3(0.02f, 0.01f, 0.03f), NULL,
	                                 log_pair, &got);
	portable_tree_pairs_between(&tree, lower, upper, &other, lb, ub, v3(0.02f, 0.01f, 0.03f), NULL, log_pair,
	                            &want);
	expect_same_visits(&got, &want, "between");
	free(got.pairs);
	free(want.pairs);
	plait_element_tree_destroy(&tree, &heap);
	plait_element_tree_destroy(&other, &heap);
}

typedef struct visit_count {
	int visited;
} visit_count;

static void count_triangle(int t, void *context)
{
	(void)t;
	((visit_count *)context)->visited += 1;
}

/* A grid of 12 x 12 quads over [0, 1]^2 at z = 0, bent up along x so that boxes differ. */
enum { BENT_N = 13 };
typedef struct bent_grid {
	plait_vec3 positions[BENT_N * BENT_N];
	int face_sizes[(BENT_N - 1) * (BENT_N - 1)], faces[4 * (BENT_N - 1) * (BENT_N - 1)];
} bent_grid;

static plait_mesh_def make_bent_grid(bent_grid *g)
{
	enum { N = BENT_N };
	for (int j = 0; j < N; ++j) {
		for (int i = 0; i < N; ++i) {
			float x = (float)i / (float)(N - 1), y = (float)j / (float)(N - 1);
			g->positions[j * N + i] = (plait_vec3){x, y, 0.5f * x * x};
		}
	}
	for (int j = 0; j + 1 < N; ++j) {
		for (int i = 0; i + 1 < N; ++i) {
			int f = j * (N - 1) + i;
			g->face_sizes[f] = 4;
			g->faces[4 * f + 0] = j * N + i;
			g->faces[4 * f + 1] = j * N + i + 1;
			g->faces[4 * f + 2] = (j + 1) * N + i + 1;
			g->faces[4 * f + 3] = (j + 1) * N + i;
		}
	}
	return (plait_mesh_def){g->positions, N * N, g->face_sizes, (N - 1) * (N - 1), g->faces};
}

Test(mesh_shape, any_is_whether_the_visit_finds_a_triangle)
{
	bent_grid grid;
	plait_mesh_def def = make_bent_grid(&grid);
	plait_mesh_shape shape = {0};
	plait_error error = {0};
	cr_assert_eq(plait_mesh_shape_build(&shape, &heap, &def, &error), PLAIT_OK, "%s", error.message);
	unsigned state = 5u;
	int found = 0;
	for (int k = 0; k < 2000; ++k) {
		float x = 1.4f * next_unit(&state) - 0.2f, y = 1.4f * next_unit(&state) - 0.2f;
		vec3 c = v3(x, y, 0.5f * x * x + 0.3f * (next_unit(&state) - 0.5f)); /* about the surface */
		float h = 0.06f * next_unit(&state);
		vec3 lower = v3_sub(c, v3(h, h, h)), upper = v3_add(c, v3(h, h, h));
		visit_count v = {0};
		plait_mesh_shape_visit(&shape, lower, upper, true, count_triangle, &v);
		cr_assert_eq(plait_mesh_shape_any(&shape, lower, upper), v.visited > 0,
		             "box %d: any says %d, the visit met %d triangles", k, !(v.visited > 0), v.visited);
		found += v.visited > 0;
	}
	cr_assert(found > 200 && found < 1800, "the boxes should both meet and miss the mesh (%d met)", found);
	plait_mesh_shape_destroy(&shape, &heap);
}

typedef struct visit_marks {
	unsigned char marks[2 * (BENT_N - 1) * (BENT_N - 1)];
} visit_marks;

static void mark_triangle(int t, void *context)
{
	((visit_marks *)context)->marks[t] += 1;
}

/* Every query of the hierarchy against every triangle, one by one: the visit meets each
 * triangle whose box (over its sweep) overlaps, once, and the distance is the nearest. */
static void expect_queries_match_the_triangles(const plait_mesh_shape *shape, const char *when)
{
	unsigned state = 11u;
	int near = 0;
	for (int k = 0; k < 1000; ++k) {
		float x = 1.4f * next_unit(&state) - 0.2f, y = 1.4f * next_unit(&state) - 0.2f;
		vec3 c = v3(x, y, 0.5f * x * x + 0.4f * (next_unit(&state) - 0.5f));
		float h = 0.06f * next_unit(&state);
		vec3 lower = v3_sub(c, v3(h, h, h)), upper = v3_add(c, v3(h, h, h));
		visit_marks v = {{0}};
		plait_mesh_shape_visit(shape, lower, upper, true, mark_triangle, &v);
		float nearest = INFINITY;
		for (int t = 0; t < shape->triangle_count; ++t) {
			const int *tri = shape->triangles[t];
			vec3 tl =
			    v3_min(shape->positions[tri[0]], v3_min(shape->positions[tri[1]], shape->positions[tri[2]]));
			vec3 tu =
			    v3_max(shape->positions[tri[0]], v3_max(shape->positions[tri[1]], shape->positions[tri[2]]));
			if (shape->start_positions != NULL) {
				const vec3 *s = shape->start_positions;
				tl = v3_min(tl, v3_min(s[tri[0]], v3_min(s[tri[1]], s[tri[2]])));
				tu = v3_max(tu, v3_max(s[tri[0]], v3_max(s[tri[1]], s[tri[2]])));
			}
			bool overlaps = tl.x <= upper.x && lower.x <= tu.x && tl.y <= upper.y && lower.y <= tu.y &&
			                tl.z <= upper.z && lower.z <= tu.z;
			cr_assert_eq(v.marks[t], overlaps ? 1 : 0,
			             "%s, box %d: triangle %d visited %d times, overlaps %d", when, k, t, v.marks[t],
			             overlaps);
			int region;
			vec3 q = plait_closest_point_on_triangle(c, shape->positions[tri[0]], shape->positions[tri[1]],
			                                         shape->positions[tri[2]], &region, NULL);
			nearest = fminf(nearest, v3_length(v3_sub(c, q)));
		}
		vec3 normal;
		float distance = fabsf(plait_mesh_shape_distance(shape, c, &normal));
		cr_assert(fabsf(distance - nearest) <= 1e-5f * nearest + 1e-7f,
		          "%s, point %d: %.9g from the hierarchy, %.9g from the nearest triangle", when, k, distance,
		          nearest);
		near += nearest < 0.05f;
	}
	cr_assert(near > 100, "%s: the points should come near the mesh (%d did)", when, near);
}

Test(mesh_shape, visits_and_distances_follow_a_deforming_mesh)
{
	bent_grid grid;
	plait_mesh_def def = make_bent_grid(&grid);
	plait_mesh_shape shape = {0};
	plait_error error = {0};
	cr_assert_eq(plait_mesh_shape_build(&shape, &heap, &def, &error), PLAIT_OK, "%s", error.message);
	expect_queries_match_the_triangles(&shape, "built");
	cr_assert_eq(plait_mesh_shape_make_deforming(&shape, &heap, &error), PLAIT_OK, "%s", error.message);
	/* The grid flattens and slides along y over the frame: the substep [0.5, 0.75]. */
	vec3 from[BENT_N * BENT_N], to[BENT_N * BENT_N];
	for (int v = 0; v < BENT_N * BENT_N; ++v) {
		from[v] = v3(grid.positions[v].x, grid.positions[v].y, grid.positions[v].z);
		to[v] = v3(from[v].x, from[v].y + 0.1f, 0.25f * from[v].z + 0.1f * from[v].y);
	}
	plait_mesh_shape_deform(&shape, from, to, 0.5f, 0.75f);
	expect_queries_match_the_triangles(&shape, "deformed");
	plait_mesh_shape_destroy(&shape, &heap);
}

/* The portable traversals: element_tree.c again, its functions renamed, without SSE2. */
#define plait_element_tree_build portable_tree_build
#define plait_element_tree_cut portable_tree_cut
#define plait_element_tree_destroy portable_tree_destroy
#define plait_element_tree_pairs portable_tree_pairs
#define plait_element_tree_pairs_between portable_tree_pairs_between
#define plait_element_tree_pairs_skipping portable_tree_pairs_skipping
#define plait_element_tree_piece_pairs portable_tree_piece_pairs
#define plait_element_tree_query portable_tree_query
#define plait_element_tree_refit portable_tree_refit
#define plait_element_tree_refit_above portable_tree_refit_above
#define plait_element_tree_refit_subtree portable_tree_refit_subtree
#define plait_element_tree_split portable_tree_split
#undef __SSE2__
#include "collision/element_tree.c"
