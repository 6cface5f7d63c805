/* collision/mesh_shape.h: the signed distance to a closed mesh near its edges. Where the nearest
 * point is an edge shared by two triangles, their distances to it agree only to rounding, and
 * the sign must come from the triangle the point is in front of. The solid here is
 * examples/tablecloth.json's round table (a 48-sided prism, 0.45 m by 0.75 m), whose signed
 * distance is known exactly: in its slab, the 2D distance to the polygon. */
#include <criterion/criterion.h>

#include <math.h>

#include "collision/mesh_shape.h"

static const plait_allocator heap = {NULL, NULL, NULL};

enum { SIDES = 48 };
static const float table_radius = 0.45f, table_height = 0.75f;

/* The prism: a fan on top and one below, quads round the side, normals outward. */
static void build_table(plait_mesh_shape *shape, plait_vec3 *corners)
{
	static plait_vec3 positions[2 * SIDES + 2];
	static int sizes[3 * SIDES], indices[10 * SIDES];
	for (int k = 0; k < SIDES; ++k) {
		float a = 2.0f * 3.14159265f * (float)k / (float)SIDES;
		positions[k] = (plait_vec3){table_radius * cosf(a), table_height, table_radius * sinf(a)};
		positions[SIDES + k] = (plait_vec3){table_radius * cosf(a), 0.0f, table_radius * sinf(a)};
		corners[k] = positions[k];
	}
	positions[2 * SIDES] = (plait_vec3){0.0f, table_height, 0.0f};
	positions[2 * SIDES + 1] = (plait_vec3){0.0f, 0.0f, 0.0f};
	int f = 0, n = 0;
	for (int k = 0; k < SIDES; ++k) {
		int next = (k + 1) % SIDES;
		int faces[3][4] = {{2 * SIDES, next, k, -1},
		                   {2 * SIDES + 1, SIDES + k, SIDES + next, -1},
		                   {k, next, SIDES + next, SIDES + k}};
		for (int m = 0; m < 3; ++m) {
			sizes[f] = faces[m][3] < 0 ? 3 : 4;
			for (int c = 0; c < sizes[f]; ++c) {
				indices[n++] = faces[m][c];
			}
			++f;
		}
	}
	plait_mesh_def def = {positions, 2 * SIDES + 2, sizes, f, indices};
	plait_error error;
	cr_assert_eq(plait_mesh_shape_build(shape, &heap, &def, &error), PLAIT_OK, "%s", error.message);
	cr_assert(shape->closed);
}

/* Exact signed distance (in double) from p to the prism whose top outline is corners. */
static double prism_distance(const plait_vec3 *corners, plait_vec3 p)
{
	/* Outside the polygon in 2D: the distance to its nearest edge; inside: minus the nearest. */
	double outline = INFINITY;
	bool inside = true;
	for (int k = 0; k < SIDES; ++k) {
		plait_vec3 a = corners[k], b = corners[(k + 1) % SIDES];
		double ex = (double)b.x - a.x, ez = (double)b.z - a.z, px = (double)p.x - a.x, pz = (double)p.z - a.z;
		double t = (px * ex + pz * ez) / (ex * ex + ez * ez);
		t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
		outline = fmin(outline, hypot(px - t * ex, pz - t * ez));
		inside = inside && ex * pz - ez * px >= 0.0; /* the interior is left of each edge, from x to z */
	}
	double below = (double)p.y - table_height, above = -(double)p.y; /* > 0 outside the slab */
	if (inside) {
		double slab = fmax(below, above);
		return slab > 0.0 ? slab : fmax(slab, -outline);
	}
	double slab = fmax(fmax(below, above), 0.0);
	return sqrt(outline * outline + slab * slab);
}

static float next_unit(unsigned *state)
{
	*state = *state * 1664525u + 1013904223u;
	return (float)(*state >> 8) / 16777216.0f;
}

/* Beside the rim, a few micrometres under the top's plane: outside, by about its distance from
 * the rim. The top's distance to the rim and the side's to its face tie there but for rounding;
 * before the tie allowed for it, 4,877 of these 100,000 points were taken for inside (one was a
 * tablecloth vertex 9.7 mm beside the rim, pushed up and counted inside by the checker). */
Test(mesh_distance, a_point_beside_a_rim_just_under_the_top_is_outside)
{
	plait_mesh_shape shape;
	plait_vec3 corners[SIDES];
	build_table(&shape, corners);
	unsigned state = 12345u;
	int wrong = 0;
	double worst = 0.0;
	for (int k = 0; k < 100000; ++k) {
		float a = 2.0f * 3.14159265f * next_unit(&state);
		float out = 0.001f + 0.02f * next_unit(&state), under = 5e-6f * next_unit(&state);
		plait_vec3 p = {(table_radius + out) * cosf(a), table_height - under, (table_radius + out) * sinf(a)};
		vec3 normal;
		float distance = shape.outward * plait_mesh_shape_distance(&shape, p, &normal);
		double exact = prism_distance(corners, p);
		wrong += !(distance > 0.0f);
		worst = fmax(worst, fabs(fabs((double)distance) - exact));
	}
	cr_expect_eq(wrong, 0, "%d of 100000 points beside the rim were taken for inside", wrong);
	cr_expect_lt(worst, 1e-6, "distances off by up to %g m", worst);
	plait_mesh_shape_destroy(&shape, &heap);
}

/* Anywhere within 2 cm of the surface, rims and corners included, at and near the planes of the
 * faces: the sign is the exact one wherever the point is more than 20 um from the surface, and
 * the distance is the exact one to within a micrometre. */
Test(mesh_distance, signs_near_a_closed_prism_agree_with_the_exact_distance)
{
	plait_mesh_shape shape;
	plait_vec3 corners[SIDES];
	build_table(&shape, corners);
	unsigned state = 777u;
	int wrong = 0, tested = 0;
	double worst = 0.0;
	for (int k = 0; k < 100000; ++k) {
		float a = 2.0f * 3.14159265f * next_unit(&state);
		float r = table_radius + 0.04f * (next_unit(&state) - 0.5f);
		/* Heights near the top and bottom planes, some exactly on them, the rest anywhere. */
		float pick = next_unit(&state), jitter = 0.04f * (next_unit(&state) - 0.5f);
		float y = pick < 0.3f   ? table_height + jitter * (pick < 0.1f ? 1e-3f : 1.0f)
		          : pick < 0.6f ? jitter * (pick < 0.4f ? 1e-3f : 1.0f)
		                        : table_height * next_unit(&state);
		if (pick > 0.9f) {
			r = table_radius * next_unit(&state); /* over the top and under the bottom too */
		}
		plait_vec3 p = {r * cosf(a), y, r * sinf(a)};
		vec3 normal;
		float distance = shape.outward * plait_mesh_shape_distance(&shape, p, &normal);
		double exact = prism_distance(corners, p);
		worst = fmax(worst, fabs(fabs((double)distance) - fabs(exact)));
		if (fabs(exact) > 2e-5) {
			tested += 1;
			wrong += (distance > 0.0f) != (exact > 0.0);
		}
	}
	cr_expect_eq(wrong, 0, "%d of %d points got the wrong sign", wrong, tested);
	cr_expect_lt(worst, 1e-6, "distances off by up to %g m", worst);
	cr_expect_gt(tested, 90000);
	plait_mesh_shape_destroy(&shape, &heap);
}
