#include "collision/intersect.h"

/* Signed volume (times 6) of the tetrahedron (a, b, c, d), in double precision. */
static double orient(vec3 a, vec3 b, vec3 c, vec3 d)
{
	double abx = (double)b.x - a.x, aby = (double)b.y - a.y, abz = (double)b.z - a.z;
	double acx = (double)c.x - a.x, acy = (double)c.y - a.y, acz = (double)c.z - a.z;
	double adx = (double)d.x - a.x, ady = (double)d.y - a.y, adz = (double)d.z - a.z;
	return abx * (acy * adz - acz * ady) - aby * (acx * adz - acz * adx) + abz * (acx * ady - acy * adx);
}

static int sign_of(double value)
{
	return value > 0.0 ? 1 : value < 0.0 ? -1 : 0;
}

bool plait_segment_crosses_triangle(vec3 p, vec3 q, vec3 a, vec3 b, vec3 c)
{
	int sp = sign_of(orient(a, b, c, p)), sq = sign_of(orient(a, b, c, q));
	if (sp == sq && sp != 0) {
		return false; /* both ends on one side of the plane */
	}
	if (sp == 0 && sq == 0) {
		return false; /* coplanar: counted by the other triangle's edges crossing, if any */
	}
	/* The line p-q passes inside the triangle when it sees the three edges turning one way. */
	int s1 = sign_of(orient(p, q, a, b)), s2 = sign_of(orient(p, q, b, c)), s3 = sign_of(orient(p, q, c, a));
	bool non_negative = s1 >= 0 && s2 >= 0 && s3 >= 0, non_positive = s1 <= 0 && s2 <= 0 && s3 <= 0;
	return non_negative || non_positive;
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
