/* Constructed CCD cases with known answers: grazing contacts and near misses, parallel and coplanar
 * motion, contacts exactly on edges and corners, fast motion, contact at t = 0 and degenerate
 * primitives, each with thickness 0 and a positive thickness.
 *
 * Every case is given in its own units (primitives about 1 across, or metres for the fast shots)
 * with the exact answer: no contact, or the first contact as the moment one coordinate difference
 * reaches a level. Each case runs through the double and the float API, and (except the fast
 * shots, which are physical) at three scales: as given, scaled by 1e-6 (about 1e-6 m across), and
 * scaled by 1e4 and translated by 1e4 m on every axis. The cases are built so that the contact
 * conditions survive the scaling and the rounding to float exactly: points that must touch share
 * their coordinates, and a gap of exactly the thickness d lies between coordinates 0 and +-d (d is
 * dyadic, so with the scale and the offset of the frames all three round alike). The expected time
 * is computed from the coordinates actually passed to the query.
 *
 * A reported contact must be at or before the exact first contact and within the tolerance of it;
 * a near miss (a closest approach 1e-3 of the size beyond the thickness) must not be reported. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "collision/ccd.h"

#define TOL PLAIT_CCD_DEFAULT_TOLERANCE
/* Closest approach beyond the thickness of a near miss, in units of the primitives' size. */
#define NEAR_MISS 1e-3
/* The float API rounds the time of impact down to a float: at most 2^-24 below it for t < 1. */
#define FLOAT_TOI_ROUNDING 0x1p-24

/* Point indices: vertex-face queries have the vertex first, then the triangle; edge-edge queries
 * have edge a, then edge b. */
enum { VERTEX = 0, TRI_A = 1, TRI_B = 2, TRI_C = 3 };
enum { A0 = 0, A1 = 1, B0 = 2, B1 = 3 };
enum { X = 0, Y = 1, Z = 2 };

/* Zero (touching) and a positive thickness, about 1.6% of the primitives' size. */
static const double thicknesses[2] = {0.0, 1.0 / 64.0};

static const double unit_triangle[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

typedef struct ccd_case {
	char name[96];
	bool vertex_face;
	plait_ccd_motion motion;
	double distance;
	/* The exact answer. With a contact, the first one is at t = 0 (at_start), or at the moment
	 * coordinate `axis` of point `mover` minus that of point `reference` reaches `level` (which
	 * scales like the coordinates). A grazing contact is one where the distance is sqrt(d^2 + D^2)
	 * with D that coordinate difference (level 0): exactly d at its closest, never less. */
	bool contact, at_start, grazing;
	int mover, reference, axis;
	double level;
} ccd_case;

/* A vertex moving from `from` to `to` against a triangle at rest. */
static ccd_case vertex_case(const char *name, const double triangle[3][3], const double from[3],
                            const double to[3], double distance)
{
	ccd_case c = {.vertex_face = true, .distance = distance};
	snprintf(c.name, sizeof(c.name), "%s", name);
	for (int k = 0; k < 3; k++) {
		c.motion.start[VERTEX][k] = from[k];
		c.motion.end[VERTEX][k] = to[k];
		for (int i = 0; i < 3; i++)
			c.motion.start[TRI_A + i][k] = c.motion.end[TRI_A + i][k] = triangle[i][k];
	}
	return c;
}

/* Edge a translating by a_move and edge b translating by b_move. */
static ccd_case edge_case(const char *name, const double a[2][3], const double a_move[3],
                          const double b[2][3], const double b_move[3], double distance)
{
	ccd_case c = {.vertex_face = false, .distance = distance};
	snprintf(c.name, sizeof(c.name), "%s", name);
	for (int k = 0; k < 3; k++) {
		for (int i = 0; i < 2; i++) {
			c.motion.start[A0 + i][k] = a[i][k];
			c.motion.end[A0 + i][k] = a[i][k] + a_move[k];
			c.motion.start[B0 + i][k] = b[i][k];
			c.motion.end[B0 + i][k] = b[i][k] + b_move[k];
		}
	}
	return c;
}

static ccd_case contact_when(ccd_case c, int mover, int reference, int axis, double level)
{
	c.contact = true;
	c.mover = mover;
	c.reference = reference;
	c.axis = axis;
	c.level = level;
	return c;
}

/* Touching at exactly distance d when the difference along axis passes 0 (see ccd_case). */
static ccd_case grazing_when(ccd_case c, int mover, int reference, int axis)
{
	c = contact_when(c, mover, reference, axis, 0.0);
	c.grazing = true;
	return c;
}

static ccd_case contact_at_start(ccd_case c)
{
	c.contact = true;
	c.at_start = true;
	return c;
}

/* The same motion sheared into the slanted plane z = x (z += x), for thickness 0, where the contact
 * times do not change: an affine map keeps touching points touching. The dyadic coordinates of the
 * cases stay exact. */
static ccd_case sheared(ccd_case c)
{
	cr_assert_eq(c.distance, 0.0, "shearing changes distances");
	for (int i = 0; i < 4; i++) {
		c.motion.start[i][Z] += c.motion.start[i][X];
		c.motion.end[i][Z] += c.motion.end[i][X];
	}
	size_t length = strlen(c.name);
	snprintf(c.name + length, sizeof(c.name) - length, " (sheared)");
	return c;
}

/* ---- running ------------------------------------------------------------------------------ */

/* Coordinates are multiplied by scale, then offset is added on every axis. */
typedef struct ccd_frame {
	double scale, offset;
} ccd_frame;

static const ccd_frame all_frames[3] = {{1.0, 0.0}, {1e-6, 0.0}, {1e4, 1e4}};
static const ccd_frame given_frame[1] = {{1.0, 0.0}};

static plait_ccd_motion transformed(const plait_ccd_motion *m, ccd_frame frame)
{
	plait_ccd_motion out;
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++) {
			out.start[i][k] = m->start[i][k] * frame.scale + frame.offset;
			out.end[i][k] = m->end[i][k] * frame.scale + frame.offset;
		}
	}
	return out;
}

