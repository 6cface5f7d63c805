/* Closest points between the primitives of space-time collisions (paper §7): point and
 * segment, segment and segment. (Point and triangle is in mesh_shape.h.) Degenerate segments
 * (zero length) are handled as points. */
#ifndef PLAIT_COLLISION_CLOSEST_H
#define PLAIT_COLLISION_CLOSEST_H

#include "core/math.h"

/* Parameter t in [0, 1] of the point of segment a-b closest to p. */
float plait_closest_on_segment(vec3 p, vec3 a, vec3 b);

/* Parameters s (on p1-q1) and t (on p2-q2), both in [0, 1], of the closest points of two
 * segments; returns the squared distance between them. */
float plait_closest_segments(vec3 p1, vec3 q1, vec3 p2, vec3 q2, float *s, float *t);

#endif
