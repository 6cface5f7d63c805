#include "collision/intersect.h"

#include "core/dvec3.h"

/* Signed volume (times 6) of the tetrahedron (a, b, c, d), in double precision. */
static double orient(vec3 a, vec3 b, vec3 c, vec3 d)
{
	double abx = (double)b.x - a.x, aby = (double)b.y - a.y, abz = (double)b.z - a.z;
	double acx = (double)c.x - a.x, acy = (double)c.y - a.y, acz = (double)c.z - a.z;
	double adx = (double)d.x - a.x, ady = (double)d.y - a.y, adz = (double)d.z - a.z;
	return abx * (acy * adz - acz * ady) - aby * (acx * adz - acz * adx) + abz * (acx * ady - acy * adx);
}

bool plait_segment_crosses_triangle(vec3 p, vec3 q, vec3 a, vec3 b, vec3 c)
{
	double sp = orient(a, b, c, p), sq = orient(a, b, c, q);
	if ((sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0)) {
		return false; /* both ends on one side of the plane */
	}
	if (sp == 0.0 && sq == 0.0) {
		return false; /* coplanar: counted by the other triangle's edges crossing, if any */
	}
	/* Where the segment meets the plane, then whether that point is in the triangle (its border
	 * included). Asking whether the whole line through p and q passes through the triangle
	 * instead goes wrong for a segment that lies almost in the plane: the line then meets the
	 * plane far beyond the segment, where a neighbouring triangle of a flat sheet may be. */
	double t = sp / (sp - sq);
	dvec3 dp = d3(p), dq = d3(q), da = d3(a), db = d3(b), dc = d3(c);
	dvec3 x = {dp.x + t * (dq.x - dp.x), dp.y + t * (dq.y - dp.y), dp.z + t * (dq.z - dp.z)};
	dvec3 n = d3_cross(d3_sub(db, da), d3_sub(dc, da));
	double wa = d3_dot(d3_cross(d3_sub(db, x), d3_sub(dc, x)), n);
	double wb = d3_dot(d3_cross(d3_sub(dc, x), d3_sub(da, x)), n);
	double wc = d3_dot(d3_cross(d3_sub(da, x), d3_sub(db, x)), n);
	return (wa >= 0.0 && wb >= 0.0 && wc >= 0.0) || (wa <= 0.0 && wb <= 0.0 && wc <= 0.0);
}

bool plait_triangles_intersect(const vec3 t[3], const vec3 u[3])
{
	for (int k = 0; k < 3; ++k) {
		if (plait_segment_crosses_triangle(t[k], t[(k + 1) % 3], u[0], u[1], u[2]) ||
		    plait_segment_crosses_triangle(u[k], u[(k + 1) % 3], t[0], t[1], t[2])) {
			return true;
		}
	}
	return false;
}