static plait_ccd_motion_float to_float(const plait_ccd_motion *m)
{
	plait_ccd_motion_float out;
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++) {
			out.start[i][k] = (float)m->start[i][k];
			out.end[i][k] = (float)m->end[i][k];
		}
	}
	return out;
}

static plait_ccd_motion widened(const plait_ccd_motion_float *m)
{
	plait_ccd_motion out;
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++) {
			out.start[i][k] = m->start[i][k];
			out.end[i][k] = m->end[i][k];
		}
	}
	return out;
}

/* The exact first contact of the case as run (motion m, level scaled like m). All motions are
 * linear, so the coordinate difference is linear in t. */
static double first_contact(const ccd_case *c, const plait_ccd_motion *m, double level)
{
	if (c->at_start)
		return 0.0;
	int k = c->axis;
	double d0 = m->start[c->mover][k] - m->start[c->reference][k];
	double d1 = m->end[c->mover][k] - m->end[c->reference][k];
	return (level - d0) / (d1 - d0);
}

/* With a thickness, a grazing contact never comes closer than d, so it cannot be certified: the
 * query reports it as a near contact, from the start of a box that spans at most the tolerance and
 * holds a point within d (1 + 2^-10) (docs/ccd.md, step 6). The distance sqrt(d^2 + D^2) is within
 * d (1 + 2^-10) from this long before the contact on, so toi may be that much earlier than the
 * tolerance alone allows. */
static double grazing_window(const ccd_case *c, const plait_ccd_motion *m, double distance)
{
	if (!c->grazing || distance == 0.0)
		return 0.0;
	int k = c->axis;
	double d0 = m->start[c->mover][k] - m->start[c->reference][k];
	double d1 = m->end[c->mover][k] - m->end[c->reference][k];
	double slack = 0x1p-10;
	return distance * sqrt(slack * (2.0 + slack)) / fabs(d1 - d0);
}

/* contact: the exact first contact, NAN without one; allowed: how far before it toi may be. */
static void check(const ccd_case *c, const char *where, bool hit, double toi, double contact, double allowed)
{
	if (isnan(contact)) {
		cr_expect_not(hit, "%s: contact reported at t = %.17g on a miss", where, toi);
		cr_expect_eq(toi, 1.0, "%s: toi %.17g is not max_time without a hit", where, toi);
		return;
	}
	cr_assert(contact >= 0.0 && contact <= 1.0, "%s: the case's contact time %.17g is out of [0, 1]", where,
	          contact);
	cr_expect(hit, "%s: contact at t = %.17g missed", where, contact);
	if (!hit)
		return;
	cr_expect_geq(toi, 0.0, "%s: negative toi %.17g", where, toi);
	cr_expect_leq(toi, contact, "%s: toi %.17g after the first contact at %.17g", where, toi, contact);
	cr_expect_leq(contact - toi, allowed, "%s: toi %.17g more than %g before the first contact at %.17g",
	              where, toi, allowed, contact);
}

static void run_double(const ccd_case *c, ccd_frame frame, const char *where)
{
	plait_ccd_motion m = transformed(&c->motion, frame);
	double distance = c->distance * frame.scale, toi = -1.0;
	bool hit = c->vertex_face ? plait_ccd_vertex_face(&m, distance, TOL, 1.0, &toi)
	                          : plait_ccd_edge_edge(&m, distance, TOL, 1.0, &toi);
	double contact = c->contact ? first_contact(c, &m, c->level * frame.scale) : NAN;
	check(c, where, hit, toi, contact, TOL + grazing_window(c, &m, distance));
}

