/* Conservative continuous collision detection by inclusion over the space-time parameter box.
 *
 * Both queries reduce to one function of three parameters x = (t, u, v),
 *   F(t, u, v) = E(t) + u G(t) + v H(t),   E, G, H linear in t,
 * the vector between the two moving points the parameters pick (vertex minus triangle point, or
 * point on edge a minus point on edge b). The primitives come within distance d at time t iff
 * |F(t, u, v)| <= d for some (u, v) in the domain (the unit square, or the triangle u + v <= 1).
 * F is multilinear, so over a box of parameters its values lie in the convex hull of its eight
 * corner values. The search splits boxes depth first, earliest time first, discards boxes whose
 * hull provably stays farther than d from the origin, and certifies contacts where it can.
 * docs/ccd.md gives the reasoning behind each error bound. */
#include "collision/ccd.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

enum { CCD_T, CCD_U, CCD_V };

/* Unit roundoff of binary64: each +, -, * result is the exact result times (1 + delta),
 * |delta| <= this, as long as nothing underflows. */
#define CCD_ROUNDOFF (0.5 * DBL_EPSILON)
/* Added to every error bound so that gradual underflow (an absolute error of at most 2^-1075 per
 * operation, amplified by at most 2^250 through later products) is covered too. */
#define CCD_UNDERFLOW_SLACK 0x1p-800
/* Inputs are limited so that no product below can overflow. */
#define CCD_MAX_COORDINATE 0x1p100
/* The depth-first stack grows by at most one box per split; splits are bounded by the widths. */
#define CCD_STACK_CAPACITY 512
/* Work limit per query: boxes examined before the query is answered conservatively. */
#define CCD_BOX_BUDGET 20000
/* Boxes are not split below this width in u and v (this fraction of max_time in t): a contact that
 * cannot be ruled out at that size is reported. */
#define CCD_MIN_WIDTH 0x1p-36
#define CCD_NEWTON_ITERATIONS 8
/* Half-width in u and v of the box that certifies a root, unless rounding needs more. */
#define CCD_CERTIFY_RADIUS 0x1p-24
/* With a thickness d, near misses within d (1 + this) may be reported as contacts. */
#define CCD_DISTANCE_SLACK 0x1p-10

typedef struct ccd_problem {
	/* F at t = s is e[s] + u g[s] + v h[s]; F(t) = F(0) + t (F(1) - F(0)). */
	double e[2][3], g[2][3], h[2][3];
	/* Bound on the rounding error of a computed F component at any point of the domain. */
	double value_error[3];
	/* A computed F component beyond +-value_limit means the exact one is beyond +-d. */
	double value_limit[3];
	/* Bernstein coefficients on [0, 1] of the cubic det(G(t), H(t), E(t)). */
	double cubic[4];
	/* A computed blossom value of the cubic beyond +-cubic_limit means no contact then (d = 0). */
	double cubic_limit;
	/* With d > 0, the band is d |n(t)| over the interval: n = G x H has Bernstein coefficients
	 * normal[i]; normal_error bounds the error of the norm of any computed blossom of them, and
	 * blossom_error that of the cubic's. */
	double normal[3][3];
	double normal_error, blossom_error;
	double distance;
	double tolerance;
	double max_time;
	/* Vertex-face: (u, v) ranges over the triangle u + v <= 1 instead of the unit square. */
	bool triangle_domain;
} ccd_problem;

/* A box of parameters [lo, hi] in (t, u, v). */
typedef struct ccd_box {
	double lo[3], hi[3];
} ccd_box;

/* F at sample points of a box whose hull holds F over the box: the eight corners (bit 0 of the
 * index selects the upper end in t, bit 1 in u, bit 2 in v), or for a vertex-face box crossing the
 * triangle's slanted side, the corners of the part inside the triangle at both times. (A struct so
 * that const pointers to it need no casts in C11.) */
typedef struct ccd_samples {
	double f[10][3];
	double time[10];
	double u[10], v[10];
	/* The sample lies in the domain (a corner beyond the slanted side does not). */
	bool inside[10];
	int count;
} ccd_samples;

/* A 3x3 matrix stored as three vectors (columns or rows, as named). */
typedef struct ccd_matrix {
	double v[3][3];
} ccd_matrix;

/* A face of the parameter domain, as a query of its own: a point against a moving segment,
 * F = e + w h with w in [0, 1] stored as the problem's v (its g is zero). On the face, the main
 * query's parameter `pinned` is fixed at `at` and `follows` moves with w; pinned = -1 marks the
 * triangle's slanted side u + v = 1, where w is v. */
typedef struct ccd_face {
	ccd_problem problem;
	int pinned, follows;
	double at;
} ccd_face;

/* A flat query: all four points share one coordinate for the whole step (a cloth lying in a plane
 * y = const), so that component of F vanishes identically, the contact set is a curve, and its
 * earliest point lies on a face of the domain, at t = 0, or where the primitives are parallel. */
typedef struct ccd_flat {
	int zero_component;
	ccd_face faces[4];
	int face_count;
} ccd_flat;

typedef struct ccd_search {
	ccd_box stack[CCD_STACK_CAPACITY];
	int count;
	/* Every contact not yet ruled out happens at or after this time. */
	double cutoff;
	bool hit;
	int budget;
	/* Faces for certifying a flat query's contacts, NULL otherwise. */
	const ccd_flat *flat;
} ccd_search;

/* Plain comparisons: unlike fmin and fmax these inline, and no NaN can reach them (inputs are
 * range-checked). */
static inline double ccd_min(double a, double b)
{
	return a < b ? a : b;
}
static inline double ccd_max(double a, double b)
{
	return a > b ? a : b;
}

static void ccd_subtract(const double a[3], const double b[3], double out[3])
{
	for (int k = 0; k < 3; k++)
		out[k] = a[k] - b[k];
}

static double ccd_dot(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void ccd_cross(const double a[3], const double b[3], double out[3])
{
	out[0] = a[1] * b[2] - a[2] * b[1];
	out[1] = a[2] * b[0] - a[0] * b[2];
	out[2] = a[0] * b[1] - a[1] * b[0];
}

/* The cross product with |.| on every term and + for -: what its rounding error scales with. */
static void ccd_abs_cross(const double a[3], const double b[3], double out[3])
{
	out[0] = fabs(a[1] * b[2]) + fabs(a[2] * b[1]);
	out[1] = fabs(a[2] * b[0]) + fabs(a[0] * b[2]);
	out[2] = fabs(a[0] * b[1]) + fabs(a[1] * b[0]);
}

static void ccd_abs(const double a[3], double out[3])
{
	for (int k = 0; k < 3; k++)
		out[k] = fabs(a[k]);
}

static double ccd_norm(const double a[3])
{
	return sqrt(ccd_dot(a, a));
}

static bool ccd_same_point(const double a[3], const double b[3])
{
	return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

static bool ccd_motion_in_range(const plait_ccd_motion *motion)
{
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++) {
			if (!(fabs(motion->start[i][k]) <= CCD_MAX_COORDINATE &&
			      fabs(motion->end[i][k]) <= CCD_MAX_COORDINATE))
				return false;
		}
	}
	return true;
}

