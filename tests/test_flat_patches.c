/* collision/flat_patches.h: the patches of a cloth that cannot touch themselves, whose pairs with
 * themselves the gather passes over. A patch taken as flat wrongly is a contact or a crossing
 * missed, so these check that what can meet itself is never flat (a fold, a spiral ramp whose
 * normals all agree, a patch that turns over between the ends of its paths, guards wide enough
 * to fold it), and that a cloth lying smooth is. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "collision/element_tree.h"
#include "collision/flat_patches.h"
#include "test_support.h"

static const plait_allocator heap = {NULL, NULL, NULL};

/* A grid of nx x ny vertices over the unit square, two triangles a quad, in the XZ plane, its
 * triangles facing +y; with its tree and patches. */
typedef struct patch_mesh {
	int nx, ny, vertex_count, triangle_count;
	vec3 *x;
	int (*triangles)[3];
	plait_element_tree tree;
	plait_flat_patches patches;
} patch_mesh;

static void build(patch_mesh *m)
{
	vec3 *centres = malloc(sizeof *centres * (size_t)m->triangle_count);
	for (int t = 0; t < m->triangle_count; ++t) {
		const int *v = m->triangles[t];
		centres[t] = v3_scale(v3_add(m->x[v[0]], v3_add(m->x[v[1]], m->x[v[2]])), 1.0f / 3.0f);
	}
	cr_assert(plait_element_tree_build(&m->tree, &heap, centres, m->triangle_count));
	cr_assert(plait_flat_patches_build(&m->patches, &heap, &m->tree, (const int(*)[3])m->triangles,
	                                   m->triangle_count, m->x));
	free(centres);
}

static patch_mesh grid(int nx, int ny)
{
	patch_mesh m = {nx, ny, nx * ny, 2 * (nx - 1) * (ny - 1), NULL, NULL, {0}, {0}};
	m.x = malloc(sizeof *m.x * (size_t)m.vertex_count);
	m.triangles = malloc(sizeof *m.triangles * (size_t)m.triangle_count);
	for (int j = 0; j < ny; ++j) {
		for (int i = 0; i < nx; ++i) {
			m.x[j * nx + i] = v3((float)i / (float)(nx - 1), 0.0f, (float)j / (float)(ny - 1));
		}
	}
	int t = 0;
	for (int j = 0; j + 1 < ny; ++j) {
		for (int i = 0; i + 1 < nx; ++i) {
			int a = j * nx + i, b = a + 1, c = a + nx + 1, d = a + nx;
			/* (a, d, c) faces +y: (d - a) x (c - a) = z x (x + z) = +y. */
			m.triangles[t][0] = a;
			m.triangles[t][1] = d;
			m.triangles[t++][2] = c;
			m.triangles[t][0] = a;
			m.triangles[t][1] = c;
			m.triangles[t++][2] = b;
		}
	}
	build(&m);
	return m;
}

static void mesh_free(patch_mesh *m)
{
	plait_flat_patches_destroy(&m->patches, &heap);
	plait_element_tree_destroy(&m->tree, &heap);
	free(m->x);
	free(m->triangles);
}

/* Keeps the triangles whose centre `keep` takes, and builds the tree and patches again. */
static void keep_triangles(patch_mesh *m, bool (*keep)(vec3 centre))
{
	int kept = 0;
	for (int t = 0; t < m->triangle_count; ++t) {
		const int *v = m->triangles[t];
		if (keep(v3_scale(v3_add(m->x[v[0]], v3_add(m->x[v[1]], m->x[v[2]])), 1.0f / 3.0f))) {
			memmove(m->triangles[kept++], v, sizeof m->triangles[0]);
		}
	}
	cr_assert_lt(kept, m->triangle_count);
	m->triangle_count = kept;
	plait_flat_patches_destroy(&m->patches, &heap);
	plait_element_tree_destroy(&m->tree, &heap);
	build(m);
}

/* Paths from `from` to `to` (per vertex), all guards `guard`; fits and says whether the root is
 * flat. */
