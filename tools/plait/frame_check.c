#include "frame_check.h"

#include "grow_array.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

bool plait_frame_checker_init(plait_frame_checker *checker, const plait_manifest *manifest,
                              double tolerance_m, plait_tool_error *error)
{
	*checker = (plait_frame_checker){0};
	checker->manifest = manifest;
	checker->tolerance = tolerance_m / manifest->space_scale;
	size_t n = (size_t)(manifest->object_count > 0 ? manifest->object_count : 1);
	checker->first_vertex = calloc(n, sizeof *checker->first_vertex);
	checker->counts.pairs = calloc(n * n, sizeof *checker->counts.pairs);
	checker->counts.inside = calloc(n, sizeof *checker->counts.inside);
	if (checker->first_vertex == NULL || checker->counts.pairs == NULL || checker->counts.inside == NULL) {
		plait_frame_checker_free(checker);
		return plait_tool_error_set(error, "out of memory");
	}
	return true;
}

void plait_frame_checker_free(plait_frame_checker *checker)
{
	free(checker->first_vertex);
	free(checker->positions);
	free(checker->triangles);
	free(checker->boxes);
	free(checker->collider_triangles);
	free(checker->collider_boxes);
	plait_box_tree_free(&checker->tree);
	plait_box_tree_free(&checker->collider_tree);
	free(checker->counts.pairs);
	free(checker->counts.inside);
	*checker = (plait_frame_checker){0};
}

static bool plait_has_triangles_to_check(const plait_manifest_object *object)
{
	if (!object->collide)
		return false;
	// A plane's square is only a picture of it: vertices below the plane are counted exactly.
	return object->type == PLAIT_OBJECT_CLOTH ||
	       (object->type == PLAIT_OBJECT_COLLIDER && object->shape != PLAIT_SHAPE_PLANE);
}

static float plait_min(float a, float b)
{
	return a < b ? a : b;
}

static float plait_max(float a, float b)
{
	return a > b ? a : b;
}

static plait_box plait_triangle_box(const plait_vec3 *x, const int v[3])
{
	plait_vec3 a = x[v[0]], b = x[v[1]], c = x[v[2]];
	return (plait_box){{plait_min(a.x, plait_min(b.x, c.x)), plait_min(a.y, plait_min(b.y, c.y)),
	                    plait_min(a.z, plait_min(b.z, c.z))},
	                   {plait_max(a.x, plait_max(b.x, c.x)), plait_max(a.y, plait_max(b.y, c.y)),
	                    plait_max(a.z, plait_max(b.z, c.z))}};
}

// Whether u lies strictly on one side of t's plane, so that they cannot meet. Most pairs whose
// boxes overlap end here, at a fraction of the exact test's cost. A margin keeps near-touching
// pairs for the exact test, so the count is the exact test's.
static bool plait_apart_by_plane(const plait_vec3 t[3], const plait_vec3 u[3])
{
	double e1[3] = {(double)t[1].x - t[0].x, (double)t[1].y - t[0].y, (double)t[1].z - t[0].z};
	double e2[3] = {(double)t[2].x - t[0].x, (double)t[2].y - t[0].y, (double)t[2].z - t[0].z};
	double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
	               e1[0] * e2[1] - e1[1] * e2[0]};
	double s[3], scale = 0.0;
	for (int k = 0; k < 3; ++k) {
		double d[3] = {(double)u[k].x - t[0].x, (double)u[k].y - t[0].y, (double)u[k].z - t[0].z};
		s[k] = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
		scale += fabs(n[0] * d[0]) + fabs(n[1] * d[1]) + fabs(n[2] * d[2]);
	}
	double margin = 1e-9 * scale;
	return (s[0] > margin && s[1] > margin && s[2] > margin) ||
	       (s[0] < -margin && s[1] < -margin && s[2] < -margin);
}

static bool plait_share_a_vertex(const int *a, const int *b)
{
	for (int i = 0; i < 3; ++i)
		for (int j = 0; j < 3; ++j)
			if (a[i] == b[j])
				return true;
	return false;
}