/* F at (t0, u, v) and (t1, u, v). Every F value that a decision rests on is computed here, in exactly
 * the order the bound of ccd_set_value_bounds assumes. */
static void ccd_values_at(const ccd_problem *p, double u, double v, double t0, double t1, double f0[3],
                          double f1[3])
{
	for (int k = 0; k < 3; k++) {
		double start = p->e[0][k] + u * p->g[0][k] + v * p->h[0][k];
		double motion = (p->e[1][k] + u * p->g[1][k] + v * p->h[1][k]) - start;
		f0[k] = start + t0 * motion;
		f1[k] = start + t1 * motion;
	}
}

static void ccd_add_samples(const ccd_problem *p, const ccd_box *box, double u, double v,
                            ccd_samples *samples)
{
	int i = samples->count;
	ccd_values_at(p, u, v, box->lo[CCD_T], box->hi[CCD_T], samples->f[i], samples->f[i + 1]);
	samples->time[i] = box->lo[CCD_T];
	samples->time[i + 1] = box->hi[CCD_T];
	samples->u[i] = samples->u[i + 1] = u;
	samples->v[i] = samples->v[i + 1] = v;
	/* u and v are dyadic split points, so u + v is exact. */
	samples->inside[i] = samples->inside[i + 1] = !p->triangle_domain || u + v <= 1.0;
	samples->count += 2;
}

static void ccd_corner_values(const ccd_problem *p, const ccd_box *box, ccd_samples *corners)
{
	corners->count = 0;
	for (int j = 0; j < 4; j++)
		ccd_add_samples(p, box, (j & 1) ? box->hi[CCD_U] : box->lo[CCD_U],
		                (j & 2) ? box->hi[CCD_V] : box->lo[CCD_V], corners);
}

static bool ccd_box_crosses_slanted_side(const ccd_problem *p, const ccd_box *box)
{
	return p->triangle_domain && box->hi[CCD_U] + box->hi[CCD_V] > 1.0;
}

/* The part of the box's (u, v) square inside the triangle is the hull of (u0, v0), the two ends of
 * its sides along u = u0 and v = v0, and the two points where the slanted side leaves the square
 * (some of these coincide). At a fixed time F is affine in (u, v), so over that part it lies in the
 * hull of its values there; 1 - u and 1 - v are exact for dyadic u, v. */
static void ccd_clipped_values(const ccd_problem *p, const ccd_box *box, ccd_samples *samples)
{
	double u0 = box->lo[CCD_U], v0 = box->lo[CCD_V];
	double u_end = ccd_min(box->hi[CCD_U], 1.0 - v0), v_end = ccd_min(box->hi[CCD_V], 1.0 - u0);
	samples->count = 0;
	ccd_add_samples(p, box, u0, v0, samples);
	ccd_add_samples(p, box, u_end, v0, samples);
	ccd_add_samples(p, box, u0, v_end, samples);
	ccd_add_samples(p, box, u_end, 1.0 - u_end, samples);
	ccd_add_samples(p, box, 1.0 - v_end, v_end, samples);
}

/* A corner value has rounding depth 7 counted from the exact differences of input points (one
 * rounding for the difference, then u*g, +, v*h, end - start, t*(), +), and its terms' absolute
 * values sum to at most 2 M0 + M1 with M_s = |e_s| + |g_s| + |h_s|, since t, u, v <= 1. The standard
 * bound gamma_7 (2 M0 + M1), gamma_7 < 7.01 u, is rounded up to 9 u to also cover the rounding of M
 * itself and of the inexact differences e, g, h. */
static void ccd_set_value_bounds(ccd_problem *p)
{
	for (int k = 0; k < 3; k++) {
		double m0 = fabs(p->e[0][k]) + fabs(p->g[0][k]) + fabs(p->h[0][k]);
		double m1 = fabs(p->e[1][k]) + fabs(p->g[1][k]) + fabs(p->h[1][k]);
		p->value_error[k] = 9.0 * CCD_ROUNDOFF * (2.0 * m0 + m1) + CCD_UNDERFLOW_SLACK;
		/* fl(d + err) may round down; the factor (1 + 4u) more than makes up for it. */
		p->value_limit[k] = (p->distance + p->value_error[k]) * (1.0 + 4.0 * CCD_ROUNDOFF);
	}
}

/* The cubic c(t) = det(G(t), H(t), E(t)) vanishes wherever F(t, u, v) = 0 (then E, G, H are
 * dependent), and |c(t)| = |n . F| <= |n| d with n = G x H wherever |F| <= d. Its Bernstein
 * coefficients follow from multilinearity of det in its columns. */
static void ccd_set_cubic(ccd_problem *p)
{
	double n00[3], n01[3], n10[3], n11[3], mixed[3];
	ccd_cross(p->g[0], p->h[0], n00);
	ccd_cross(p->g[0], p->h[1], n01);
	ccd_cross(p->g[1], p->h[0], n10);
	ccd_cross(p->g[1], p->h[1], n11);
	for (int k = 0; k < 3; k++)
		mixed[k] = n10[k] + n01[k];

	p->cubic[0] = ccd_dot(n00, p->e[0]);
	p->cubic[1] = (ccd_dot(mixed, p->e[0]) + ccd_dot(n00, p->e[1])) / 3.0;
	p->cubic[2] = (ccd_dot(n11, p->e[0]) + ccd_dot(mixed, p->e[1])) / 3.0;
	p->cubic[3] = ccd_dot(n11, p->e[1]);

	double a00[3], a01[3], a10[3], a11[3], amixed[3], ae0[3], ae1[3];
	ccd_abs_cross(p->g[0], p->h[0], a00);
	ccd_abs_cross(p->g[0], p->h[1], a01);
	ccd_abs_cross(p->g[1], p->h[0], a10);
	ccd_abs_cross(p->g[1], p->h[1], a11);
	ccd_abs(p->e[0], ae0);
	ccd_abs(p->e[1], ae1);
	for (int k = 0; k < 3; k++)
		amixed[k] = a10[k] + a01[k];
	double magnitude = ccd_max(
	    ccd_max(ccd_dot(a00, ae0), ccd_dot(a11, ae1)),
	    ccd_max(ccd_dot(amixed, ae0) + ccd_dot(a00, ae1), ccd_dot(a11, ae0) + ccd_dot(amixed, ae1)) / 3.0);

	/* Rounding depth 9 (difference, product, cross, mixed sum, product, two adds, sum, /3): gamma_9
	 * < 9.01 u, rounded up to 12 u for the rounding of the magnitude itself. */
	double coefficient_error = 12.0 * CCD_ROUNDOFF * magnitude + CCD_UNDERFLOW_SLACK;
	double largest = 0.0;
	for (int i = 0; i < 4; i++)
		largest = ccd_max(largest, fabs(p->cubic[i]));
	largest += coefficient_error;
	/* Three de Casteljau levels, each a convex combination adding at most 5.01 u times the largest
	 * value and passing earlier errors on undamped. */
	double blossom_error = coefficient_error + 16.0 * CCD_ROUNDOFF * largest;

	p->blossom_error = blossom_error;
	p->cubic_limit = blossom_error * (1.0 + 8.0 * CCD_ROUNDOFF) + CCD_UNDERFLOW_SLACK;

	/* n's Bernstein coefficients n00, mixed / 2, n11, each computed within 5 u of its absolute-value
	 * version (at most 4 roundings); two de Casteljau levels add at most 10.02 u of the largest
	 * norm per component, so 18 u of it in norm. */
	for (int k = 0; k < 3; k++) {
		p->normal[0][k] = n00[k];
		p->normal[1][k] = 0.5 * mixed[k];
		p->normal[2][k] = n11[k];
	}
	double largest_normal = ccd_max(ccd_max(ccd_norm(n00), ccd_norm(n11)), 0.5 * ccd_norm(mixed));
	double coefficient_normal_error =
	    5.0 * CCD_ROUNDOFF * ccd_max(ccd_max(ccd_norm(a00), ccd_norm(a11)), 0.5 * ccd_norm(amixed));
	p->normal_error =
	    coefficient_normal_error + 18.0 * CCD_ROUNDOFF * (largest_normal + coefficient_normal_error);
}