static void run_float(const ccd_case *c, ccd_frame frame, const char *where)
{
	plait_ccd_motion wide = transformed(&c->motion, frame);
	plait_ccd_motion_float m = to_float(&wide);
	float distance = (float)(c->distance * frame.scale), toi = -1.0f;
	bool hit = c->vertex_face ? plait_ccd_vertex_face_float(&m, distance, (float)TOL, 1.0f, &toi)
	                          : plait_ccd_edge_edge_float(&m, distance, (float)TOL, 1.0f, &toi);
	/* The exact answer for the float coordinates: the same construction, rounded consistently. */
	wide = widened(&m);
	double contact = c->contact ? first_contact(c, &wide, (float)(c->level * frame.scale)) : NAN;
	check(c, where, hit, toi, contact, TOL + FLOAT_TOI_ROUNDING + grazing_window(c, &wide, distance));
}

static void run_in(ccd_case c, const ccd_frame *frames, int frame_count)
{
	for (int f = 0; f < frame_count; f++) {
		for (int precision = 0; precision < 2; precision++) {
			char where[256];
			snprintf(where, sizeof(where), "%s %s, d = %g, %s, scale %g, offset %g",
			         c.vertex_face ? "vf" : "ee", c.name, c.distance, precision ? "float" : "double",
			         frames[f].scale, frames[f].offset);
			if (precision)
				run_float(&c, frames[f], where);
			else
				run_double(&c, frames[f], where);
		}
	}
}

/* At every scale, in double and float. */
static void run(ccd_case c)
{
	run_in(c, all_frames, 3);
}

/* ---- grazing contact and near misses -------------------------------------------------------- */

Test(ccd_cases, grazing_contact_and_near_miss)
{
	const double(*tri)[3] = unit_triangle;
	for (int i = 0; i < 2; i++) {
		double d = thicknesses[i], miss = d + NEAR_MISS;
		/* Falling beside the edge y = 0 at a lateral gap d: the distance sqrt(d^2 + z^2) is d at
		 * z = 0 only (t = 0.5). With d = 0 the vertex passes exactly through the edge. */
		run(grazing_when(vertex_case("vertex falls past an edge at gap d", tri, (const double[3]){0.5, -d, 1},
		                             (const double[3]){0.5, -d, -1}, d),
		                 VERTEX, TRI_A, Z));
		run(vertex_case("vertex falls past an edge, near miss", tri, (const double[3]){0.5, -miss, 1},
		                (const double[3]){0.5, -miss, -1}, d));
		/* Crossing the plane exactly on the edge y = 0 while coming from outside: at y < 0 the
		 * distance is that to the edge, sqrt(y^2 + z^2) = -sqrt(2) y; it reaches d at y = -d / sqrt(2).
		 * Shifted by 1.415 times the near-miss gap, the closest approach, shift / sqrt(2), is
		 * beyond d + 1e-3. */
		run(contact_when(vertex_case("vertex crosses the plane on an edge, from outside", tri,
		                             (const double[3]){0.5, -1, 1}, (const double[3]){0.5, 1, -1}, d),
		                 VERTEX, TRI_A, Y, -d / sqrt(2.0)));
		double shift = 1.415 * miss;
		run(vertex_case("vertex crosses the plane beside an edge, near miss", tri,
		                (const double[3]){0.5, -1 - shift, 1}, (const double[3]){0.5, 1 - shift, -1}, d));
		/* Falling past a corner: (-d, 0) is d from the corner (0, 0) and farther from the rest. */
		run(grazing_when(vertex_case("vertex falls past a corner at gap d", tri, (const double[3]){-d, 0, 1},
		                             (const double[3]){-d, 0, -1}, d),
		                 VERTEX, TRI_A, Z));
		run(vertex_case("vertex falls past a corner, near miss", tri, (const double[3]){-miss, 0, 1},
		                (const double[3]){-miss, 0, -1}, d));

		/* Edge b (along y, at x = d) falls past the end (0, 0, 0) of edge a: the distance is
		 * sqrt(d^2 + z^2), d at z = 0 only. With d = 0, a's endpoint touches b's interior. */
		const double a[2][3] = {{-1, 0, 0}, {0, 0, 0}}, still[3] = {0, 0, 0}, fall[3] = {0, 0, -2};
		run(grazing_when(edge_case("edge falls past an edge's end at gap d", a, still,
		                           (const double[2][3]){{d, -1, 1}, {d, 1, 1}}, fall, d),
		                 B0, A1, Z));
		run(edge_case("edge falls past an edge's end, near miss", a, still,
		              (const double[2][3]){{miss, -1, 1}, {miss, 1, 1}}, fall, d));
		/* The same with b's endpoint passing a's endpoint. */
		run(grazing_when(edge_case("endpoint falls past an endpoint at gap d", a, still,
		                           (const double[2][3]){{d, 0, 1}, {d, 1, 1}}, fall, d),
		                 B0, A1, Z));
		run(edge_case("endpoint falls past an endpoint, near miss", a, still,
		              (const double[2][3]){{miss, 0, 1}, {miss, 1, 1}}, fall, d));
		/* Skew edges passing over each other at height d: a along x, b along y. */
		const double across[2][3] = {{0, 0, 0}, {1, 0, 0}};
		run(grazing_when(edge_case("edge slides over an edge at height d", across, still,
		                           (const double[2][3]){{-1, -0.5, d}, {-1, 0.5, d}},
		                           (const double[3]){2, 0, 0}, d),
		                 B0, A0, X));
		run(edge_case("edge slides over an edge, near miss", across, still,
		              (const double[2][3]){{-1, -0.5, miss}, {-1, 0.5, miss}}, (const double[3]){3, 0, 0},
		              d));
	}
}

