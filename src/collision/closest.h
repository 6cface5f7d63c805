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
/* Whether plait_closest_segments finds both closest points strictly inside their segments
 * (0 < s, t < 1), decided by the same arithmetic at a fraction of its cost. */
bool plait_closest_segments_inside(vec3 p1, vec3 q1, vec3 p2, vec3 q2);

/* Cheap lower bounds of distances, from projections on an axis (a projection on a unit axis
 * lengthens no distance). Exact up to rounding for primitives apart along the axis used,
 * weaker otherwise. */

/* Segments p-q and r-s (points are segments of length zero): the gap between their intervals
 * along the line through their midpoints. */
float plait_segments_gap(vec3 p, vec3 q, vec3 r, vec3 s);

/* Point x and triangle t[0..2], given a point `centre` of the triangle (its centroid, say) and
 * its unit normal (any unit vector is safe; zero for a degenerate triangle): the larger of the
 * gaps between x and the triangle along the normal and along the line from the centre to x. */
float plait_point_triangle_gap(vec3 x, const vec3 *t, vec3 centre, vec3 normal);

/* The unit normal of triangle t[0..2] (counter-clockwise), zero when it is degenerate. */
vec3 plait_triangle_normal(const vec3 *t);

#endif