static bool root_flat(patch_mesh *m, const vec3 *from, const vec3 *to, float guard)
{
	vec3 *motion = malloc(sizeof *motion * (size_t)m->vertex_count);
	float *guards = malloc(sizeof *guards * (size_t)m->vertex_count);
	for (int i = 0; i < m->vertex_count; ++i) {
		motion[i] = v3_sub(to[i], from[i]);
		guards[i] = guard;
	}
	plait_patch_paths paths = {to, motion, guards, 1.0f, 0.0f, NULL};
	plait_flat_patches_fit(&m->patches, &m->tree, &paths);
	bool flat = plait_flat_patches_flat(&m->patches, 0, &paths, NULL);
	free(motion);
	free(guards);
	return flat;
}

Test(flat_patches, the_fast_arctangent_keeps_within_its_bound)
{
	float worst = 0.0f;
	for (int k = 0; k <= 20000; ++k) {
		float angle = 3.14159265f * (float)k / 20000.0f;
		float y = fabsf(sinf(angle)), x = cosf(angle);
		for (float scale = 1e-4f; scale < 1e5f; scale *= 31.0f) {
			float error =
			    fabsf(plait_flat_patches_atan2(scale * y, scale * x) - atan2f(scale * y, scale * x));
			worst = fmaxf(worst, error);
		}
	}
	cr_expect_lt(worst, 2e-5f, "arctangent off by %g radians", (double)worst);
	cr_expect_eq(plait_flat_patches_atan2(0.0f, 0.0f), 0.0f);
}

static vec3 turned(vec3 axis, vec3 across, float angle)
{
	return v3_add(v3_scale(axis, cosf(angle)), v3_scale(across, sinf(angle)));
}

static vec3 random_unit(uint32_t *state)
{
	for (;;) {
		vec3 v = v3(test_uniform(state, -1, 1), test_uniform(state, -1, 1), test_uniform(state, -1, 1));
		float length = v3_length(v);
		if (length > 0.1f && length < 1.0f) {
			return v3_scale(v, 1.0f / length);
		}
	}
}

/* Every direction of either cone is within the merged one (a merged cone that misses some is a
 * normal let past a right angle). */
Test(flat_patches, a_merged_cone_holds_both_cones)
{
	uint32_t state = 7;
	int merged = 0;
	for (int trial = 0; trial < 2000; ++trial) {
		plait_cone c[2];
		for (int k = 0; k < 2; ++k) {
			c[k] = (plait_cone){random_unit(&state), test_uniform(&state, 0.0f, 0.8f)};
		}
		plait_cone m = plait_cone_merge(c[0], c[1]);
		if (m.angle >= 1.5707963f) {
			continue;
		}
		merged += 1;
		cr_assert(fabsf(v3_length(m.axis) - 1.0f) < 1e-5f);
		for (int k = 0; k < 2; ++k) {
			for (int s = 0; s < 24; ++s) {
				vec3 across = v3_cross(c[k].axis, random_unit(&state));
				across = v3_scale(across, 1.0f / v3_length(across));
				vec3 edge = turned(c[k].axis, across, c[k].angle);
				float angle = atan2f(v3_length(v3_cross(edge, m.axis)), v3_dot(edge, m.axis));
				cr_assert_leq(angle, m.angle + 1e-5f,
				              "trial %d: a direction %g from the merged axis, angle %g", trial, (double)angle,
				              (double)m.angle);
			}
		}
	}
	cr_expect_gt(merged, 500);
}

/* A grid's nodes from 16 triangles up are disks, each with its contour, the notches filled. */
Test(flat_patches, a_grids_patches_are_disks)
{
	patch_mesh m = grid(40, 40);
	int large = 0, disks = 0;
	for (int n = 0; n < m.tree.node_count; ++n) {
		int first = m.patches.contour_first[n], count = m.patches.contour_first[n + 1] - first;
		/* A node's triangle count: its leaves' under it. */
		int triangles = 0, stack[64], top = 0;
		stack[top++] = n;
		while (top > 0) {
			const plait_tree_node *node = &m.tree.nodes[stack[--top]];
			if (node->count > 0) {
				triangles += node->count;
			} else {
				stack[top++] = node->first;
				stack[top++] = node->first + 1;
			}
		}
		large += triangles >= 16;
		disks += count > 0;
	}
	/* Now and then a median split leaves a triangle touching the rest at a corner only (no disk). */
	cr_expect_geq(disks, large - large / 50, "%d of %d nodes have contours", disks, large);
	/* The root's contour is the grid's border, 4 (n - 1) vertices. */
	cr_expect_eq(m.patches.contour_first[1] - m.patches.contour_first[0], 4 * 39);
	mesh_free(&m);
}