/* ---- parallel edges ----------------------------------------------------------------------------- */

Test(ccd_cases, parallel_edges)
{
	const double up[3] = {0, 1, 0}, down[3] = {0, -1, 0}, still[3] = {0, 0, 0};
	const double a[2][3] = {{0, -0.5, 0}, {1, -0.5, 0}};
	for (int i = 0; i < 2; i++) {
		double d = thicknesses[i], miss = d + NEAR_MISS;
		/* Both move, closing in y: the gap 1 - 2t reaches d at t = (1 - d) / 2. */
		run(contact_when(edge_case("parallel, overlapping, closing", a, up,
		                           (const double[2][3]){{0.5, 0.5, 0}, {1.5, 0.5, 0}}, down, d),
		                 B0, A0, Y, d));
		/* End to end: the endpoints (1, y) close head on. */
		run(contact_when(edge_case("parallel, end to end, closing", a, up,
		                           (const double[2][3]){{1, 0.5, 0}, {2, 0.5, 0}}, down, d),
		                 B0, A0, Y, d));
		run(edge_case("parallel, not overlapping, near miss", a, up,
		              (const double[2][3]){{1 + miss, 0.5, 0}, {2 + miss, 0.5, 0}}, down, d));
		/* Overlapping in projection but passing d + 1e-3 apart in z. */
		run(edge_case("parallel, overlapping, passing above, near miss", a, up,
		              (const double[2][3]){{0.5, 0.5, miss}, {1.5, 0.5, miss}}, down, d));
		/* Closing along (0, 1, 2) out of any axis plane: the gap (1 - 2 t) (0, 1/2, 1) is sqrt(5) / 2
		 * times the z gap. */
		run(contact_when(edge_case("parallel, overlapping, closing diagonally", a, still,
		                           (const double[2][3]){{0.5, 0, 1}, {1.5, 0, 1}},
		                           (const double[3]){0, -1, -2}, d),
		                 B0, A0, Z, 2.0 * d / sqrt(5.0)));

		/* Sliding along x at constant distance: a along x at y = 0, b at y = h. */
		const double line[2][3] = {{0, 0, 0}, {1, 0, 0}}, slide[3] = {2, 0, 0};
		/* At h = d, b's front end (x, d) is sqrt(x^2 + d^2) from a's end (0, 0): d at x = 0. With
		 * d = 0 the edges are collinear and meet end to end. */
		run(grazing_when(edge_case("parallel, sliding into overlap at distance d", line, still,
		                           (const double[2][3]){{-2, d, 0}, {-1, d, 0}}, slide, d),
		                 B1, A0, X));
		run(edge_case("parallel, sliding along each other, near miss", line, still,
		              (const double[2][3]){{-1.5, miss, 0}, {-0.5, miss, 0}}, slide, d));
		run(contact_at_start(edge_case("parallel, sliding along each other at distance d", line, still,
		                               (const double[2][3]){{-0.5, d, 0}, {0.5, d, 0}}, slide, d)));
		if (d > 0.0) {
			/* At h = d / 2 the ends come within d at x = -sqrt(3) d / 2. */
			run(contact_when(edge_case("parallel, sliding into overlap at distance d / 2", line, still,
			                           (const double[2][3]){{-2, d / 2, 0}, {-1, d / 2, 0}}, slide, d),
			                 B1, A0, X, -sqrt(3.0) * d / 2));
			/* Side by side 0.6 d apart in x, closing in y: within d at a y gap of 0.8 d. */
			run(contact_when(edge_case("parallel, side by side, closing", a, up,
			                           (const double[2][3]){{1 + 0.6 * d, 0.5, 0}, {2 + 0.6 * d, 0.5, 0}},
			                           down, d),
			                 B0, A0, Y, 0.8 * d));
		}
	}
}

/* ---- coplanar motion ---------------------------------------------------------------------------- */

