/* The cheap distance bounds of collision/closest.h, which let the mesh contacts skip pairs
 * without their closest points: each must never exceed the exact distance (a pair wrongly
 * skipped is a contact or a crossing missed), and must be exact where the primitives lie apart
 * along its axis (else it skips nothing). */
#include <criterion/criterion.h>

#include "collision/closest.h"
#include "collision/mesh_shape.h"
#include "test_support.h"

static vec3 random_point(uint32_t *state, float size)
{
	return v3(test_uniform(state, -size, size), test_uniform(state, -size, size),
	          test_uniform(state, -size, size));
}

static float segments_distance(vec3 p, vec3 q, vec3 r, vec3 s)
{
	float a, b;
	return sqrtf(plait_closest_segments(p, q, r, s, &a, &b));
}

static float point_triangle_distance(vec3 x, const vec3 *t)
{
	int region;
	return v3_length(v3_sub(x, plait_closest_point_on_triangle(x, t[0], t[1], t[2], &region, NULL)));
}

/* Rounding of the exact distances and the bounds, relative to the coordinates. */
static float rounding(float size)
{
	return 1e-5f * size;
}

Test(closest, segment_gap_never_exceeds_the_distance)
{
	uint32_t state = 12345;
	static const float sizes[3] = {1e-2f, 1.0f, 100.0f};
	for (int k = 0; k < 30000; ++k) {
		float size = sizes[k % 3];
		vec3 p = random_point(&state, size), q = random_point(&state, size);
		vec3 r = random_point(&state, size), s = random_point(&state, size);
		if (k % 7 == 0) {
			q = p; /* a point against a segment */
		}
		if (k % 11 == 0) {
			/* Short edges near each other: neighbours in a fine cloth. */
			q = v3_add(p, v3_scale(random_point(&state, size), 0.05f));
			r = v3_add(p, v3_scale(random_point(&state, size), 0.1f));
			s = v3_add(r, v3_scale(random_point(&state, size), 0.05f));
		}
		float gap = plait_segments_gap(p, q, r, s), exact = segments_distance(p, q, r, s);
		cr_assert(gap <= exact + rounding(size), "case %d: gap %g > distance %g", k, (double)gap,
		          (double)exact);
	}
}

Test(closest, segment_gap_is_exact_apart_along_the_midpoints)
{
	/* Parallel edges side by side, and collinear ones end to end: the gap is the distance. */
	float gap = plait_segments_gap(v3(0, 0, 0), v3(1, 0, 0), v3(0, 0.25f, 0), v3(1, 0.25f, 0));
	cr_assert_float_eq(gap, 0.25f, 1e-6f);
	gap = plait_segments_gap(v3(0, 0, 0), v3(1, 0, 0), v3(1.5f, 0, 0), v3(2.5f, 0, 0));
	cr_assert_float_eq(gap, 0.5f, 1e-6f);
	gap = plait_segments_gap(v3(2, 3, 4), v3(2, 3, 4), v3(2, 3, 1), v3(2, 3, 1));
	cr_assert_float_eq(gap, 3.0f, 1e-6f);
}

Test(closest, point_triangle_gap_never_exceeds_the_distance)
{
	uint32_t state = 777;
	static const float sizes[3] = {1e-2f, 1.0f, 100.0f};
	for (int k = 0; k < 30000; ++k) {
		float size = sizes[k % 3];
		vec3 t[3] = {random_point(&state, size), random_point(&state, size), random_point(&state, size)};
		vec3 x = random_point(&state, size);
		if (k % 5 == 0) {
			/* In the triangle's plane, as for a neighbour in a flat cloth. */
			float a = test_uniform(&state, -1.0f, 2.0f), b = test_uniform(&state, -1.0f, 2.0f);
			x = v3_add(t[0], v3_add(v3_scale(v3_sub(t[1], t[0]), a), v3_scale(v3_sub(t[2], t[0]), b)));
		}
		if (k % 13 == 0) {
			t[2] = v3_lerp(t[0], t[1], 0.3f); /* degenerate: a segment */
		}
		vec3 centre = v3_scale(v3_add(v3_add(t[0], t[1]), t[2]), 1.0f / 3.0f);
		float gap = plait_point_triangle_gap(x, t, centre, plait_triangle_normal(t));
		float exact = point_triangle_distance(x, t);
		cr_assert(gap <= exact + rounding(size), "case %d: gap %g > distance %g", k, (double)gap,
		          (double)exact);
	}
}

Test(closest, point_triangle_gap_is_exact_over_the_face_and_beyond_a_corner)
{
	vec3 t[3] = {v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)};
	vec3 centre = v3(1.0f / 3.0f, 1.0f / 3.0f, 0.0f), normal = plait_triangle_normal(t);
	cr_assert_float_eq(normal.z, 1.0f, 1e-6f);
	/* Above the face: the height. */
	cr_assert_float_eq(plait_point_triangle_gap(v3(0.2f, 0.2f, -0.5f), t, centre, normal), 0.5f, 1e-6f);
	/* In the plane, beyond the corner at the origin along the line from the centre. */
	vec3 x = v3(-1.0f / 3.0f, -1.0f / 3.0f, 0.0f);
	cr_assert_float_eq(plait_point_triangle_gap(x, t, centre, normal), v3_length(x), 1e-6f);
}