Test(flat_patches, a_sheet_moving_as_a_whole_is_flat)
{
	patch_mesh m = grid(32, 32);
	vec3 *to = malloc(sizeof *to * (size_t)m.vertex_count);
	for (int i = 0; i < m.vertex_count; ++i) {
		/* Falling, drifting and tilting a little (a tenth of a radian). */
		vec3 x = m.x[i];
		to[i] = v3(x.x + 0.05f, x.y - 0.2f + 0.1f * x.x, x.z - 0.03f);
	}
	cr_expect(root_flat(&m, m.x, to, 1e-3f));
	/* Rippled gently, as cloth lying on a body. */
	for (int i = 0; i < m.vertex_count; ++i) {
		to[i].y += 0.02f * sinf(6.0f * m.x[i].x) * cosf(5.0f * m.x[i].z);
	}
	cr_expect(root_flat(&m, m.x, to, 1e-3f));
	free(to);
	mesh_free(&m);
}

/* The sheet's far half folded back over the near one, a centimetre above it. */
Test(flat_patches, a_sheet_folded_over_itself_is_not_flat_but_its_halves_are)
{
	patch_mesh m = grid(32, 32);
	vec3 *folded = malloc(sizeof *folded * (size_t)m.vertex_count);
	for (int i = 0; i < m.vertex_count; ++i) {
		vec3 x = m.x[i];
		float beyond = x.x - 0.5f;
		/* Round a half circle of radius 5 mm at the fold. */
		if (beyond <= 0.0f) {
			folded[i] = x;
		} else if (beyond < 0.005f * 3.14159f) {
			float a = beyond / 0.005f;
			folded[i] = v3(0.5f + 0.005f * sinf(a), 0.005f - 0.005f * cosf(a), x.z);
		} else {
			folded[i] = v3(0.5f - (beyond - 0.005f * 3.14159f), 0.01f, x.z);
		}
	}
	cr_expect(!root_flat(&m, folded, folded, 1e-4f));
	int flat = 0;
	vec3 *motion = calloc((size_t)m.vertex_count, sizeof *motion);
	plait_patch_paths paths = {folded, motion, NULL, 1.0f, 0.0f, NULL};
	plait_flat_patches_fit(&m.patches, &m.tree, &paths);
	for (int n = 0; n < m.tree.node_count; ++n) {
		flat += plait_flat_patches_flat(&m.patches, n, &paths, NULL);
	}
	cr_expect_gt(flat, 20, "only %d nodes flat in the folded sheet's halves", flat);
	free(motion);
	free(folded);
	mesh_free(&m);
}

/* A long strip wound one and a half times round the y axis as a gentle ramp: every normal within
 * a few degrees of +y, yet seen from above it lies over itself. The cone alone would pass it.
 * Turned to several headings, so that the contour's count of turns alone (which may come out
 * one) does not decide it. */
Test(flat_patches, a_spiral_ramp_whose_normals_agree_is_not_flat)
{
	patch_mesh m = grid(240, 4);
	vec3 *ramp = malloc(sizeof *ramp * (size_t)m.vertex_count);
	vec3 *still = calloc((size_t)m.vertex_count, sizeof *still);
	for (int heading = 0; heading < 12; ++heading) {
		for (int i = 0; i < m.vertex_count; ++i) {
			float along = m.x[i].x, across = m.x[i].z;
			float turn = 3.0f * 3.14159265f * along + 0.5236f * (float)heading, radius = 0.2f + 0.1f * across;
			/* Along +x turning about -y keeps the triangles facing up. */
			ramp[i] = v3(radius * cosf(turn), 0.08f * along, -radius * sinf(turn));
		}
		plait_patch_paths paths = {ramp, still, NULL, 1.0f, 0.0f, NULL};
		plait_flat_patches_fit(&m.patches, &m.tree, &paths);
		cr_assert_lt(m.patches.patch_cone[0].angle, 0.3f, "the ramp's normals span %g radians",
		             (double)m.patches.patch_cone[0].angle);
		cr_expect(!plait_flat_patches_flat(&m.patches, 0, &paths, NULL), "heading %d", heading);
	}
	free(still);
	free(ramp);
	mesh_free(&m);
}

