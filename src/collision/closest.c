#include "collision/closest.h"

static float clamp01(float x)
{
	return x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x;
}

float plait_closest_on_segment(vec3 p, vec3 a, vec3 b)
{
	vec3 ab = v3_sub(b, a);
	float length_sq = v3_length_sq(ab);
	return length_sq > 0.0f ? clamp01(v3_dot(v3_sub(p, a), ab) / length_sq) : 0.0f;
}

/* Ericson, Real-Time Collision Detection, 5.1.9: minimise over s, then clamp t and recompute s. */
float plait_closest_segments(vec3 p1, vec3 q1, vec3 p2, vec3 q2, float *s, float *t)
{
	vec3 d1 = v3_sub(q1, p1), d2 = v3_sub(q2, p2), r = v3_sub(p1, p2);
	float a = v3_length_sq(d1), e = v3_length_sq(d2), f = v3_dot(d2, r);
	float tiny = 1e-20f;
	if (a <= tiny && e <= tiny) {
		*s = *t = 0.0f;
	} else if (a <= tiny) {
		*s = 0.0f;
		*t = clamp01(f / e);
	} else {
		float c = v3_dot(d1, r);
		if (e <= tiny) {
			*t = 0.0f;
			*s = clamp01(-c / a);
		} else {
			float b = v3_dot(d1, d2);
			float denominator = a * e - b * b;
			/* Parallel segments (denominator 0): any s works; take 0 and let t follow. */
			*s = denominator > 1e-12f * a * e ? clamp01((b * f - c * e) / denominator) : 0.0f;
			*t = (b * *s + f) / e;
			if (*t < 0.0f) {
				*t = 0.0f;
				*s = clamp01(-c / a);
			} else if (*t > 1.0f) {
				*t = 1.0f;
				*s = clamp01((b - c) / a);
			}
		}
	}
	vec3 c1 = v3_mul_add(p1, *s, d1), c2 = v3_mul_add(p2, *t, d2);
	return v3_length_sq(v3_sub(c1, c2));
}

bool plait_closest_segments_inside(vec3 p1, vec3 q1, vec3 p2, vec3 q2)
{
	/* plait_closest_segments's arithmetic, step for step, to its first clamp. */
	vec3 d1 = v3_sub(q1, p1), d2 = v3_sub(q2, p2), r = v3_sub(p1, p2);
	float a = v3_length_sq(d1), e = v3_length_sq(d2), f = v3_dot(d2, r);
	float tiny = 1e-20f;
	if (a <= tiny || e <= tiny) {
		return false;
	}
	float c = v3_dot(d1, r), b = v3_dot(d1, d2);
	float denominator = a * e - b * b;
	if (!(denominator > 1e-12f * a * e)) {
		return false;
	}
	float s = clamp01((b * f - c * e) / denominator);
	if (s <= 0.0f || s >= 1.0f) {
		return false;
	}
	float t = (b * s + f) / e;
	return t > 0.0f && t < 1.0f;
}

float plait_segments_gap(vec3 p, vec3 q, vec3 r, vec3 s)
{
	vec3 d = v3_sub(v3_add(r, s), v3_add(p, q)); /* twice the line between the midpoints */
	float length = v3_length(d);
	if (!(length > 0.0f)) {
		return 0.0f;
	}
	vec3 u = v3_scale(d, 1.0f / length);
	return 0.5f * (length - fabsf(v3_dot(u, v3_sub(q, p))) - fabsf(v3_dot(u, v3_sub(s, r))));
}

float plait_point_triangle_gap(vec3 x, const vec3 *t, vec3 centre, vec3 normal)
{
	vec3 d = v3_sub(x, centre);
	/* Less the triangle's own spread along the normal: nothing when the normal is exact, and
	 * still a bound when rounding tilted it (a nearly degenerate triangle). */
	float spread = plait_maxf(
	    plait_maxf(fabsf(v3_dot(normal, v3_sub(t[0], centre))), fabsf(v3_dot(normal, v3_sub(t[1], centre)))),
	    fabsf(v3_dot(normal, v3_sub(t[2], centre))));
	float height = fabsf(v3_dot(normal, d)) - spread;
	float length = v3_length(d);
	if (!(length > 0.0f)) {
		return height;
	}
	vec3 u = v3_scale(d, 1.0f / length);
	float reach = plait_maxf(plait_maxf(v3_dot(u, v3_sub(t[0], centre)), v3_dot(u, v3_sub(t[1], centre))),
	                         v3_dot(u, v3_sub(t[2], centre)));
	return plait_maxf(height, length - reach);
}

vec3 plait_triangle_normal(const vec3 *t)
{
	vec3 n = v3_cross(v3_sub(t[1], t[0]), v3_sub(t[2], t[0]));
	float length = v3_length(n);
	return length > 0.0f ? v3_scale(n, 1.0f / length) : v3(0.0f, 0.0f, 0.0f);
}
