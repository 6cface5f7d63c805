/* A point and a triangle that both move on straight lines over a substep, as a particle and a
 * triangle of a deforming mesh collider do: cheap tests that spare the continuous test
 * (collision/ccd.h), which costs far more with four moving points than with one, in the common
 * cases where it is not needed. start and end are the triangle's corners at t = 0 and t = 1. */
#ifndef PLAIT_COLLISION_MOVING_TRIANGLE_H
#define PLAIT_COLLISION_MOVING_TRIANGLE_H

#include "core/math.h"

/* False when the point provably never crosses the triangle or comes within radius of it in a
 * way a proximity test at the end would miss: it moves by less than radius relative to every
 * corner (so relative to every point of the triangle: carried along by it, it cannot cross it
 * without ending within radius), or a plane of the triangle at start or end keeps the segment
 * p0-p1 more than radius from every position of the triangle. */
bool plait_moving_triangle_may_touch(vec3 p0, vec3 p1, const vec3 start[3], const vec3 end[3], float radius);

/* Whether the point starts within radius of the triangle, give or take 0.1% for the rounding of
 * a push that left it at exactly that distance: a contact at t = 0 that the continuous test
 * would take long to certify. */
bool plait_moving_triangle_touching_at_start(vec3 p0, const vec3 start[3], float radius);

#endif