/* A fan of 32 triangles round one vertex that goes round it twice, climbing the first turn and
 * coming down the second (so it passes through itself): every triangle faces up and its
 * contour turns forward all the way round, twice. Only the count of turns tells. */
Test(flat_patches, a_fan_going_twice_round_its_centre_is_not_flat)
{
	enum { RING = 32 };
	patch_mesh m = {RING + 1, 1, RING + 1, RING, NULL, NULL, {0}, {0}};
	m.x = malloc(sizeof *m.x * (size_t)m.vertex_count);
	m.triangles = malloc(sizeof *m.triangles * (size_t)m.triangle_count);
	m.x[RING] = v3(0.0f, 0.0f, 0.0f);
	for (int k = 0; k < RING; ++k) {
		float angle = 4.0f * 3.14159265f * (float)k / (float)RING;
		float height = 0.01f * (float)(k < RING / 2 ? k : RING - k);
		m.x[k] = v3(cosf(angle), height, -sinf(angle));
		m.triangles[k][0] = RING;
		m.triangles[k][1] = k;
		m.triangles[k][2] = (k + 1) % RING;
	}
	build(&m);
	vec3 *still = calloc((size_t)m.vertex_count, sizeof *still);
	plait_patch_paths paths = {m.x, still, NULL, 1.0f, 0.0f, NULL};
	plait_flat_patches_fit(&m.patches, &m.tree, &paths);
	cr_assert_gt(m.patches.contour_first[1], m.patches.contour_first[0], "the fan is a disk");
	cr_assert_lt(m.patches.patch_cone[0].angle, 0.3f);
	cr_expect(!plait_flat_patches_flat(&m.patches, 0, &paths, NULL));
	free(still);
	mesh_free(&m);
}

/* Turned in its own plane along straight paths: by 20 degrees it stays a sheet all along; by
 * 180 degrees every triangle shrinks to a point halfway, though both ends are flat sheets. */
Test(flat_patches, a_patch_that_turns_over_between_its_ends_is_not_flat)
{
	patch_mesh m = grid(24, 24);
	vec3 *to = malloc(sizeof *to * (size_t)m.vertex_count);
	float angles[2] = {0.35f, 3.14159265f};
	for (int k = 0; k < 2; ++k) {
		float c = cosf(angles[k]), s = sinf(angles[k]);
		for (int i = 0; i < m.vertex_count; ++i) {
			float x = m.x[i].x - 0.5f, z = m.x[i].z - 0.5f;
			to[i] = v3(0.5f + c * x - s * z, 0.0f, 0.5f + s * x + c * z);
		}
		cr_expect_eq(root_flat(&m, m.x, to, 1e-4f), k == 0, "turned by %g radians", (double)angles[k]);
	}
	free(to);
	mesh_free(&m);
}

/* Guards a third of an edge wide could fold neighbouring triangles onto each other: not flat. */
Test(flat_patches, guards_wide_enough_to_fold_a_patch_keep_it_from_flat)
{
	patch_mesh m = grid(16, 16);
	float edge = 1.0f / 15.0f;
	cr_expect(root_flat(&m, m.x, m.x, 0.02f * edge));
	cr_expect(!root_flat(&m, m.x, m.x, 0.34f * edge));
	mesh_free(&m);
}

static bool outside_the_hole(vec3 c)
{
	return !(fabsf(c.x - 0.5f) < 0.1f && fabsf(c.z - 0.5f) < 0.1f);
}