static void ccd_problem_init(ccd_problem *p, const plait_ccd_motion *motion, bool vertex_face,
                             double distance, double tolerance, double max_time)
{
	for (int s = 0; s < 2; s++) {
		const double(*x)[3] = s == 0 ? motion->start : motion->end;
		if (vertex_face) {
			/* F = vertex - (a + u (b - a) + v (c - a)) */
			ccd_subtract(x[0], x[1], p->e[s]);
			ccd_subtract(x[1], x[2], p->g[s]);
			ccd_subtract(x[1], x[3], p->h[s]);
		} else {
			/* F = (a0 + u (a1 - a0)) - (b0 + v (b1 - b0)) */
			ccd_subtract(x[0], x[2], p->e[s]);
			ccd_subtract(x[1], x[0], p->g[s]);
			ccd_subtract(x[2], x[3], p->h[s]);
		}
	}
	p->distance = distance > 0.0 ? distance : 0.0;
	p->tolerance = tolerance > DBL_EPSILON ? tolerance : DBL_EPSILON;
	p->max_time = max_time > 0.0 ? ccd_min(max_time, 1.0) : 0.0;
	p->triangle_domain = vertex_face;
	ccd_set_value_bounds(p);
	ccd_set_cubic(p);
}

/* The face query of point `point` against the segment from point `from` to point `to`:
 * F = x_point - (x_from + w (x_to - x_from)), e = x_point - x_from, h = x_from - x_to. */
static void ccd_face_init(ccd_face *face, const ccd_problem *main, const plait_ccd_motion *motion, int point,
                          int from, int to)
{
	ccd_problem *p = &face->problem;
	for (int s = 0; s < 2; s++) {
		const double(*x)[3] = s == 0 ? motion->start : motion->end;
		ccd_subtract(x[point], x[from], p->e[s]);
		ccd_subtract(x[from], x[to], p->h[s]);
		for (int k = 0; k < 3; k++)
			p->g[s][k] = 0.0;
	}
	p->distance = 0.0;
	p->tolerance = main->tolerance;
	p->max_time = main->max_time;
	p->triangle_domain = false;
	ccd_set_value_bounds(p);
	/* Only the certificates use a face; its cubic stays unused. */
	for (int i = 0; i < 4; i++)
		p->cubic[i] = 0.0;
	p->cubic_limit = INFINITY;
}

static void ccd_add_face(ccd_flat *flat, const ccd_problem *main, const plait_ccd_motion *motion, int point,
                         int from, int to, int pinned, double at, int follows)
{
	ccd_face *face = &flat->faces[flat->face_count++];
	ccd_face_init(face, main, motion, point, from, to);
	face->pinned = pinned;
	face->at = at;
	face->follows = follows;
}

/* Sets up the faces when exactly one component of F vanishes identically (its differences are
 * exactly zero, which happens exactly when the inputs agree) and the query tests touching; with a
 * thickness the close-corner certificate already works. Returns false for other queries. */
static bool ccd_flat_init(ccd_flat *flat, const ccd_problem *p, const plait_ccd_motion *motion,
                          bool vertex_face)
{
	flat->zero_component = -1;
	flat->face_count = 0;
	int zeros = 0;
	for (int k = 0; k < 3; k++) {
		bool zero = true;
		for (int s = 0; s < 2; s++)
			zero = zero && p->e[s][k] == 0.0 && p->g[s][k] == 0.0 && p->h[s][k] == 0.0;
		if (zero) {
			zeros++;
			flat->zero_component = k;
		}
	}
	if (zeros != 1 || p->distance > 0.0)
		return false;
	if (vertex_face) {
		ccd_add_face(flat, p, motion, 0, 1, 3, CCD_U, 0.0, CCD_V); /* edge a-c */
		ccd_add_face(flat, p, motion, 0, 1, 2, CCD_V, 0.0, CCD_U); /* edge a-b */
		ccd_add_face(flat, p, motion, 0, 2, 3, -1, 1.0, CCD_V);    /* edge b-c */
	} else {
		ccd_add_face(flat, p, motion, 0, 2, 3, CCD_U, 0.0, CCD_V); /* a0 against edge b */
		ccd_add_face(flat, p, motion, 1, 2, 3, CCD_U, 1.0, CCD_V); /* a1 against edge b */
		ccd_add_face(flat, p, motion, 2, 0, 1, CCD_V, 0.0, CCD_U); /* b0 against edge a */
		ccd_add_face(flat, p, motion, 3, 0, 1, CCD_V, 1.0, CCD_U); /* b1 against edge a */
	}
	return true;
}

/* x + s (y - x) */
static double ccd_lerp(double x, double y, double s)
{
	return x + s * (y - x);
}

/* Bernstein coefficients of the cubic on [a, b] (within [0, 1]): the blossom values c(a,a,a),
 * c(a,a,b), c(a,b,b), c(b,b,b), by de Casteljau steps at a and b. */
