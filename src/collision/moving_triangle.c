#include "collision/moving_triangle.h"

#include <math.h>

#include "collision/mesh_shape.h"

static bool moves_with_triangle(vec3 p0, vec3 p1, const vec3 start[3], const vec3 end[3], float radius)
{
	vec3 path = v3_sub(p1, p0);
	float largest_sq = 0.0f;
	for (int k = 0; k < 3; ++k) {
		largest_sq = plait_maxf(largest_sq, v3_length_sq(v3_sub(path, v3_sub(end[k], start[k]))));
	}
	return largest_sq < radius * radius;
}

/* Whether the plane through origin with normal n (any length) has points[0..1] (the path) on
 * one side and points[2..7] (the triangle at start and end, whose hull holds every position of
 * it) on the other, more than radius apart. In double, with a margin far above its rounding. */
static bool plane_separates(const vec3 points[8], vec3 origin, vec3 n, float radius)
{
	double nx = n.x, ny = n.y, nz = n.z;
	double length = sqrt(nx * nx + ny * ny + nz * nz);
	if (!(length > 0.0)) {
		return false;
	}
	double d[8], scale = 0.0;
	for (int k = 0; k < 8; ++k) {
		vec3 x = points[k];
		d[k] =
		    (((double)x.x - origin.x) * nx + ((double)x.y - origin.y) * ny + ((double)x.z - origin.z) * nz) /
		    length;
		scale = fmax(scale, fmax(fabs((double)x.x), fmax(fabs((double)x.y), fabs((double)x.z))));
	}
	double low = d[2], high = d[2];
	for (int k = 3; k < 8; ++k) {
		low = fmin(low, d[k]);
		high = fmax(high, d[k]);
	}
	double gap = (double)radius + 1e-9 * scale;
	return fmin(d[0], d[1]) - high > gap || low - fmax(d[0], d[1]) > gap;
}

bool plait_moving_triangle_may_touch(vec3 p0, vec3 p1, const vec3 start[3], const vec3 end[3], float radius)
{
	if (moves_with_triangle(p0, p1, start, end, radius)) {
		return false;
	}
	vec3 points[8] = {p0, p1, start[0], start[1], start[2], end[0], end[1], end[2]};
	vec3 n0 = v3_cross(v3_sub(start[1], start[0]), v3_sub(start[2], start[0]));
	vec3 n1 = v3_cross(v3_sub(end[1], end[0]), v3_sub(end[2], end[0]));
	return !plane_separates(points, start[0], n0, radius) && !plane_separates(points, end[0], n1, radius);
}

bool plait_moving_triangle_touching_at_start(vec3 p0, const vec3 start[3], float radius)
{
	int region;
	vec3 q = plait_closest_point_on_triangle(p0, start[0], start[1], start[2], &region, NULL);
	float reach = 1.001f * radius;
	return v3_length_sq(v3_sub(p0, q)) < reach * reach;
}
