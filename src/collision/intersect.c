#include "collision/intersect.h"

/* Signed volume (times 6) of the tetrahedron (a, b, c, d), in double precision. */
static double orient(vec3 a, vec3 b, vec3 c, vec3 d)
{
	double abx = (double)b.x - a.x, aby = (double)b.y - a.y, abz = (double)b.z - a.z;
	double acx = (double)c.x - a.x, acy = (double)c.y - a.y, acz = (double)c.z - a.z;
	double adx = (double)d.x - a.x, ady = (double)d.y - a.y, adz = (double)d.z - a.z;
	return abx * (acy * adz - acz * ady) - aby * (acx * adz - acz * adx) + abz * (acx * ady - acy * adx);
}

typedef struct dvec3 {
	double x, y, z;
} dvec3;

static dvec3 dv(vec3 v)
{
	return (dvec3){v.x, v.y, v.z};
}

static dvec3 dsub(dvec3 a, dvec3 b)
{
	return (dvec3){a.x - b.x, a.y - b.y, a.z - b.z};
}

static dvec3 dcross(dvec3 a, dvec3 b)
{
	return (dvec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

static double ddot(dvec3 a, dvec3 b)
{
	return a.x * b.x + a.y * b.y + a.z * b.z;
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
	dvec3 dp = dv(p), dq = dv(q), da = dv(a), db = dv(b), dc = dv(c);
	dvec3 x = {dp.x + t * (dq.x - dp.x), dp.y + t * (dq.y - dp.y), dp.z + t * (dq.z - dp.z)};
	dvec3 n = dcross(dsub(db, da), dsub(dc, da));
	double wa = ddot(dcross(dsub(db, x), dsub(dc, x)), n);
	double wb = ddot(dcross(dsub(dc, x), dsub(da, x)), n);
	double wc = ddot(dcross(dsub(da, x), dsub(db, x)), n);
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