Test(ccd_cases, coplanar_motion)
{
	const double(*tri)[3] = unit_triangle;
	/* The triangle (0, -1), (1, -1), (0, 0): its 45-degree corner sits at the origin. */
	const double corner_at_origin[3][3] = {{0, -1, 0}, {1, -1, 0}, {0, 0, 0}};
	for (int i = 0; i < 2; i++) {
		double d = thicknesses[i], miss = d + NEAR_MISS;
		/* Sliding in the plane into the triangle through its edge x = 0: within d at x = -d. */
		ccd_case into =
		    contact_when(vertex_case("vertex slides into the triangle in its plane", tri,
		                             (const double[3]){-1, 0.25, 0}, (const double[3]){1, 0.25, 0}, d),
		                 VERTEX, TRI_A, X, -d);
		run(into);
		/* Sliding past the corner at the origin at gap y = d: the corner is the closest point, at
		 * x = 0 only (beyond it the slanted edge is at least sqrt(2) d away). */
		ccd_case past =
		    grazing_when(vertex_case("vertex slides past a corner in the plane at gap d", corner_at_origin,
		                             (const double[3]){-1, d, 0}, (const double[3]){1, d, 0}, d),
		                 VERTEX, TRI_C, X);
		run(past);
		run(vertex_case("vertex slides past a corner in the plane, near miss", corner_at_origin,
		                (const double[3]){-1, miss, 0}, (const double[3]){1, miss, 0}, d));
		run(vertex_case("vertex slides past the triangle in its plane", tri, (const double[3]){-1, 1.5, 0},
		                (const double[3]){2, 1.5, 0}, d));

		/* Edge a (along y) moves right, edge b (slanted) left: b's lower end (x, -0.5) leads, and
		 * the x gap 1.5 - 3 t reaches d at t = (1.5 - d) / 3; then they cross. */
		const double a[2][3] = {{0, -1, 0}, {0, 1, 0}}, right[3] = {1, 0, 0}, left[3] = {-2, 0, 0};
		ccd_case crossing =
		    contact_when(edge_case("edges in one plane, crossing", a, right,
		                           (const double[2][3]){{1.5, -0.5, 0}, {2.5, 0.5, 0}}, left, d),
		                 B0, A0, X, d);
		run(crossing);
		/* b passes a's end (0, 1) at a gap: its closest approach is the y gap at its lower end. */
		ccd_case beside = edge_case("edges in one plane, passing beside", a, right,
		                            (const double[2][3]){{1.5, 1 + miss, 0}, {2.5, 2 + miss, 0}}, left, d);
		run(beside);
		/* b's lower end slides along a's line into a's end (0, -1): collinear for the whole step. */
		run(contact_when(edge_case("edges on one line, meeting end to end",
		                           (const double[2][3]){{0, 0, 0}, {0, 1, 0}}, (const double[3]){0, 0, 0},
		                           (const double[2][3]){{0, -2, 0}, {0, -1.5, 0}}, (const double[3]){0, 2, 0},
		                           d),
		                 B1, A0, Y, -d));

		/* The same out of the axis planes (touching only: shearing changes distances). */
		if (d == 0.0) {
			run(sheared(into));
			run(sheared(past));
			run(sheared(crossing));
			run(sheared(beside));
		}
	}
}

/* ---- exactly through edges and corners ---------------------------------------------------------- */

Test(ccd_cases, through_edges_and_corners)
{
	const double(*tri)[3] = unit_triangle;
	/* Falling straight through these points of the triangle: the distance is z, so the first
	 * contact is at z = d. The slanted edge's midpoint (0.5, 0.5) scales exactly too. */
	const struct {
		const char *name;
		double x, y;
	} targets[6] = {
	    {"vertex falls through the interior", 0.25, 0.25},   {"vertex falls through the edge y = 0", 0.5, 0},
	    {"vertex falls through the slanted edge", 0.5, 0.5}, {"vertex falls through the corner (0, 0)", 0, 0},
	    {"vertex falls through the corner (1, 0)", 1, 0},    {"vertex falls through the corner (0, 1)", 0, 1},
	};
	const double still[3] = {0, 0, 0}, fall[3] = {0, 0, -2};
	const double a[2][3] = {{0, 0, 0}, {1, 0, 0}};
	for (int i = 0; i < 2; i++) {
		double d = thicknesses[i], miss = d + NEAR_MISS;
		for (int j = 0; j < 6; j++) {
			run(contact_when(vertex_case(targets[j].name, tri,
			                             (const double[3]){targets[j].x, targets[j].y, 1},
			                             (const double[3]){targets[j].x, targets[j].y, -1}, d),
			                 VERTEX, TRI_A, Z, d));
		}
		/* Just outside the slanted edge, (0.5 + s, 0.5 + s) is sqrt(2) s from it. */
		double s = 0.708 * miss;
		run(vertex_case("vertex falls just outside the slanted edge", tri,
		                (const double[3]){0.5 + s, 0.5 + s, 1}, (const double[3]){0.5 + s, 0.5 + s, -1}, d));
		/* Just outside the corner (1, 0), on the slanted edge's line: sqrt(2) miss from the corner. */
		run(vertex_case("vertex falls just outside a corner", tri, (const double[3]){1 + miss, -miss, 1},
		                (const double[3]){1 + miss, -miss, -1}, d));

		/* Edge b's lower end falls onto a's interior: straight down, with all four points in the
		 * plane y = 0 (a flat query), or with b slanted out of it. Within d at height d. */
		run(contact_when(edge_case("endpoint falls onto an edge's interior", a, still,
		                           (const double[2][3]){{0.5, 0, 1}, {0.5, 0, 2}}, fall, d),
		                 B0, A0, Z, d));
		run(contact_when(edge_case("slanted endpoint falls onto an edge's interior", a, still,
		                           (const double[2][3]){{0.5, 0, 1}, {0.75, 1, 2}}, fall, d),
		                 B0, A0, Z, d));
		run(contact_when(edge_case("endpoint falls onto an endpoint", a, still,
		                           (const double[2][3]){{1, 0, 1}, {1.25, 1, 2}}, fall, d),
		                 B0, A0, Z, d));
		run(contact_when(edge_case("edge falls across an edge", a, still,
		                           (const double[2][3]){{0.5, -1, 1}, {0.5, 1, 1}}, fall, d),
		                 B0, A0, Z, d));
		run(edge_case("endpoint falls just beyond an edge's end", a, still,
		              (const double[2][3]){{1 + miss, 0, 1}, {1.25 + miss, 1, 2}}, fall, d));
	}
}

