/* Double-precision 3-vectors, for the few places where a float's digits run out (exact
 * predicates, circles from differences of squares). Hot arrays stay float (core/math.h). */
#ifndef PLAIT_CORE_DVEC3_H
#define PLAIT_CORE_DVEC3_H

#include <math.h>

#include "core/math.h"

typedef struct dvec3 {
	double x, y, z;
} dvec3;

static inline dvec3 d3(vec3 a)
{
	return (dvec3){a.x, a.y, a.z};
}
static inline dvec3 d3_add(dvec3 a, dvec3 b)
{
	return (dvec3){a.x + b.x, a.y + b.y, a.z + b.z};
}
static inline dvec3 d3_sub(dvec3 a, dvec3 b)
{
	return (dvec3){a.x - b.x, a.y - b.y, a.z - b.z};
}
static inline dvec3 d3_scale(dvec3 a, double s)
{
	return (dvec3){a.x * s, a.y * s, a.z * s};
}
static inline double d3_dot(dvec3 a, dvec3 b)
{
	return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline dvec3 d3_cross(dvec3 a, dvec3 b)
{
	return (dvec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
static inline double d3_length(dvec3 a)
{
	return sqrt(d3_dot(a, a));
}

#endif