static void plait_visit_pair(int a, int b, void *context)
{
	plait_frame_checker *checker = context;
	const plait_frame_triangle *ta = &checker->triangles[a], *tb = &checker->triangles[b];
	const plait_manifest *m = checker->manifest;
	int oa = ta->object, ob = tb->object;
	if (m->objects[oa].type == PLAIT_OBJECT_COLLIDER && m->objects[ob].type == PLAIT_OBJECT_COLLIDER)
		return; // colliders are rigid: their meeting is the scene's business
	if (oa == ob && plait_share_a_vertex(ta->v, tb->v))
		return; // neighbours touch by construction
	const plait_vec3 *x = checker->positions;
	plait_vec3 t[3] = {x[ta->v[0]], x[ta->v[1]], x[ta->v[2]]}, u[3] = {x[tb->v[0]], x[tb->v[1]], x[tb->v[2]]};
	if (plait_apart_by_plane(t, u) || plait_apart_by_plane(u, t) || !plait_triangles_intersect(t, u))
		return;
	int low = oa < ob ? oa : ob, high = oa < ob ? ob : oa;
	checker->counts.pairs[low * m->object_count + high] += 1;
	checker->counts.intersections += 1;
	if (oa != ob)
		checker->counts.between_objects += 1;
}

/* ---- Vertices inside colliders ---- */

static double plait_dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void plait_to_double(plait_vec3 v, double out[3])
{
	out[0] = v.x;
	out[1] = v.y;
	out[2] = v.z;
}

static bool plait_inside_shape(const plait_collider_shape *s, const double p[3], double tolerance)
{
	double d[3];
	switch (s->type) {
	case PLAIT_SHAPE_PLANE: {
		double n[3], o[3];
		plait_to_double(s->normal, n);
		plait_to_double(s->point, o);
		double length = sqrt(plait_dot3(n, n));
		d[0] = p[0] - o[0], d[1] = p[1] - o[1], d[2] = p[2] - o[2];
		return length > 0.0 && plait_dot3(d, n) / length < -tolerance;
	}
	case PLAIT_SHAPE_SPHERE: {
		double c[3], reach = (double)s->radius - tolerance;
		plait_to_double(s->center, c);
		d[0] = p[0] - c[0], d[1] = p[1] - c[1], d[2] = p[2] - c[2];
		return reach > 0.0 && plait_dot3(d, d) < reach * reach;
	}
	case PLAIT_SHAPE_CAPSULE: {
		double a[3], b[3], ab[3], reach = (double)s->radius - tolerance;
		plait_to_double(s->a, a);
		plait_to_double(s->b, b);
		ab[0] = b[0] - a[0], ab[1] = b[1] - a[1], ab[2] = b[2] - a[2];
		d[0] = p[0] - a[0], d[1] = p[1] - a[1], d[2] = p[2] - a[2];
		double length_sq = plait_dot3(ab, ab);
		double t = length_sq > 0.0 ? plait_dot3(d, ab) / length_sq : 0.0;
		t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
		d[0] -= t * ab[0], d[1] -= t * ab[1], d[2] -= t * ab[2];
		return reach > 0.0 && plait_dot3(d, d) < reach * reach;
	}
	case PLAIT_SHAPE_BOX: {
		double c[3], h[3];
		plait_to_double(s->center, c);
		plait_to_double(s->half_extents, h);
		d[0] = p[0] - c[0], d[1] = p[1] - c[1], d[2] = p[2] - c[2];
		for (int k = 0; k < 3; ++k) {
			double axis[3];
			plait_to_double(s->axes[k], axis);
			double length = sqrt(plait_dot3(axis, axis));
			if (!(length > 0.0) || fabs(plait_dot3(d, axis) / length) >= h[k] - tolerance)
				return false;
		}
		return true;
	}
	case PLAIT_SHAPE_MESH:
		break;
	}
	return false;
}