/* A sheet with a hole in the middle is a disk no longer: never flat. */
Test(flat_patches, patches_that_are_no_disk_are_never_flat)
{
	patch_mesh m = grid(20, 20);
	keep_triangles(&m, outside_the_hole);
	cr_expect_eq(m.patches.contour_first[1], m.patches.contour_first[0], "the holed sheet has a contour");
	cr_expect(!root_flat(&m, m.x, m.x, 0.0f));
	mesh_free(&m);
}

static bool in_the_l(vec3 c)
{
	return !(c.x > 0.25f && c.z > 0.25f);
}

/* A flat L with thin arms (a sheet without its far 3/4 x 3/4): its border is star-shaped only
 * round points near the inner corner, which the contour's mean is not; the centre chosen in the
 * rest shape is. */
Test(flat_patches, a_flat_l_is_flat_round_the_centre_chosen_at_rest)
{
	patch_mesh m = grid(33, 33);
	keep_triangles(&m, in_the_l);
	cr_assert_geq(m.patches.centre[0].triangle, 0, "no centre for the L");
	cr_expect(root_flat(&m, m.x, m.x, 1e-4f));
	mesh_free(&m);
}

/* Workers fit the cones and refit the boxes subtree by subtree under a cut of the tree, then the
 * nodes above it: the same cones and boxes, to the bit, as fitting the whole tree at once, at any
 * depth of cut (the solver's bits must not depend on the number of workers). */
Test(flat_patches, fitting_by_subtrees_gives_the_whole_trees_cones_and_boxes)
{
	patch_mesh m = grid(33, 29);
	vec3 *motion = malloc(sizeof *motion * (size_t)m.vertex_count);
	for (int i = 0; i < m.vertex_count; ++i) {
		vec3 x = m.x[i];
		m.x[i].y = 0.05f * sinf(9.0f * x.x) * cosf(7.0f * x.z);
		motion[i] = v3(0.002f * sinf(31.0f * x.z), 0.003f * cosf(17.0f * x.x), 0.001f);
	}
	plait_patch_paths paths = {m.x, motion, NULL, 1.0f, 1.0f, NULL};
	int nodes = m.tree.node_count;
	vec3 *lower = malloc(sizeof *lower * (size_t)m.triangle_count);
	vec3 *upper = malloc(sizeof *upper * (size_t)m.triangle_count);
	for (int t = 0; t < m.triangle_count; ++t) {
		const int *v = m.triangles[t];
		lower[t] = v3_min(m.x[v[0]], v3_min(m.x[v[1]], m.x[v[2]]));
		upper[t] = v3_max(m.x[v[0]], v3_max(m.x[v[1]], m.x[v[2]]));
	}
	plait_flat_patches_fit(&m.patches, &m.tree, &paths);
	plait_element_tree_refit(&m.tree, lower, upper);
	plait_cone *cones = malloc(sizeof *cones * (size_t)nodes);
	plait_tree_node *whole = malloc(sizeof *whole * (size_t)nodes);
	memcpy(cones, m.patches.patch_cone, sizeof *cones * (size_t)nodes);
	memcpy(whole, m.tree.nodes, sizeof *whole * (size_t)nodes);
	int flat = 0;
	for (int n = 0; n < nodes; ++n) {
		flat += cones[n].angle < 1.0f;
	}
	cr_assert_gt(flat, 10, "the crumpled grid has only %d nodes with narrow cones", flat);
	for (int levels = 0; levels <= 6; ++levels) {
		memset(m.patches.patch_cone, 0, sizeof *cones * (size_t)nodes);
		for (int n = 0; n < nodes; ++n) {
			m.tree.nodes[n].lower = m.tree.nodes[n].upper = v3(0.0f, 0.0f, 0.0f);
		}
		int roots[64];
		int count = plait_element_tree_cut(&m.tree, levels, roots);
		cr_assert(count >= 1 && count <= 1 << levels);
		for (int k = count - 1; k >= 0; --k) { /* any order */
			plait_flat_patches_fit_subtree(&m.patches, &m.tree, &paths, roots[k]);
			plait_element_tree_refit_subtree(&m.tree, roots[k], lower, upper);
		}
		plait_flat_patches_fit_above(&m.patches, &m.tree, levels);
		plait_element_tree_refit_above(&m.tree, levels, lower, upper);
		cr_expect(memcmp(cones, m.patches.patch_cone, sizeof *cones * (size_t)nodes) == 0,
		          "cones differ with a cut %d levels down", levels);
		cr_expect(memcmp(whole, m.tree.nodes, sizeof *whole * (size_t)nodes) == 0,
		          "boxes differ with a cut %d levels down", levels);
	}
	free(cones);
	free(whole);
	free(lower);
	free(upper);
	free(motion);
	mesh_free(&m);
}