static void ccd_cubic_on(const ccd_problem *p, double a, double b, double out[4])
{
	const double *c = p->cubic;
	double la[3], lb[3];
	for (int i = 0; i < 3; i++) {
		la[i] = ccd_lerp(c[i], c[i + 1], a);
		lb[i] = ccd_lerp(c[i], c[i + 1], b);
	}
	double aa0 = ccd_lerp(la[0], la[1], a), aa1 = ccd_lerp(la[1], la[2], a);
	double ab0 = ccd_lerp(la[0], la[1], b), ab1 = ccd_lerp(la[1], la[2], b);
	double bb0 = ccd_lerp(lb[0], lb[1], b), bb1 = ccd_lerp(lb[1], lb[2], b);
	out[0] = ccd_lerp(aa0, aa1, a);
	out[1] = ccd_lerp(aa0, aa1, b);
	out[2] = ccd_lerp(ab0, ab1, b);
	out[3] = ccd_lerp(bb0, bb1, b);
}

/* Where the segment from (i, y_i) to (j, y_j) meets the level y (between them), in units of i. */
static double ccd_crossing(int i, double yi, int j, double yj, double y)
{
	return i + (j - i) * ((y - yi) / (yj - yi));
}

/* Narrows [*a, *b] to a subinterval holding every t in it with |c(t)| <= band (Bezier clipping): the
 * cubic lies in the convex hull of its control points (a + i (b - a) / 3, beta_i), so it can only
 * reach the band where that hull does. Returns false when it nowhere does: no contact then. */
/* With d > 0: an upper bound of d |n(t)| for t in [a, b]. |n(t)| is at most the largest norm of the
 * Bernstein coefficients of n on [a, b] (convex hull), its blossom values n(a,a), n(a,b), n(b,b). */
static double ccd_band(const ccd_problem *p, double a, double b)
{
	double largest = 0.0;
	for (int i = 0; i < 3; i++) {
		double blossom[3];
		for (int k = 0; k < 3; k++) {
			double first = ccd_lerp(p->normal[0][k], p->normal[1][k], i == 2 ? b : a);
			double second = ccd_lerp(p->normal[1][k], p->normal[2][k], i == 2 ? b : a);
			blossom[k] = ccd_lerp(first, second, i == 0 ? a : b);
		}
		largest = ccd_max(largest, ccd_norm(blossom));
	}
	/* The norm's own rounding (square root included) is below 4u. */
	return p->distance * (largest * (1.0 + 4.0 * CCD_ROUNDOFF) + p->normal_error) *
	       (1.0 + 4.0 * CCD_ROUNDOFF);
}

static bool ccd_clip_time(const ccd_problem *p, double *a, double *b)
{
	double beta[4];
	ccd_cubic_on(p, *a, *b, beta);
	double limit = p->distance > 0.0 ? (ccd_band(p, *a, *b) + p->blossom_error) * (1.0 + 8.0 * CCD_ROUNDOFF) +
	                                       CCD_UNDERFLOW_SLACK
	                                 : p->cubic_limit;
	/* The hull meets the band between the extreme abscissas of the control points inside it and of
	 * the crossings of the segments between control points with the band's edges. */
	double lo = 4.0, hi = -1.0;
	for (int i = 0; i < 4; i++) {
		if (fabs(beta[i]) <= limit) {
			lo = ccd_min(lo, i);
			hi = ccd_max(hi, i);
		}
		for (int j = i + 1; j < 4; j++) {
			for (int side = -1; side <= 1; side += 2) {
				double y = side * limit;
				if ((beta[i] < y && beta[j] > y) || (beta[i] > y && beta[j] < y)) {
					double s = ccd_crossing(i, beta[i], j, beta[j], y);
					lo = ccd_min(lo, s);
					hi = ccd_max(hi, s);
				}
			}
		}
	}
	if (lo > hi)
		return false;
	/* The abscissas carry a few roundings each; a margin far above them keeps the clip
	 * conservative. */
	double width = *b - *a, margin = width * 0x1p-40 + 8.0 * CCD_ROUNDOFF * *b;
	double new_a = *a + width * (lo / 3.0) - margin, new_b = *a + width * (hi / 3.0) + margin;
	*a = ccd_max(*a, new_a);
	*b = ccd_min(*b, new_b);
	return true;
}

/* True when the hull of the corner values provably stays farther than d from the origin, along a
 * coordinate axis or along the box's mean value. */
static bool ccd_corners_excluded(const ccd_problem *p, const ccd_samples *corners)
{
	const double(*f)[3] = corners->f;
	double mean[3], largest[3];
	for (int k = 0; k < 3; k++) {
		double lo = f[0][k], hi = f[0][k], sum = f[0][k];
		for (int c = 1; c < corners->count; c++) {
			lo = ccd_min(lo, f[c][k]);
			hi = ccd_max(hi, f[c][k]);
			sum += f[c][k];
		}
		if (lo > p->value_limit[k] || hi < -p->value_limit[k])
			return true;
		mean[k] = sum;
		largest[k] = ccd_max(-lo, hi);
	}

	/* Along w: w . F >= w . F~ - sum |w_k| err_k - (dot product rounding, below 4u sum |w_k| |F~_k|),
	 * and |F| >= w . F / |w|. */
	double slack = 0.0;
	for (int k = 0; k < 3; k++)
		slack += fabs(mean[k]) * (p->value_error[k] + 4.0 * CCD_ROUNDOFF * largest[k]);
	double reach = p->distance > 0.0 ? p->distance * ccd_norm(mean) * (1.0 + 8.0 * CCD_ROUNDOFF) : 0.0;
	double limit = (reach + slack) * (1.0 + 8.0 * CCD_ROUNDOFF) + CCD_UNDERFLOW_SLACK;
	for (int c = 0; c < corners->count; c++) {
		if (!(ccd_dot(mean, f[c]) > limit))
			return false;
	}
	return true;
}

static bool ccd_box_outside_domain(const ccd_problem *p, const ccd_box *box)
{
	/* Split points of [0, 1] are dyadic with at most 36 bits, so this sum is exact. */
	return p->triangle_domain && box->lo[CCD_U] + box->lo[CCD_V] > 1.0;
}

/* F and its Jacobian columns dF/dt, dF/du, dF/dv at x (estimates: only Newton uses them). */
static void ccd_value_and_jacobian(const ccd_problem *p, const double x[3], double f[3], ccd_matrix *jacobian)
{
	double(*columns)[3] = jacobian->v;
	double t = x[CCD_T], u = x[CCD_U], v = x[CCD_V];
	for (int k = 0; k < 3; k++) {
		double g = p->g[0][k] + t * (p->g[1][k] - p->g[0][k]);
		double h = p->h[0][k] + t * (p->h[1][k] - p->h[0][k]);
		double start = p->e[0][k] + u * p->g[0][k] + v * p->h[0][k];
		double motion = (p->e[1][k] + u * p->g[1][k] + v * p->h[1][k]) - start;
		f[k] = start + t * motion;
		columns[0][k] = motion;
		columns[1][k] = g;
		columns[2][k] = h;
	}
}

