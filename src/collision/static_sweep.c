#include "collision/static_sweep.h"

#include "collision/closest.h"
#include "collision/intersect.h"
#include "collision/mesh_shape.h"

static float distance_to_triangle(vec3 p, vec3 a, vec3 b, vec3 c)
{
	int region;
	return v3_length(v3_sub(p, plait_closest_point_on_triangle(p, a, b, c, &region, NULL)));
}

bool plait_point_path_reaches_triangle(vec3 p0, vec3 p1, vec3 a, vec3 b, vec3 c, float radius, float *toi)
{
	/* Rounding in the distances is far below this; the radius is widened by it so that a path
	 * that truly touches is never judged clear. */
	vec3 motion = v3_sub(p1, p0);
	float scale = radius + v3_length(motion) + v3_length(v3_sub(p0, a)) + v3_length(v3_sub(b, a)) +
	              v3_length(v3_sub(c, a));
	float reach = radius + 1e-5f * scale;
	float start = distance_to_triangle(p0, a, b, c);
	if (start <= reach) {
		*toi = 0.0f;
		return true;
	}
	/* The closest approach of the segment to the triangle: an end, a point nearest an edge, or
	 * where the segment pierces it. */
	float nearest = distance_to_triangle(p1, a, b, c), at = 1.0f;
	vec3 edges[3][2] = {{a, b}, {b, c}, {c, a}};
	for (int e = 0; e < 3; ++e) {
		float s, t;
		float d = sqrtf(plait_closest_segments(p0, p1, edges[e][0], edges[e][1], &s, &t));
		if (d < nearest) {
			nearest = d;
			at = s;
		}
	}
	if (plait_segment_crosses_triangle(p0, p1, a, b, c)) {
		vec3 normal = v3_cross(v3_sub(b, a), v3_sub(c, a));
		float d0 = v3_dot(v3_sub(p0, a), normal), d1 = v3_dot(v3_sub(p1, a), normal);
		float crossing = d0 != d1 ? d0 / (d0 - d1) : 0.0f;
		nearest = 0.0f;
		at = crossing < 0.0f ? 0.0f : crossing > 1.0f ? 1.0f : crossing;
	}
	if (nearest > reach) {
		return false;
	}
	/* Convex in time: above the radius before the first touch, within it from there to the
	 * closest approach. Bisect, keeping the earlier end. */
	float lower = 0.0f, upper = at;
	for (int step = 0; step < 32 && upper - lower > 1e-7f; ++step) {
		float middle = 0.5f * (lower + upper);
		if (distance_to_triangle(v3_mul_add(p0, middle, motion), a, b, c) <= reach) {
			upper = middle;
		} else {
			lower = middle;
		}
	}
	*toi = lower;
	return true;
}