/* A leaf's cone on paths without guards, from the definition, one triangle at a time in plain
 * C: each normal's Bernstein coefficients over the paths, their sum's direction as the axis, and
 * the widest coefficient's angle, held off by half the squared edges (flat_patches.c). */
static plait_cone reference_leaf_cone(const plait_patch_paths *paths, const int (*triangles)[3],
                                      const int *which, int count)
{
	const plait_cone none = {{0.0f, 0.0f, 1.0f}, 4.0f};
	vec3 n[4][3];
	float rho[4];
	vec3 sum = {0.0f, 0.0f, 0.0f};
	for (int k = 0; k < count; ++k) {
		vec3 a[3], b[3];
		for (int m = 0; m < 3; ++m) {
			int v = triangles[which[k]][m];
			a[m] = v3_mul_add(paths->at[v], -paths->back, paths->motion[v]);
			b[m] = v3_mul_add(paths->at[v], paths->on, paths->motion[v]);
		}
		vec3 e1a = v3_sub(a[1], a[0]), e2a = v3_sub(a[2], a[0]), e1b = v3_sub(b[1], b[0]),
		     e2b = v3_sub(b[2], b[0]);
		n[k][0] = v3_cross(e1a, e2a);
		n[k][1] = v3_scale(v3_add(v3_cross(e1a, e2b), v3_cross(e1b, e2a)), 0.5f);
		n[k][2] = v3_cross(e1b, e2b);
		rho[k] = 0.5e-6f *
		         (fmaxf(v3_length_sq(e1a), v3_length_sq(e1b)) + fmaxf(v3_length_sq(e2a), v3_length_sq(e2b)));
		sum = v3_add(sum, v3_add(n[k][0], v3_add(n[k][1], n[k][2])));
	}
	float length = v3_length(sum);
	if (!(length > 0.0f)) {
		return none;
	}
	vec3 axis = v3_scale(sum, 1.0f / length);
	float widest_sq = 0.0f;
	for (int k = 0; k < count; ++k) {
		for (int m = 0; m < 3; ++m) {
			float along = v3_dot(n[k][m], axis);
			if (!(along > 0.0f)) {
				return none;
			}
			widest_sq = fmaxf(widest_sq, v3_length_sq(v3_cross(n[k][m], axis)) / (along * along));
		}
	}
	float widest = sqrtf(widest_sq), tangent = 0.0f;
	for (int k = 0; k < count; ++k) {
		float least = fminf(v3_dot(n[k][0], axis), fminf(v3_dot(n[k][1], axis), v3_dot(n[k][2], axis)));
		if (!(rho[k] < least)) {
			return none;
		}
		tangent = fmaxf(tangent, (least * widest + rho[k]) / (least - rho[k]));
	}
	return (plait_cone){axis, plait_flat_patches_atan2(tangent, 1.0f) + 1e-4f};
}

/* Leaf cones on paths without guards (the gather's) take a four-lane path. Each must be the
 * definition's to the bit, for leaves of two to four triangles (a 17 x 17 grid's leaves hold
 * four, a 21 x 17 grid's two or three). */