/* Rows of the adjugate of the matrix with the given columns: adjugate * matrix = det * identity. */
static double ccd_adjugate(const ccd_matrix *matrix, ccd_matrix *adjugate)
{
	const double(*columns)[3] = matrix->v;
	double(*rows)[3] = adjugate->v;
	ccd_cross(columns[1], columns[2], rows[0]);
	ccd_cross(columns[2], columns[0], rows[1]);
	ccd_cross(columns[0], columns[1], rows[2]);
	return ccd_dot(columns[0], rows[0]);
}

/* Newton converges quadratically: once a step is below a quarter of the square root of the
 * certification radius, the error left after it is far below that radius. */
static double ccd_newton_settled(const double radius[3])
{
	return 0.25 * sqrt(ccd_min(radius[CCD_T], ccd_min(radius[CCD_U], radius[CCD_V])));
}

/* Newton's method for F(x) = 0 from x. Fails if it does not settle or wanders out of the region (a
 * root elsewhere is another box's business). Leaves the adjugate of the last Jacobian in rows. */
static bool ccd_newton(const ccd_problem *p, const ccd_box *region, double settled, double x[3],
                       ccd_matrix *adjugate, double *det)
{
	for (int iteration = 0; iteration < CCD_NEWTON_ITERATIONS; iteration++) {
		double f[3];
		ccd_matrix jacobian;
		ccd_value_and_jacobian(p, x, f, &jacobian);
		*det = ccd_adjugate(&jacobian, adjugate);
		if (!(fabs(*det) > 0.0))
			return false;
		double inverse = 1.0 / *det, change = 0.0;
		for (int i = 0; i < 3; i++) {
			double step = ccd_dot(adjugate->v[i], f) * inverse;
			x[i] -= step;
			change = ccd_max(change, fabs(step));
			if (!(x[i] >= region->lo[i] && x[i] <= region->hi[i]))
				return false;
		}
		if (change < settled)
			return true;
	}
	return false;
}

/* The Poincare-Miranda theorem: if each G_i = (Y F)_i has one strict sign on the face x_i = lo and
 * the other on x_i = hi, G has a zero in the box, and so does F when Y is invertible. G_i is
 * multilinear like F, so its extremes over a face are at the face's four corners. */
static bool ccd_miranda(const ccd_problem *p, const ccd_box *box, const ccd_matrix *preconditioner)
{
	const double(*rows)[3] = preconditioner->v;
	ccd_samples corners;
	ccd_corner_values(p, box, &corners);
	double(*f)[3] = corners.f;
	double largest[3] = {0.0, 0.0, 0.0};
	for (int c = 0; c < 8; c++) {
		for (int k = 0; k < 3; k++)
			largest[k] = ccd_max(largest[k], fabs(f[c][k]));
	}
	for (int i = 0; i < 3; i++) {
		/* |G~_i - G_i| <= sum_k |Y_ik| (err_k + dot product rounding of 4u |F~_k|). */
		double error = 0.0;
		for (int k = 0; k < 3; k++)
			error += fabs(rows[i][k]) * (p->value_error[k] + 4.0 * CCD_ROUNDOFF * largest[k]);
		error = error * (1.0 + 8.0 * CCD_ROUNDOFF) + CCD_UNDERFLOW_SLACK;
		bool rising = true, falling = true;
		for (int c = 0; c < 8; c++) {
			double g = ccd_dot(rows[i], f[c]);
			bool upper = (c >> i) & 1;
			rising = rising && (upper ? g > error : g < -error);
			falling = falling && (upper ? g < -error : g > error);
		}
		if (!rising && !falling)
			return false;
	}
	/* Y is invertible when its determinant is certainly nonzero (rounding depth 5, gamma_5 < 8u). */
	double cross[3], abs_cross[3], abs_row[3];
	ccd_cross(rows[1], rows[2], cross);
	ccd_abs_cross(rows[1], rows[2], abs_cross);
	ccd_abs(rows[0], abs_row);
	return fabs(ccd_dot(rows[0], cross)) >
	       8.0 * CCD_ROUNDOFF * ccd_dot(abs_row, abs_cross) + CCD_UNDERFLOW_SLACK;
}

/* Room around x inside the domain in dimension i (u and v share the triangle's slanted side). */
static double ccd_room(const ccd_problem *p, const double x[3], int i)
{
	double upper = i == CCD_T ? p->max_time : 1.0;
	double room = ccd_min(x[i], upper - x[i]);
	if (i != CCD_T && p->triangle_domain)
		room = ccd_min(room, 0.5 * (1.0 - x[CCD_U] - x[CCD_V]));
	return room;
}

static bool ccd_box_inside_domain(const ccd_problem *p, const ccd_box *box)
{
	if (!(box->lo[CCD_T] >= 0.0 && box->hi[CCD_T] <= p->max_time))
		return false;
	for (int i = CCD_U; i <= CCD_V; i++) {
		if (!(box->lo[i] >= 0.0 && box->hi[i] <= 1.0))
			return false;
	}
	/* fl(u + v) <= 1 - 2u implies u + v < 1. */
	return !p->triangle_domain || box->hi[CCD_U] + box->hi[CCD_V] <= 1.0 - DBL_EPSILON;
}

/* Looks for a zero of F near the box by Newton's method and certifies it with a small Miranda box
 * around the estimate. On success *contact_time is a time at or after that contact. */
static bool ccd_certify_root(const ccd_problem *p, const ccd_box *box, double *contact_time)
{
	/* Newton starts in the middle and may roam a box width beyond the box: farther roots belong to
	 * other boxes. */
	double x[3], det;
	ccd_matrix adjugate;
	ccd_box region;
	for (int i = 0; i < 3; i++) {
		double middle = 0.5 * (box->lo[i] + box->hi[i]), width = box->hi[i] - box->lo[i];
		x[i] = middle;
		region.lo[i] = middle - width;
		region.hi[i] = middle + width;
	}
	double radius[3] = {0.0625 * p->tolerance, CCD_CERTIFY_RADIUS, CCD_CERTIFY_RADIUS};
	if (!ccd_newton(p, &region, ccd_newton_settled(radius), x, &adjugate, &det))
		return false;

	/* The root is uncertain by about the rounding error mapped through the inverse Jacobian; the
	 * box must be a good many times wider than that for the Miranda signs to show, yet fit in the
	 * domain. */
	ccd_box test;
	for (int i = 0; i < 3; i++) {
		double spread = 0.0;
		for (int k = 0; k < 3; k++)
			spread += fabs(adjugate.v[i][k]) * p->value_error[k];
		double needed = 32.0 * spread / fabs(det);
		double r = ccd_max(needed, ccd_min(radius[i], 0.5 * ccd_room(p, x, i)));
		test.lo[i] = x[i] - r;
		test.hi[i] = x[i] + r;
	}
	if (!(test.hi[CCD_T] - test.lo[CCD_T] <= 0.5 * p->tolerance) || !ccd_box_inside_domain(p, &test) ||
	    !ccd_miranda(p, &test, &adjugate))
		return false;
	*contact_time = test.hi[CCD_T];
	return true;
}