/* Six times the signed volume of (a, b, c, d). */
static double plait_orient(const double a[3], const double b[3], const double c[3], const double d[3])
{
	double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
	double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
	double ad[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
	return ab[0] * (ac[1] * ad[2] - ac[2] * ad[1]) - ab[1] * (ac[0] * ad[2] - ac[2] * ad[0]) +
	       ab[2] * (ac[0] * ad[1] - ac[1] * ad[0]);
}

typedef struct plait_ray_pass {
	const plait_frame_checker *checker;
	double p[3], q[3];
	int crossings;
	bool degenerate; /* the ray grazed an edge or a corner: its parity means nothing */
} plait_ray_pass;

static void plait_visit_ray(int item, void *context)
{
	plait_ray_pass *pass = context;
	const plait_frame_triangle *t = &pass->checker->collider_triangles[item];
	double a[3], b[3], c[3];
	plait_to_double(pass->checker->positions[t->v[0]], a);
	plait_to_double(pass->checker->positions[t->v[1]], b);
	plait_to_double(pass->checker->positions[t->v[2]], c);
	// A start on the triangle's plane is on the surface (the distance test settles it) or beside
	// the triangle (no crossing); the far end is outside every triangle.
	double sp = plait_orient(a, b, c, pass->p), sq = plait_orient(a, b, c, pass->q);
	if (!((sp > 0.0 && sq < 0.0) || (sp < 0.0 && sq > 0.0)))
		return;
	double s1 = plait_orient(pass->p, pass->q, a, b), s2 = plait_orient(pass->p, pass->q, b, c),
	       s3 = plait_orient(pass->p, pass->q, c, a);
	bool positive = s1 > 0.0 && s2 > 0.0 && s3 > 0.0, negative = s1 < 0.0 && s2 < 0.0 && s3 < 0.0;
	if (positive || negative) {
		pass->crossings += 1;
		return;
	}
	bool mixed = (s1 > 0.0 || s2 > 0.0 || s3 > 0.0) && (s1 < 0.0 || s2 < 0.0 || s3 < 0.0);
	if (!mixed)
		pass->degenerate = true;
}

// Squared distance from p to triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
static double plait_triangle_distance_sq(const double p[3], const double a[3], const double b[3],
                                         const double c[3])
{
	double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
	for (int k = 0; k < 3; ++k) {
		ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k], bp[k] = p[k] - b[k],
		cp[k] = p[k] - c[k];
	}
	double d1 = plait_dot3(ab, ap), d2 = plait_dot3(ac, ap), d3 = plait_dot3(ab, bp), d4 = plait_dot3(ac, bp);
	double d5 = plait_dot3(ab, cp), d6 = plait_dot3(ac, cp);
	double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
	double v, w;
	if (d1 <= 0.0 && d2 <= 0.0)
		v = 0.0, w = 0.0;
	else if (d3 >= 0.0 && d4 <= d3)
		v = 1.0, w = 0.0;
	else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
		v = d1 / (d1 - d3), w = 0.0;
	else if (d6 >= 0.0 && d5 <= d6)
		v = 0.0, w = 1.0;
	else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
		v = 0.0, w = d2 / (d2 - d6);
	else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
		w = (d4 - d3) / ((d4 - d3) + (d5 - d6)), v = 1.0 - w;
	else if (va + vb + vc > 0.0)
		v = vb / (va + vb + vc), w = vc / (va + vb + vc);
	else
		v = 0.0, w = 0.0; // degenerate triangle: its first corner
	for (int k = 0; k < 3; ++k)
		q[k] = p[k] - (a[k] + v * ab[k] + w * ac[k]);
	return plait_dot3(q, q);
}

typedef struct plait_near_pass {
	const plait_frame_checker *checker;
	double p[3];
	double limit_sq;
	bool near;
} plait_near_pass;

static void plait_visit_near(int item, void *context)
{
	plait_near_pass *pass = context;
	if (pass->near)
		return;
	const plait_frame_triangle *t = &pass->checker->collider_triangles[item];
	double a[3], b[3], c[3];
	plait_to_double(pass->checker->positions[t->v[0]], a);
	plait_to_double(pass->checker->positions[t->v[1]], b);
	plait_to_double(pass->checker->positions[t->v[2]], c);
	pass->near = plait_triangle_distance_sq(pass->p, a, b, c) <= pass->limit_sq;
}