Test(flat_patches, leaf_cones_without_guards_are_the_definitions)
{
	const int sizes[2][2] = {{17, 17}, {21, 17}};
	for (int g = 0; g < 2; ++g) {
		patch_mesh m = grid(sizes[g][0], sizes[g][1]);
		vec3 *motion = malloc(sizeof *motion * (size_t)m.vertex_count);
		for (int i = 0; i < m.vertex_count; ++i) {
			vec3 x = m.x[i];
			m.x[i].y = 0.08f * sinf(11.0f * x.x) * cosf(5.0f * x.z);
			motion[i] = v3(0.004f * sinf(23.0f * x.z), 0.006f * cosf(13.0f * x.x), -0.002f);
		}
		plait_patch_paths paths = {m.x, motion, NULL, 1.0f, 2.0f, NULL};
		plait_flat_patches_fit(&m.patches, &m.tree, &paths);
		int full = 0;
		for (int node = 0; node < m.tree.node_count; ++node) {
			const plait_tree_node *leaf = &m.tree.nodes[node];
			if (leaf->count == 0) {
				continue;
			}
			full += leaf->count == 4;
			plait_cone want = reference_leaf_cone(&paths, (const int(*)[3])m.patches.triangles,
			                                      m.tree.order + leaf->first, leaf->count);
			plait_cone got = m.patches.patch_cone[node];
			cr_assert(want.angle < 1.0f, "leaf %d: the reference cone is %g", node, (double)want.angle);
			cr_expect(memcmp(&want, &got, sizeof want) == 0,
			          "leaf %d of %d triangles: cone (%g %g %g) %.9g, the definition's (%g %g %g) %.9g", node,
			          leaf->count, (double)got.axis.x, (double)got.axis.y, (double)got.axis.z,
			          (double)got.angle, (double)want.axis.x, (double)want.axis.y, (double)want.axis.z,
			          (double)want.angle);
		}
		cr_assert(g == 1 || full > 50, "the 17 x 17 grid should have leaves of four (%d)", full);
		free(motion);
		mesh_free(&m);
	}
}

/* Two trees over one cloth (an object's own and its cross patches, dynamics/mesh_contact_cross.c)
 * fit their cones from triangle normals found once (plait_flat_patches_normals): the same cones
 * to the bit as finding them in the fit, on paths without guards (the gather's, four lanes) and
 * with them, and for a tree with other leaves than the one the normals were found with. */
Test(flat_patches, cones_from_shared_normals_are_the_fits_own)
{
	patch_mesh m = grid(23, 19);
	vec3 *motion = malloc(sizeof *motion * (size_t)m.vertex_count);
	float *guards = malloc(sizeof *guards * (size_t)m.vertex_count);
	for (int i = 0; i < m.vertex_count; ++i) {
		vec3 x = m.x[i];
		m.x[i].y = 0.06f * sinf(10.0f * x.x) * cosf(6.0f * x.z);
		motion[i] = v3(0.003f * sinf(19.0f * x.z), 0.005f * cosf(11.0f * x.x), 0.001f);
		guards[i] = 0.0004f * (float)(i % 5);
	}
	/* A second tree over the same triangles, split along the diagonals. */
	vec3 *centres = malloc(sizeof *centres * (size_t)m.triangle_count);
	for (int t = 0; t < m.triangle_count; ++t) {
		const int *v = m.triangles[t];
		vec3 c = v3_scale(v3_add(m.x[v[0]], v3_add(m.x[v[1]], m.x[v[2]])), 1.0f / 3.0f);
		centres[t] = v3(c.x - c.z, c.y, c.x + c.z);
	}
	plait_element_tree turned = {0};
	plait_flat_patches turned_patches = {0};
	cr_assert(plait_element_tree_build(&turned, &heap, centres, m.triangle_count));
	cr_assert(plait_flat_patches_build(&turned_patches, &heap, &turned, (const int(*)[3])m.triangles,
	                                   m.triangle_count, m.x));
	plait_triangle_normals *normals = malloc(sizeof *normals * (size_t)m.triangle_count);
	for (int guarded = 0; guarded < 2; ++guarded) {
		plait_patch_paths paths = {m.x, motion, guarded ? guards : NULL, 1.0f, 1.0f, NULL};
		/* In two ranges, the first not a multiple of four long (lanes, then the rest). */
		plait_flat_patches_normals(&m.patches, &paths, 0, 37, normals);
		plait_flat_patches_normals(&m.patches, &paths, 37, m.triangle_count, normals);
		plait_patch_paths shared = paths;
		shared.normals = normals;
		const plait_flat_patches *fps[2] = {&m.patches, &turned_patches};
		const plait_element_tree *trees[2] = {&m.tree, &turned};
		for (int k = 0; k < 2; ++k) {
			plait_flat_patches *fp = (plait_flat_patches *)fps[k];
			size_t size = sizeof(plait_cone) * (size_t)fp->node_count;
			plait_flat_patches_fit(fp, trees[k], &paths);
			plait_cone *own = malloc(size);
			memcpy(own, fp->patch_cone, size);
			int narrow = 0;
			for (int n = 0; n < fp->node_count; ++n) {
				narrow += own[n].angle < 1.0f;
			}
			cr_assert_gt(narrow, 10, "tree %d: only %d narrow cones", k, narrow);
			memset(fp->patch_cone, 0, size);
			plait_flat_patches_fit(fp, trees[k], &shared);
			cr_expect(memcmp(own, fp->patch_cone, size) == 0,
			          "tree %d, guards %d: cones differ from shared normals", k, guarded);
			free(own);
		}
	}
	free(normals);
	free(centres);
	free(guards);
	free(motion);
	plait_flat_patches_destroy(&turned_patches, &heap);
	plait_element_tree_destroy(&turned, &heap);
	mesh_free(&m);
}

