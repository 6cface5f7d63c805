/* Static intersection tests: for checking results, and the segment test for paths against a
 * rigid mesh (collision/static_sweep.c). */
#ifndef PLAIT_COLLISION_INTERSECT_H
#define PLAIT_COLLISION_INTERSECT_H

#include "core/math.h"

/* Whether segment p-q crosses triangle (a, b, c), its ends and the triangle's border included.
 * Computed in double precision with orientation signs. */
bool plait_segment_crosses_triangle(vec3 p, vec3 q, vec3 a, vec3 b, vec3 c);

/* Whether two triangles intersect: some edge of one crosses the other. */
bool plait_triangles_intersect(const vec3 t[3], const vec3 u[3]);

#endif
