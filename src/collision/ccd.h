/* Continuous collision detection (CCD) for linearly moving primitives: vertex-face and edge-edge.
 *
 * The tests are conservative: they never miss a contact (floating-point rounding included), may
 * rarely report one that is not there (a near miss closer than double precision can resolve, or a
 * degenerate configuration that could not be resolved within the work budget), and report a time
 * of impact that is never after the first contact. docs/ccd.md explains the method and its error
 * bounds.
 *
 * Each primitive's four points move on straight lines: point i is start[i] at t = 0 and end[i] at
 * t = 1. Vertex-face: point 0 is the vertex, points 1..3 the triangle. Edge-edge: points 0, 1 are
 * the first edge, points 2, 3 the second.
 *
 * minimum_distance: the contact distance (thickness); 0 tests for touching. A query reports a hit
 *   when the primitives come within this distance for some t in [0, max_time]. (It may also report
 *   a near miss within (1 + 2^-10) times it, where telling the two apart would take boxes finer
 *   than the tolerance in time.)
 * tolerance: accuracy of the time of impact, in units of t. When the contact is certified,
 *   first_contact - tolerance <= toi <= first_contact. It never turns a near miss into a hit.
 *   PLAIT_CCD_DEFAULT_TOLERANCE (1e-6) costs little when touching (minimum_distance 0); with a
 *   thickness, hits cost more the finer the tolerance, and 1e-4 is cheaper (docs/ccd.md).
 * max_time: end of the tested interval, in [0, 1]; larger values are clamped to 1.
 * toi: receives the time of impact on a hit, max_time otherwise. Never after the first contact.
 *
 * Coordinates and minimum_distance must be finite and below 2^100 in magnitude; a query outside
 * that range is answered as a hit at t = 0. */
#ifndef PLAIT_COLLISION_CCD_H
#define PLAIT_COLLISION_CCD_H

#include <stdbool.h>

#define PLAIT_CCD_DEFAULT_TOLERANCE 1e-6

/* The four points of a query at t = 0 and t = 1. A struct rather than two array parameters so that
 * non-const arrays pass without qualifier warnings. */
typedef struct plait_ccd_motion {
	double start[4][3];
	double end[4][3];
} plait_ccd_motion;

typedef struct plait_ccd_motion_float {
	float start[4][3];
	float end[4][3];
} plait_ccd_motion_float;

bool plait_ccd_vertex_face(const plait_ccd_motion *motion, double minimum_distance, double tolerance,
                           double max_time, double *toi);
bool plait_ccd_edge_edge(const plait_ccd_motion *motion, double minimum_distance, double tolerance,
                         double max_time, double *toi);

/* Float convenience for the solver's float positions: the inputs widen to double exactly and the
 * time of impact is rounded down to float, so the guarantees above still hold. */
bool plait_ccd_vertex_face_float(const plait_ccd_motion_float *motion, float minimum_distance,
                                 float tolerance, float max_time, float *toi);
bool plait_ccd_edge_edge_float(const plait_ccd_motion_float *motion, float minimum_distance, float tolerance,
                               float max_time, float *toi);

#endif