/* Newton's method and the Miranda test in the two free dimensions i1, i2 of a box whose third
 * dimension has zero width, on the two components of F other than the one that vanishes
 * identically. Same reasoning as ccd_certify_root with 2x2 matrices: the adjugate of
 * [[a, b], [c, d]] is [[d, -b], [-c, a]]. */
static bool ccd_certify_root_2d(const ccd_problem *p, const ccd_box *box, int i1, int i2, int zero_component,
                                double *contact_time)
{
	int k1 = (zero_component + 1) % 3, k2 = (zero_component + 2) % 3;
	double x[3], y[2][2] = {{0.0, 0.0}, {0.0, 0.0}}, det = 0.0;
	ccd_box region = *box;
	for (int i = 0; i < 3; i++)
		x[i] = 0.5 * (box->lo[i] + box->hi[i]);
	for (int j = 0; j < 2; j++) {
		int i = j == 0 ? i1 : i2;
		double width = box->hi[i] - box->lo[i];
		region.lo[i] -= width;
		region.hi[i] += width;
	}
	double radius[3] = {0.0625 * p->tolerance, CCD_CERTIFY_RADIUS, CCD_CERTIFY_RADIUS};
	double settled = ccd_newton_settled(radius);
	bool converged = false;
	for (int iteration = 0; iteration < CCD_NEWTON_ITERATIONS && !converged; iteration++) {
		double f[3];
		ccd_matrix jacobian;
		ccd_value_and_jacobian(p, x, f, &jacobian);
		double a = jacobian.v[i1][k1], b = jacobian.v[i2][k1], c = jacobian.v[i1][k2], d = jacobian.v[i2][k2];
		det = a * d - b * c;
		if (!(fabs(det) > 0.0))
			return false;
		y[0][0] = d, y[0][1] = -b, y[1][0] = -c, y[1][1] = a;
		double step1 = (y[0][0] * f[k1] + y[0][1] * f[k2]) / det;
		double step2 = (y[1][0] * f[k1] + y[1][1] * f[k2]) / det;
		x[i1] -= step1;
		x[i2] -= step2;
		if (!(x[i1] >= region.lo[i1] && x[i1] <= region.hi[i1] && x[i2] >= region.lo[i2] &&
		      x[i2] <= region.hi[i2]))
			return false;
		converged = ccd_max(fabs(step1), fabs(step2)) < settled;
	}
	if (!converged)
		return false;

	ccd_box test = *box;
	for (int j = 0; j < 2; j++) {
		int i = j == 0 ? i1 : i2;
		double spread = fabs(y[j][0]) * p->value_error[k1] + fabs(y[j][1]) * p->value_error[k2];
		double r = ccd_max(32.0 * spread / fabs(det), ccd_min(radius[i], 0.5 * ccd_room(p, x, i)));
		test.lo[i] = x[i] - r;
		test.hi[i] = x[i] + r;
	}
	if (!(test.hi[CCD_T] - test.lo[CCD_T] <= 0.5 * p->tolerance) || !ccd_box_inside_domain(p, &test))
		return false;

	ccd_samples corners;
	ccd_corner_values(p, &test, &corners);
	double largest1 = 0.0, largest2 = 0.0;
	for (int c = 0; c < 8; c++) {
		largest1 = ccd_max(largest1, fabs(corners.f[c][k1]));
		largest2 = ccd_max(largest2, fabs(corners.f[c][k2]));
	}
	for (int j = 0; j < 2; j++) {
		int i = j == 0 ? i1 : i2;
		/* A two-term dot product rounds by less than 4u of its absolute terms. */
		double error = (fabs(y[j][0]) * (p->value_error[k1] + 4.0 * CCD_ROUNDOFF * largest1) +
		                fabs(y[j][1]) * (p->value_error[k2] + 4.0 * CCD_ROUNDOFF * largest2)) *
		                   (1.0 + 8.0 * CCD_ROUNDOFF) +
		               CCD_UNDERFLOW_SLACK;
		bool rising = true, falling = true;
		for (int c = 0; c < 8; c++) {
			double g = y[j][0] * corners.f[c][k1] + y[j][1] * corners.f[c][k2];
			bool upper = (c >> i) & 1;
			rising = rising && (upper ? g > error : g < -error);
			falling = falling && (upper ? g < -error : g > error);
		}
		if (!rising && !falling)
			return false;
	}
	/* Y is invertible when its determinant is certainly nonzero (two products and a difference). */
	double diagonal = y[0][0] * y[1][1], cross = y[0][1] * y[1][0];
	if (!(fabs(diagonal - cross) > 4.0 * CCD_ROUNDOFF * (fabs(diagonal) + fabs(cross)) + CCD_UNDERFLOW_SLACK))
		return false;
	*contact_time = test.hi[CCD_T];
	return true;
}

/* The part of a face inside a box of the main query, as a box of the face's own query. */
static bool ccd_face_box(const ccd_face *face, const ccd_box *box, ccd_box *out)
{
	double lo, hi;
	if (face->pinned >= 0) {
		double side = face->at == 0.0 ? box->lo[face->pinned] : box->hi[face->pinned];
		if (side != face->at)
			return false;
		lo = box->lo[face->follows];
		hi = box->hi[face->follows];
	} else {
		/* The slanted side u + v = 1 at (1 - w, w); u, v are dyadic, so these sums and
		 * differences are exact. */
		if (!(box->lo[CCD_U] + box->lo[CCD_V] <= 1.0 && box->hi[CCD_U] + box->hi[CCD_V] >= 1.0))
			return false;
		lo = ccd_max(box->lo[CCD_V], 1.0 - box->hi[CCD_U]);
		hi = ccd_min(box->hi[CCD_V], 1.0 - box->lo[CCD_U]);
	}
	out->lo[CCD_T] = box->lo[CCD_T];
	out->hi[CCD_T] = box->hi[CCD_T];
	out->lo[CCD_U] = out->hi[CCD_U] = 0.0;
	out->lo[CCD_V] = lo;
	out->hi[CCD_V] = hi;
	return lo <= hi;
}

/* A flat query's contacts in or near the box: overlap at t = 0, or a contact on a face of the
 * domain. Reports the earliest certified one. */
static bool ccd_certify_flat(const ccd_problem *p, const ccd_flat *flat, const ccd_box *box,
                             double *contact_time)
{
	bool found = false;
	double time;
	if (box->lo[CCD_T] == 0.0) {
		ccd_box start = *box;
		start.hi[CCD_T] = 0.0;
		if (ccd_certify_root_2d(p, &start, CCD_U, CCD_V, flat->zero_component, &time)) {
			*contact_time = time;
			return true;
		}
	}
	for (int i = 0; i < flat->face_count; i++) {
		ccd_box face_box;
		if (!ccd_face_box(&flat->faces[i], box, &face_box) ||
		    !ccd_certify_root_2d(&flat->faces[i].problem, &face_box, CCD_T, CCD_V, flat->zero_component,
		                         &time))
			continue;
		*contact_time = found ? ccd_min(*contact_time, time) : time;
		found = true;
	}
	return found;
}