// Inside a closed mesh by more than the tolerance: an odd number of crossings along rays in
// directions no mesh is likely to line up with (two votes of three agree; a ray that grazes an
// edge does not vote), and no triangle within the tolerance.
static bool plait_inside_mesh(const plait_frame_checker *checker, const plait_box *bounds, const double p[3])
{
	if (p[0] < bounds->lower.x || p[0] > bounds->upper.x || p[1] < bounds->lower.y ||
	    p[1] > bounds->upper.y || p[2] < bounds->lower.z || p[2] > bounds->upper.z)
		return false;
	static const double directions[7][3] = {
	    {0.5773502691896258, 0.5773502691896258, 0.5773502691896258},
	    {-0.3015113445777636, 0.9045340337332909, 0.3015113445777636},
	    {0.8017837257372732, -0.2672612419124244, 0.5345224838248488},
	    {-0.6666666666666666, -0.3333333333333333, 0.6666666666666666},
	    {0.2357022603955158, -0.9428090415820634, -0.2357022603955158},
	    {-0.4850712500726659, 0.2425356250363330, -0.8401680504168059},
	    {0.9128709291752769, 0.3651483716701107, -0.1825741858350554},
	};
	double span[3] = {(double)bounds->upper.x - bounds->lower.x, (double)bounds->upper.y - bounds->lower.y,
	                  (double)bounds->upper.z - bounds->lower.z};
	double reach = 2.0 * sqrt(plait_dot3(span, span)) + 1.0;
	int inside_votes = 0, outside_votes = 0;
	for (int k = 0; k < 7 && inside_votes < 2 && outside_votes < 2; ++k) {
		plait_ray_pass pass = {checker, {p[0], p[1], p[2]}, {0}, 0, false};
		for (int i = 0; i < 3; ++i)
			pass.q[i] = p[i] + reach * directions[k][i];
		plait_box_tree_segment(&checker->collider_tree, pass.p, pass.q, plait_visit_ray, &pass);
		if (pass.degenerate)
			continue;
		if (pass.crossings % 2 == 1)
			inside_votes += 1;
		else
			outside_votes += 1;
	}
	if (inside_votes <= outside_votes)
		return false;
	double t = checker->tolerance;
	plait_near_pass near = {checker, {p[0], p[1], p[2]}, t * t, false};
	plait_box query = {{(float)(p[0] - t), (float)(p[1] - t), (float)(p[2] - t)},
	                   {(float)(p[0] + t), (float)(p[1] + t), (float)(p[2] + t)}};
	plait_box_tree_query(&checker->collider_tree, query, plait_visit_near, &near);
	return !near.near;
}

static bool plait_build_collider_tree(plait_frame_checker *checker, int c, const plait_frame_mesh *mesh)
{
	if (!plait_grow_array((void **)&checker->collider_triangles, &checker->collider_capacity,
	                      mesh->triangle_count, sizeof *checker->collider_triangles) ||
	    !plait_grow_array((void **)&checker->collider_boxes, &checker->collider_box_capacity,
	                      mesh->triangle_count, sizeof *checker->collider_boxes))
		return false;
	int base = checker->first_vertex[c];
	for (int t = 0; t < mesh->triangle_count; ++t) {
		plait_frame_triangle *tri = &checker->collider_triangles[t];
		tri->object = c;
		for (int k = 0; k < 3; ++k)
			tri->v[k] = base + mesh->triangles[t][k];
		checker->collider_boxes[t] = plait_triangle_box(checker->positions, tri->v);
	}
	return plait_box_tree_build(&checker->collider_tree, checker->collider_boxes, mesh->triangle_count);
}