/* ---- fast motion ---------------------------------------------------------------------------------- */

Test(ccd_cases, fast_particle_through_a_small_triangle)
{
	/* 1000 m/s over a 1/600 s substep: 1.67 m per step, through a triangle 1 cm across. */
	const double size = 0.01, step = 1000.0 / 600.0;
	const double tri[3][3] = {{0, 0, 0}, {size, 0, 0}, {0, size, 0}};
	const struct {
		const char *name;
		double x, y;
	} targets[6] = {
	    {"fast vertex through the interior", 0.25 * size, 0.25 * size},
	    {"fast vertex through the edge y = 0", 0.5 * size, 0},
	    {"fast vertex through the slanted edge", 0.5 * size, 0.5 * size},
	    {"fast vertex through the corner (0, 0)", 0, 0},
	    {"fast vertex through the corner (size, 0)", size, 0},
	    {"fast vertex through the corner (0, size)", 0, size},
	};
	/* Zero thickness, and 1 mm. */
	const double fast_thicknesses[2] = {0.0, 1e-3};
	for (int i = 0; i < 2; i++) {
		double d = fast_thicknesses[i], miss = d + NEAR_MISS * size;
		/* Straight down, crossing the plane at t = 0.7 / step = 0.42; within d at z = d. */
		for (int j = 0; j < 6; j++) {
			run_in(contact_when(vertex_case(targets[j].name, tri,
			                                (const double[3]){targets[j].x, targets[j].y, 0.7},
			                                (const double[3]){targets[j].x, targets[j].y, 0.7 - step}, d),
			                    VERTEX, TRI_A, Z, d),
			       given_frame, 1);
		}
		/* Obliquely at 1000 m/s, velocity (600, 0, -800) m/s, crossing the plane at t = 0.42 at
		 * (0.25 size, 0.25 size). */
		double t = 0.42, vx = 0.6 * step, vz = -0.8 * step, x = 0.25 * size - t * vx;
		run_in(contact_when(vertex_case("fast oblique vertex through the interior", tri,
		                                (const double[3]){x, 0.25 * size, -t * vz},
		                                (const double[3]){x + vx, 0.25 * size, -t * vz + vz}, d),
		                    VERTEX, TRI_A, Z, d),
		       given_frame, 1);
		/* Near misses: 1e-3 of the triangle's size beyond d outside an edge and outside a corner. */
		run_in(vertex_case("fast vertex just outside an edge", tri, (const double[3]){0.5 * size, -miss, 0.7},
		                   (const double[3]){0.5 * size, -miss, 0.7 - step}, d),
		       given_frame, 1);
		run_in(vertex_case("fast vertex just outside a corner", tri,
		                   (const double[3]){size + miss, -miss, 0.7},
		                   (const double[3]){size + miss, -miss, 0.7 - step}, d),
		       given_frame, 1);
	}
}

/* ---- contact at t = 0 ----------------------------------------------------------------------------- */

