/* A point moving on a straight line against a triangle that stands still (a rigid mesh
 * collider, in its own space). The distance from a point moving on a line to a fixed convex
 * set is a convex function of time, so the first time it comes within a radius is found from
 * the closest approach of the segment to the triangle and a bisection before it: a few
 * closest-point evaluations instead of the general space-time test (collision/ccd.h), whose
 * subdivision is slow on the grazing paths of cloth resting on a mesh. */
#ifndef PLAIT_COLLISION_STATIC_SWEEP_H
#define PLAIT_COLLISION_STATIC_SWEEP_H

#include "core/math.h"

/* Whether the path p0 -> p1 comes within radius of triangle (a, b, c) at some t in [0, 1];
 * *toi receives a time no later than the first such t (0 when p0 already is). Conservative:
 * rounding can report a contact a hair early or a path that grazes within a hair of the
 * radius, never miss one. */
bool plait_point_path_reaches_triangle(vec3 p0, vec3 p1, vec3 a, vec3 b, vec3 c, float radius, float *toi);

#endif