static bool plait_count_inside(plait_frame_checker *checker, const plait_frame_mesh *meshes, int frame,
                               plait_tool_error *error)
{
	const plait_manifest *m = checker->manifest;
	for (int c = 0; c < m->object_count; ++c) {
		const plait_manifest_object *collider = &m->objects[c];
		if (collider->type != PLAIT_OBJECT_COLLIDER || !collider->collide ||
		    !(collider->closed || collider->shape == PLAIT_SHAPE_PLANE))
			continue;
		bool mesh = collider->shape == PLAIT_SHAPE_MESH;
		plait_box bounds;
		if (mesh && (!plait_build_collider_tree(checker, c, &meshes[c]) ||
		             !plait_box_tree_bounds(&checker->collider_tree, &bounds))) {
			if (meshes[c].triangle_count == 0)
				continue;
			return plait_tool_error_set(error, "out of memory");
		}
		const plait_collider_shape *shape = mesh ? NULL : &collider->shapes[frame - m->first_frame];
		for (int o = 0; o < m->object_count; ++o) {
			const plait_manifest_object *object = &m->objects[o];
			if (object->type == PLAIT_OBJECT_COLLIDER || !object->collide)
				continue;
			for (int i = 0; i < meshes[o].vertex_count; ++i) {
				double p[3];
				plait_to_double(meshes[o].positions[i], p);
				bool inside = mesh ? plait_inside_mesh(checker, &bounds, p)
				                   : plait_inside_shape(shape, p, checker->tolerance);
				if (inside) {
					checker->counts.inside[c] += 1;
					checker->counts.inside_colliders += 1;
				}
			}
		}
	}
	return true;
}

bool plait_frame_check(plait_frame_checker *checker, const plait_frame_mesh *meshes, int frame,
                       plait_tool_error *error)
{
	const plait_manifest *m = checker->manifest;
	int n = m->object_count;
	memset(checker->counts.pairs, 0, sizeof *checker->counts.pairs * (size_t)n * (size_t)n);
	memset(checker->counts.inside, 0, sizeof *checker->counts.inside * (size_t)n);
	checker->counts.intersections = checker->counts.between_objects = checker->counts.inside_colliders = 0;

	// Every object's vertices back to back, so a triangle is three indices into one array.
	long long vertices = 0, triangles = 0;
	for (int o = 0; o < n; ++o) {
		checker->first_vertex[o] = (int)vertices;
		vertices += meshes[o].vertex_count;
		if (plait_has_triangles_to_check(&m->objects[o]))
			triangles += meshes[o].triangle_count;
	}
	if (!plait_grow_array((void **)&checker->positions, &checker->position_capacity, vertices,
	                      sizeof *checker->positions) ||
	    !plait_grow_array((void **)&checker->triangles, &checker->triangle_capacity, triangles,
	                      sizeof *checker->triangles) ||
	    !plait_grow_array((void **)&checker->boxes, &checker->box_capacity, triangles,
	                      sizeof *checker->boxes))
		return plait_tool_error_set(error, "out of memory (%lld vertices, %lld triangles)", vertices,
		                            triangles);
	int count = 0;
	for (int o = 0; o < n; ++o) {
		const plait_frame_mesh *mesh = &meshes[o];
		int base = checker->first_vertex[o];
		if (mesh->vertex_count > 0)
			memcpy(checker->positions + base, mesh->positions,
			       sizeof *mesh->positions * (size_t)mesh->vertex_count);
		if (!plait_has_triangles_to_check(&m->objects[o]))
			continue;
		for (int t = 0; t < mesh->triangle_count; ++t) {
			plait_frame_triangle *tri = &checker->triangles[count];
			tri->object = o;
			for (int k = 0; k < 3; ++k)
				tri->v[k] = base + mesh->triangles[t][k];
			checker->boxes[count++] = plait_triangle_box(checker->positions, tri->v);
		}
	}
	if (!plait_box_tree_build(&checker->tree, checker->boxes, count))
		return plait_tool_error_set(error, "out of memory");
	plait_box_tree_pairs(&checker->tree, plait_visit_pair, checker);
	return plait_count_inside(checker, meshes, frame, error);
}