Test(ccd_cases, touching_at_start)
{
	const double(*tri)[3] = unit_triangle;
	const double a[2][3] = {{0, 0, 0}, {1, 0, 0}}, still[3] = {0, 0, 0}, rise[3] = {0, 0, 1};
	for (int i = 0; i < 2; i++) {
		double d = thicknesses[i];
		/* At distance d from the triangle at t = 0, moving away, at rest, or moving in. */
		run(contact_at_start(vertex_case("vertex on the face at t = 0, moving away", tri,
		                                 (const double[3]){0.25, 0.25, d}, (const double[3]){0.25, 0.25, 1},
		                                 d)));
		run(contact_at_start(vertex_case("vertex on the face, at rest", tri, (const double[3]){0.25, 0.25, d},
		                                 (const double[3]){0.25, 0.25, d}, d)));
		run(contact_at_start(vertex_case("vertex on the face at t = 0, moving through", tri,
		                                 (const double[3]){0.25, 0.25, d}, (const double[3]){0.25, 0.25, -1},
		                                 d)));
		run(contact_at_start(vertex_case("vertex on an edge at t = 0, sliding out in the plane", tri,
		                                 (const double[3]){0.5, -d, 0}, (const double[3]){0.5, -1, 0}, d)));
		run(contact_at_start(vertex_case("vertex on a corner at t = 0, moving away", tri,
		                                 (const double[3]){1, 0, d}, (const double[3]){1, 1, 1}, d)));
		/* Edges crossing at t = 0, an endpoint on an interior, and a shared endpoint. */
		run(contact_at_start(edge_case("edges crossing at t = 0, moving apart", a, still,
		                               (const double[2][3]){{0.5, -1, d}, {0.5, 1, d}}, rise, d)));
		run(contact_at_start(edge_case("endpoint on an edge at t = 0, moving apart", a, still,
		                               (const double[2][3]){{0.5, 0, d}, {0.5, 1, 1}}, rise, d)));
		run(contact_at_start(edge_case("edges sharing an endpoint, moving apart", a, still,
		                               (const double[2][3]){{1, 0, 0}, {1, 1, 0}}, rise, d)));
		if (d > 0.0) {
			/* Closer than d at t = 0. */
			run(contact_at_start(vertex_case("vertex within d at t = 0, moving away", tri,
			                                 (const double[3]){0.25, 0.25, d / 2},
			                                 (const double[3]){0.25, 0.25, 1}, d)));
			run(contact_at_start(edge_case("edges within d at t = 0, moving apart", a, still,
			                               (const double[2][3]){{0.5, -1, d / 2}, {0.5, 1, d / 2}}, rise,
			                               d)));
		}
	}
}

/* ---- degenerate primitives ------------------------------------------------------------------------ */

Test(ccd_cases, degenerate_primitives)
{
	/* A triangle with three collinear corners, and one shrunk to a point. */
	const double segment[3][3] = {{0, 0, 0}, {1, 0, 0}, {0.5, 0, 0}};
	const double point[3][3] = {{0.5, 0.5, 0}, {0.5, 0.5, 0}, {0.5, 0.5, 0}};
	const double still[3] = {0, 0, 0}, fall[3] = {0, 0, -2};
	const double a_point[2][3] = {{0.5, 0, 0}, {0.5, 0, 0}};
	for (int i = 0; i < 2; i++) {
		double d = thicknesses[i];
		/* Falling straight through them: within d at z = d. Beside them, 0.25 away: no contact. */
		run(contact_when(vertex_case("vertex falls through a zero-area triangle", segment,
		                             (const double[3]){0.25, 0, 1}, (const double[3]){0.25, 0, -1}, d),
		                 VERTEX, TRI_A, Z, d));
		run(vertex_case("vertex falls beside a zero-area triangle", segment, (const double[3]){0.25, 0.25, 1},
		                (const double[3]){0.25, 0.25, -1}, d));
		run(contact_when(vertex_case("vertex slides along a zero-area triangle's line into it", segment,
		                             (const double[3]){-1, 0, 0}, (const double[3]){1, 0, 0}, d),
		                 VERTEX, TRI_A, X, -d));
		run(contact_when(vertex_case("vertex falls through a triangle shrunk to a point", point,
		                             (const double[3]){0.5, 0.5, 1}, (const double[3]){0.5, 0.5, -1}, d),
		                 VERTEX, TRI_A, Z, d));
		run(vertex_case("vertex falls beside a triangle shrunk to a point", point,
		                (const double[3]){0.75, 0.5, 1}, (const double[3]){0.75, 0.5, -1}, d));

		/* A zero-length edge a at (0.5, 0, 0), against a falling edge and a falling point. */
		run(contact_when(edge_case("edge falls through a zero-length edge", a_point, still,
		                           (const double[2][3]){{0.5, -1, 1}, {0.5, 1, 1}}, fall, d),
		                 B0, A0, Z, d));
		run(edge_case("edge falls beside a zero-length edge", a_point, still,
		              (const double[2][3]){{0.75, -1, 1}, {0.75, 1, 1}}, fall, d));
		run(contact_when(edge_case("zero-length edge falls through a zero-length edge", a_point, still,
		                           (const double[2][3]){{0.5, 0, 1}, {0.5, 0, 1}}, fall, d),
		                 B0, A0, Z, d));
		run(edge_case("zero-length edge falls beside a zero-length edge", a_point, still,
		              (const double[2][3]){{0.75, 0, 1}, {0.75, 0, 1}}, fall, d));
	}
}

/* ---- A point against a triangle that stands still (collision/static_sweep.h) -------------- */

#include "collision/mesh_shape.h"
#include "collision/static_sweep.h"
#include "test_support.h"