/* True when the exact F at (t, u, v) is certainly shorter than d: its components are within
 * value_error of the computed ones; the rounded square sum gains at most 4u and d * d loses at most
 * u. */
static bool ccd_certainly_within(const ccd_problem *p, const double f[3])
{
	double upper[3];
	for (int k = 0; k < 3; k++)
		upper[k] = fabs(f[k]) + p->value_error[k];
	return ccd_dot(upper, upper) * (1.0 + 8.0 * CCD_ROUNDOFF) <
	       p->distance * p->distance * (1.0 - 4.0 * CCD_ROUNDOFF);
}

/* The earliest s in [0, 1] with |a + s (b - a)| <= r (a root of a quadratic), or a value above 1 if
 * there is none. An estimate: the caller checks the point it leads to. */
static double ccd_first_within(const double a[3], const double b[3], double r)
{
	double d[3];
	ccd_subtract(b, a, d);
	double dd = ccd_dot(d, d), ad = ccd_dot(a, d), excess = ccd_dot(a, a) - r * r;
	if (excess <= 0.0)
		return 0.0;
	double discriminant = ad * ad - dd * excess;
	if (!(dd > 0.0) || !(ad < 0.0) || !(discriminant >= 0.0))
		return 2.0;
	/* The smaller root, in the form that does not cancel. */
	return excess / (-ad + sqrt(discriminant));
}

/* With d > 0: a point of the box inside the domain whose distance is certainly below d is a
 * contact. Along each sampled (u, v) the distance is a quadratic in t, so its first time within d
 * is solved for (slightly inside, to leave room for rounding) and the point then checked. Returns
 * the earliest certified time. */
static bool ccd_certify_close_sample(const ccd_problem *p, const ccd_samples *samples, double *contact_time)
{
	bool found = false;
	for (int c = 0; c + 1 < samples->count; c += 2) {
		if (!samples->inside[c])
			continue;
		double s = ccd_first_within(samples->f[c], samples->f[c + 1], p->distance * (1.0 - 0x1p-20));
		if (!(s <= 1.0))
			continue;
		double t0 = samples->time[c], t1 = samples->time[c + 1], t = ccd_min(t0 + s * (t1 - t0), t1);
		double f[3], unused[3];
		ccd_values_at(p, samples->u[c], samples->v[c], t, t, f, unused);
		if (!ccd_certainly_within(p, f)) {
			t = t1;
			if (!ccd_certainly_within(p, samples->f[c + 1]))
				continue;
		}
		*contact_time = found ? ccd_min(*contact_time, t) : t;
		found = true;
	}
	return found;
}

/* With a thickness, proving that nothing came within d just before a contact can take ever finer
 * boxes around the point where the distance first reaches d (near-tangent approaches). A box that
 * cannot be ruled out, spans at most the tolerance in time and over which F varies by at most
 * slack d / sqrt(3) per component holds a point within d (1 + slack): the mean m of its samples is
 * F at a point of the box, and the failed direction test means some sample c has m . F_c <= d |m|,
 * so |m| <= d + |F_c - m|. Such a box is reported as a contact from its start time on. */
static bool ccd_near_contact(const ccd_problem *p, const ccd_box *box, const ccd_samples *samples)
{
	if (!(p->distance > 0.0) || !(box->hi[CCD_T] - box->lo[CCD_T] <= p->tolerance))
		return false;
	double allowed = CCD_DISTANCE_SLACK * p->distance * 0.57735;
	for (int k = 0; k < 3; k++) {
		double lo = samples->f[0][k], hi = samples->f[0][k];
		for (int c = 1; c < samples->count; c++) {
			lo = ccd_min(lo, samples->f[c][k]);
			hi = ccd_max(hi, samples->f[c][k]);
		}
		if (!(hi - lo <= allowed))
			return false;
	}
	return true;
}

static double ccd_min_width(const ccd_problem *p, int i)
{
	return i == CCD_T ? CCD_MIN_WIDTH * p->max_time : CCD_MIN_WIDTH;
}

/* The dimension along which F changes most over the box, among those still wide enough to split;
 * -1 if none is. */
static int ccd_split_dimension(const ccd_problem *p, const ccd_box *box, const ccd_samples *corners)
{
	const double(*f)[3] = corners->f;
	int best_dimension = -1;
	double best_change = -1.0;
	for (int i = 0; i < 3; i++) {
		double middle = 0.5 * (box->lo[i] + box->hi[i]);
		if (!(box->hi[i] - box->lo[i] > ccd_min_width(p, i)) || !(middle > box->lo[i] && middle < box->hi[i]))
			continue;
		double change = 0.0;
		for (int c = 0; c < 8; c++) {
			if ((c >> i) & 1)
				continue;
			for (int k = 0; k < 3; k++)
				change = ccd_max(change, fabs(f[c | (1 << i)][k] - f[c][k]));
		}
		if (change > best_change) {
			best_change = change;
			best_dimension = i;
		}
	}
	return best_dimension;
}

static void ccd_push(ccd_search *search, const ccd_box *box)
{
	search->stack[search->count++] = *box;
}

/* Pushes the two halves of the box, the earlier one in t on top so it is searched first. */
static void ccd_split(ccd_search *search, const ccd_box *box, int i)
{
	double middle = 0.5 * (box->lo[i] + box->hi[i]);
	ccd_box lower = *box, upper = *box;
	lower.hi[i] = middle;
	upper.lo[i] = middle;
	ccd_push(search, &upper);
	ccd_push(search, &lower);
}

/* A contact at or before contact_time exists: the first contact is then at most that late, and no
 * box needs searching past contact_time - tolerance. */
static void ccd_record_contact(const ccd_problem *p, ccd_search *search, double contact_time)
{
	search->hit = true;
	search->cutoff = ccd_min(search->cutoff, contact_time - p->tolerance);
}

/* A box that might hold a contact and cannot be searched further: report it conservatively. */
static void ccd_record_unresolved(ccd_search *search, double start_time)
{
	search->hit = true;
	search->cutoff = ccd_min(search->cutoff, start_time);
}

/* Out of budget or stack space: every box left might hold a contact. */
static void ccd_give_up(ccd_search *search, const ccd_box *box)
{
	for (int i = 0; i < search->count; i++)
		ccd_record_unresolved(search, search->stack[i].lo[CCD_T]);
	ccd_record_unresolved(search, box->lo[CCD_T]);
	search->count = 0;
}

/* True when the box provably holds no contact (its time interval may shrink on the way). Otherwise
 * *judged points at the samples the box was judged by: its corners, or for a box crossing the
 * triangle's slanted side, which also covers points beyond the face, the part inside. */
