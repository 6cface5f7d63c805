#include "core/math.h"

mat3 m3_identity(void)
{
	mat3 r = {{{1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, 1.0f}}};
	return r;
}

mat3 m3_mul(const mat3 *a, const mat3 *b)
{
	mat3 r;
	for (int i = 0; i < 3; ++i) {
		for (int j = 0; j < 3; ++j) {
			r.m[i][j] = a->m[i][0] * b->m[0][j] + a->m[i][1] * b->m[1][j] + a->m[i][2] * b->m[2][j];
		}
	}
	return r;
}

mat3 m3_from_euler_deg(vec3 degrees)
{
	const double to_radians = 3.14159265358979323846 / 180.0;
	double cx = cos(degrees.x * to_radians), sx = sin(degrees.x * to_radians);
	double cy = cos(degrees.y * to_radians), sy = sin(degrees.y * to_radians);
	double cz = cos(degrees.z * to_radians), sz = sin(degrees.z * to_radians);
	mat3 rx = {{{1, 0, 0}, {0, (float)cx, (float)-sx}, {0, (float)sx, (float)cx}}};
	mat3 ry = {{{(float)cy, 0, (float)sy}, {0, 1, 0}, {(float)-sy, 0, (float)cy}}};
	mat3 rz = {{{(float)cz, (float)-sz, 0}, {(float)sz, (float)cz, 0}, {0, 0, 1}}};
	mat3 ryx = m3_mul(&ry, &rx);
	return m3_mul(&rz, &ryx);
}