static float triangle_distance(vec3 p, vec3 a, vec3 b, vec3 c)
{
	int region;
	return v3_length(v3_sub(p, plait_closest_point_on_triangle(p, a, b, c, &region, NULL)));
}

/* Random paths near random triangles, at three scales: a path that comes within the radius
 * (found by dense sampling) is always reported, no later than the first sample within it; a
 * path reported clear never comes within it. */
Test(ccd_cases, static_triangle_sweep_never_misses)
{
	uint32_t state = 2463534242u;
	float scales[3] = {1e-3f, 1.0f, 100.0f};
	int hits = 0, misses = 0;
	for (int n = 0; n < 6000; ++n) {
		float s = scales[n % 3];
		vec3 a = {test_uniform(&state, -s, s), test_uniform(&state, -s, s), test_uniform(&state, -s, s)};
		vec3 b = {test_uniform(&state, -s, s), test_uniform(&state, -s, s), test_uniform(&state, -s, s)};
		vec3 c = {test_uniform(&state, -s, s), test_uniform(&state, -s, s), test_uniform(&state, -s, s)};
		if (n % 7 == 0) {
			c = v3_lerp(a, b, 0.5f); /* degenerate: a segment */
		}
		vec3 p0 = {test_uniform(&state, -2 * s, 2 * s), test_uniform(&state, -2 * s, 2 * s),
		           test_uniform(&state, -2 * s, 2 * s)};
		vec3 p1 = {test_uniform(&state, -2 * s, 2 * s), test_uniform(&state, -2 * s, 2 * s),
		           test_uniform(&state, -2 * s, 2 * s)};
		float radius = test_uniform(&state, 0.0f, 0.3f * s);
		float toi;
		bool hit = plait_point_path_reaches_triangle(p0, p1, a, b, c, radius, &toi);
		float first_within = 2.0f, smallest = INFINITY;
		for (int k = 0; k <= 4000; ++k) {
			float t = (float)k / 4000.0f;
			float d = triangle_distance(v3_lerp(p0, p1, t), a, b, c);
			smallest = fminf(smallest, d);
			if (d <= radius && first_within > 1.0f) {
				first_within = t;
			}
		}
		if (first_within <= 1.0f) {
			cr_assert(hit, "case %d: the path comes within %g of the triangle (radius %g) but no hit", n,
			          (double)smallest, (double)radius);
			cr_assert_leq(toi, first_within + 1e-6f, "case %d: toi %g after the first touch %g", n,
			              (double)toi, (double)first_within);
			++hits;
		} else if (!hit) {
			cr_assert_gt(smallest, radius, "case %d", n);
			++misses;
		}
	}
	cr_log_info("static sweeps: %d touching, %d clear", hits, misses);
	cr_assert_gt(hits, 500);
	cr_assert_gt(misses, 500);
}

/* The cases that make the general test slow: a point sliding along a face at exactly the
 * radius, grazing an edge, and piercing the face at speed. */
Test(ccd_cases, static_triangle_sweep_grazing_and_piercing)
{
	vec3 a = {0.0f, 0.0f, 0.0f}, b = {1.0f, 0.0f, 0.0f}, c = {0.0f, 0.0f, 1.0f};
	float toi;
	/* Sliding at the radius: touching from the start. */
	cr_assert(plait_point_path_reaches_triangle(v3(0.1f, 0.01f, 0.1f), v3(0.3f, 0.01f, 0.2f), a, b, c, 0.01f,
	                                            &toi));
	cr_assert_eq(toi, 0.0f);
	/* Sliding just above it: clear. */
	cr_assert(!plait_point_path_reaches_triangle(v3(0.1f, 0.0102f, 0.1f), v3(0.3f, 0.0102f, 0.2f), a, b, c,
	                                             0.01f, &toi));
	/* Descending onto it: the touch at y = 0.01 comes at t = 0.9 (y from 0.1 to 0). */
	cr_assert(
	    plait_point_path_reaches_triangle(v3(0.2f, 0.1f, 0.2f), v3(0.2f, 0.0f, 0.2f), a, b, c, 0.01f, &toi));
	cr_assert(toi <= 0.9f && toi > 0.899f, "toi %g", (double)toi);
	/* At 1000 m/s through it, zero radius: no tunnelling. */
	cr_assert(
	    plait_point_path_reaches_triangle(v3(0.2f, 1.0f, 0.2f), v3(0.2f, -1.0f, 0.2f), a, b, c, 0.0f, &toi));
	cr_assert(toi <= 0.5f && toi > 0.499f, "toi %g", (double)toi);
	/* Past an edge at the radius. */
	cr_assert(plait_point_path_reaches_triangle(v3(-1.0f, 0.0f, -0.01f), v3(2.0f, 0.0f, -0.01f), a, b, c,
	                                            0.01f, &toi));
	cr_assert(!plait_point_path_reaches_triangle(v3(-1.0f, 0.0f, -0.0102f), v3(2.0f, 0.0f, -0.0102f), a, b, c,
	                                             0.01f, &toi));
}