/* The failsafe's check of a patch the gather passed over (plait_flat_patches_keeps_flat): a
 * patch lifted whole keeps flat; one with a corner of any of its triangles pulled across the
 * opposite edge (which turns over that triangle, among others round the corner) does not,
 * wherever that triangle lies in the patch's list (the check takes four at a time). */
Test(flat_patches, a_patch_keeps_flat_until_any_triangle_turns_over)
{
	patch_mesh m = grid(10, 9);
	vec3 *still = calloc((size_t)m.vertex_count, sizeof *still);
	vec3 *motion = malloc(sizeof *motion * (size_t)m.vertex_count);
	vec3 *lift = malloc(sizeof *lift * (size_t)m.vertex_count);
	plait_patch_paths rest = {m.x, still, NULL, 1.0f, 0.0f, NULL};
	plait_flat_patches_fit(&m.patches, &m.tree, &rest);
	vec3 axis;
	cr_assert(plait_flat_patches_flat(&m.patches, 0, &rest, &axis));
	for (int i = 0; i < m.vertex_count; ++i) {
		lift[i] = v3(0.001f, 0.003f, -0.002f);
	}
	plait_patch_paths lifted = {m.x, lift, NULL, 1.0f, 0.0f, NULL};
	int checked = 0;
	for (int node = 0; node < m.tree.node_count; ++node) {
		int begin = m.patches.node_begin[node], end = m.patches.node_end[node];
		if (end - begin < 16 || !plait_flat_patches_flat(&m.patches, node, &rest, NULL)) {
			continue; /* never flat (too small, or no star round its centre) */
		}
		cr_expect(plait_flat_patches_keeps_flat(&m.patches, node, axis, &lifted), "node %d", node);
		/* Each of the node's triangles in turn: one corner pulled across its opposite edge. */
		for (int k = begin; k < end; ++k) {
			const int *v = m.patches.triangles[m.patches.order[k]];
			vec3 across = v3_sub(v3_scale(v3_add(m.x[v[1]], m.x[v[2]]), 0.5f), m.x[v[0]]);
			for (int i = 0; i < m.vertex_count; ++i) {
				motion[i] = v3(0.0f, 0.0f, 0.0f);
			}
			motion[v[0]] = v3_scale(across, -2.0f); /* the path starts beyond the edge */
			plait_patch_paths turned = {m.x, motion, NULL, 1.0f, 0.0f, NULL};
			cr_expect(!plait_flat_patches_keeps_flat(&m.patches, node, axis, &turned),
			          "node %d keeps flat with triangle %d of [%d, %d) turned over", node, k, begin, end);
			checked += 1;
		}
	}
	cr_assert_gt(checked, 100);
	free(lift);
	free(motion);
	free(still);
	mesh_free(&m);
}