static bool ccd_ruled_out(const ccd_problem *p, ccd_box *box, ccd_samples *corners, ccd_samples *clipped,
                          const ccd_samples **judged)
{
	if (ccd_box_outside_domain(p, box) || !ccd_clip_time(p, &box->lo[CCD_T], &box->hi[CCD_T]))
		return true;
	ccd_corner_values(p, box, corners);
	if (ccd_corners_excluded(p, corners))
		return true;
	*judged = corners;
	if (ccd_box_crosses_slanted_side(p, box)) {
		ccd_clipped_values(p, box, clipped);
		if (ccd_corners_excluded(p, clipped))
			return true;
		*judged = clipped;
	}
	return false;
}

static bool ccd_certify(const ccd_problem *p, const ccd_search *search, const ccd_box *box,
                        const ccd_samples *judged, double *contact_time)
{
	if (p->distance > 0.0)
		return ccd_certify_close_sample(p, judged, contact_time);
	if (search->flat)
		return ccd_certify_flat(p, search->flat, box, contact_time);
	return ccd_certify_root(p, box, contact_time);
}

/* Looks again at the part of the box before the cutoff a new contact set. A root certificate sits
 * at the contact, so that part usually clips away at once; a close sample of a thick query may be at
 * the box's end, so the box is halved in time to approach the first contact by bisection rather
 * than one tolerance at a time. */
static void ccd_search_before_contact(const ccd_problem *p, ccd_search *search, ccd_box box)
{
	box.hi[CCD_T] = ccd_min(box.hi[CCD_T], search->cutoff);
	if (box.lo[CCD_T] >= box.hi[CCD_T])
		return;
	if (p->distance > 0.0)
		ccd_split(search, &box, CCD_T);
	else
		ccd_push(search, &box);
}

/* Examines one box: discards it, certifies a contact in or near it, or splits it. */
static void ccd_examine(const ccd_problem *p, ccd_search *search, ccd_box box)
{
	/* Later parts of the box no longer matter for the first contact. */
	if (box.lo[CCD_T] >= search->cutoff)
		return;
	box.hi[CCD_T] = ccd_min(box.hi[CCD_T], search->cutoff);
	if (search->budget-- <= 0 || search->count > CCD_STACK_CAPACITY - 2) {
		ccd_give_up(search, &box);
		return;
	}
	ccd_samples corners, clipped;
	const ccd_samples *judged;
	if (ccd_ruled_out(p, &box, &corners, &clipped, &judged))
		return;

	/* A certified contact counts only if it moves the cutoff by at least tolerance / 2, so the same
	 * contact cannot be found over and over. */
	double contact_time = INFINITY;
	if (ccd_certify(p, search, &box, judged, &contact_time) &&
	    contact_time - 0.5 * p->tolerance < search->cutoff) {
		ccd_record_contact(p, search, contact_time);
		ccd_search_before_contact(p, search, box);
		return;
	}

	if (ccd_near_contact(p, &box, judged)) {
		ccd_record_unresolved(search, box.lo[CCD_T]);
		return;
	}
	int i = ccd_split_dimension(p, &box, &corners);
	if (i < 0) {
		ccd_record_unresolved(search, box.lo[CCD_T]);
		return;
	}
	ccd_split(search, &box, i);
}

/* Points that coincide at t = 0 touch at once; numerically that is a corner root no certificate
 * can reach, so it is checked exactly. */
static bool ccd_touching_at_start(const plait_ccd_motion *motion, bool vertex_face)
{
	const double(*x)[3] = motion->start;
	if (vertex_face)
		return ccd_same_point(x[0], x[1]) || ccd_same_point(x[0], x[2]) || ccd_same_point(x[0], x[3]);
	return ccd_same_point(x[0], x[2]) || ccd_same_point(x[0], x[3]) || ccd_same_point(x[1], x[2]) ||
	       ccd_same_point(x[1], x[3]);
}

static bool ccd_run(const plait_ccd_motion *motion, bool vertex_face, double minimum_distance,
                    double tolerance, double max_time, double *toi)
{
	if (!ccd_motion_in_range(motion) || !(fabs(minimum_distance) <= CCD_MAX_COORDINATE) ||
	    ccd_touching_at_start(motion, vertex_face)) {
		*toi = 0.0;
		return true;
	}
	ccd_problem p;
	ccd_problem_init(&p, motion, vertex_face, minimum_distance, tolerance, max_time);

	ccd_search search;
	search.count = 0;
	search.cutoff = INFINITY;
	search.hit = false;
	search.budget = CCD_BOX_BUDGET;
	ccd_flat flat;
	search.flat = ccd_flat_init(&flat, &p, motion, vertex_face) ? &flat : NULL;
	ccd_box root = {{0.0, 0.0, 0.0}, {p.max_time, 1.0, 1.0}};
	ccd_push(&search, &root);
	while (search.count > 0) {
		ccd_box box = search.stack[--search.count];
		ccd_examine(&p, &search, box);
	}
	*toi = search.hit ? ccd_max(search.cutoff, 0.0) : p.max_time;
	return search.hit;
}

bool plait_ccd_vertex_face(const plait_ccd_motion *motion, double minimum_distance, double tolerance,
                           double max_time, double *toi)
{
	return ccd_run(motion, true, minimum_distance, tolerance, max_time, toi);
}

bool plait_ccd_edge_edge(const plait_ccd_motion *motion, double minimum_distance, double tolerance,
                         double max_time, double *toi)
{
	return ccd_run(motion, false, minimum_distance, tolerance, max_time, toi);
}

/* The largest float not above x (for x >= 0). */
static float ccd_float_down(double x)
{
	float f = (float)x;
	return (double)f > x ? nextafterf(f, 0.0f) : f;
}

static bool ccd_run_float(const plait_ccd_motion_float *motion, bool vertex_face, float minimum_distance,
                          float tolerance, float max_time, float *toi)
{
	plait_ccd_motion wide;
	for (int i = 0; i < 4; i++) {
		for (int k = 0; k < 3; k++) {
			wide.start[i][k] = motion->start[i][k];
			wide.end[i][k] = motion->end[i][k];
		}
	}
	double toi_wide;
	bool hit = ccd_run(&wide, vertex_face, minimum_distance, tolerance, max_time, &toi_wide);
	*toi = ccd_float_down(toi_wide);
	return hit;
}

bool plait_ccd_vertex_face_float(const plait_ccd_motion_float *motion, float minimum_distance,
                                 float tolerance, float max_time, float *toi)
{
	return ccd_run_float(motion, true, minimum_distance, tolerance, max_time, toi);
}

bool plait_ccd_edge_edge_float(const plait_ccd_motion_float *motion, float minimum_distance, float tolerance,
                               float max_time, float *toi)
{
	return ccd_run_float(motion, false, minimum_distance, tolerance, max_time, toi);
}
