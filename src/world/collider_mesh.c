/* A collider's geometry where it is now, for writing it out and checking results: its shape in
 * world space, and its surface as a triangle mesh of fixed topology. Round shapes are
 * tessellated as lathes (rings of vertices about an axis, a pole at each end) with every vertex
 * on the true surface, so the flat triangles stay inside the shape: a point outside the shape is
 * outside the tessellation too, and a cloth resting on a sphere never seems to cut into it. */
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "world/world.h"

#define LATHE_SEGMENTS 64
#define SPHERE_RINGS 31      /* between the poles: 32 steps of latitude */
#define CAPSULE_CAP_RINGS 16 /* per half sphere, its equator included */

/* The collider behind id, or NULL with *result saying why. */
static plait_collider *collider_of(plait_object_id id, plait_result *result, plait_error *error)
{
	plait_object *object = plait_world_resolve(id, error);
	if (object == NULL) {
		*result = PLAIT_ERROR_INVALID_ID;
		return NULL;
	}
	if (object->collider < 0) {
		*result =
		    plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT, "'%s' is not a collider", object->name);
		return NULL;
	}
	*result = PLAIT_OK;
	return &id.world->sim.colliders[object->collider];
}

/* The placement the solver has reached: transform_end is only the target of the next step. */
static plait_rigid current_rigid(const plait_collider *collider)
{
	return plait_rigid_from_transform(collider->transform_start);
}

plait_result plait_collider_get_shape(plait_object_id id, plait_collider_shape *out, plait_error *error)
{
	plait_result result;
	plait_collider *collider = collider_of(id, &result, error);
	if (collider == NULL) {
		return result;
	}
	if (out == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "plait_collider_get_shape needs a shape to fill");
	}
	const plait_shape *shape = &collider->shape;
	plait_rigid r = current_rigid(collider);
	memset(out, 0, sizeof *out);
	out->type = shape->type;
	switch (shape->type) {
	case PLAIT_SHAPE_PLANE:
		out->point = plait_rigid_apply(&r, shape->point);
		out->normal = v3_normalize(plait_rigid_rotate(&r, shape->normal));
		break;
	case PLAIT_SHAPE_SPHERE:
		out->center = plait_rigid_apply(&r, shape->center);
		out->radius = shape->radius * r.scale;
		break;
	case PLAIT_SHAPE_CAPSULE:
		out->a = plait_rigid_apply(&r, shape->a);
		out->b = plait_rigid_apply(&r, shape->b);
		out->radius = shape->radius * r.scale;
		break;
	case PLAIT_SHAPE_BOX:
		out->center = plait_rigid_apply(&r, shape->center);
		out->half_extents = v3_scale(shape->half_extents, r.scale);
		for (int k = 0; k < 3; ++k) {
			vec3 column = {shape->rotation.m[0][k], shape->rotation.m[1][k], shape->rotation.m[2][k]};
			out->axes[k] = plait_rigid_rotate(&r, column);
		}
		break;
	case PLAIT_SHAPE_MESH:
		break;
	}
	return PLAIT_OK;
}

bool plait_collider_is_closed(plait_object_id id)
{
	plait_result result;
	plait_collider *collider = collider_of(id, &result, NULL);
	if (collider == NULL || collider->shape.type == PLAIT_SHAPE_PLANE) {
		return false;
	}
	const plait_mesh_shape *mesh = collider->shape.mesh;
	if (collider->shape.type != PLAIT_SHAPE_MESH) {
		return true;
	}
	if (mesh == NULL || mesh->triangle_count == 0) {
		return false;
	}
	return mesh->closed;
}

/* A lathe: a pole, `rings` rings of LATHE_SEGMENTS vertices, another pole, about axis w. */
typedef struct lathe {
	vec3 u, v, w; /* right-handed: u x v = w */
	vec3 top, bottom;
	int rings;
} lathe;

static int lathe_vertex_count(int rings)
{
	return 2 + rings * LATHE_SEGMENTS;
}

static int lathe_triangle_count(int rings)
{
	return 2 * LATHE_SEGMENTS * rings;
}

/* Unit u and v with u x v = w, for a unit w. */
static void perpendicular_frame(vec3 w, vec3 *u, vec3 *v)
{
	vec3 helper = fabsf(w.x) < 0.9f ? v3(1.0f, 0.0f, 0.0f) : v3(0.0f, 0.0f, 1.0f);
	*u = v3_normalize(v3_cross(helper, w));
	*v = v3_cross(w, *u);
}

static lathe lathe_of(const plait_shape *shape)
{
	lathe l;
	if (shape->type == PLAIT_SHAPE_SPHERE) {
		l.w = v3(0.0f, 1.0f, 0.0f);
		l.top = v3_mul_add(shape->center, shape->radius, l.w);
		l.bottom = v3_mul_add(shape->center, -shape->radius, l.w);
		l.rings = SPHERE_RINGS;
	} else {
		vec3 axis = v3_sub(shape->b, shape->a);
		l.w = v3_length(axis) > 0.0f ? v3_normalize(axis) : v3(0.0f, 1.0f, 0.0f);
		l.top = v3_mul_add(shape->b, shape->radius, l.w);
		l.bottom = v3_mul_add(shape->a, -shape->radius, l.w);
		l.rings = 2 * CAPSULE_CAP_RINGS;
	}
	perpendicular_frame(l.w, &l.u, &l.v);
	return l;
}

/* Centre along the axis and radius of ring k (0-based, from the top). A sphere's rings are at
 * latitudes (k + 1) pi / 32; a capsule's top half sphere is about b down to its equator, the
 * bottom one about a from its equator. */
static void lathe_ring(const plait_shape *shape, const lathe *l, int k, vec3 *center, float *radius)
{
	const float pi = PLAIT_PI;
	if (shape->type == PLAIT_SHAPE_SPHERE) {
		float theta = (float)(k + 1) * pi / (float)(SPHERE_RINGS + 1);
		*center = v3_mul_add(shape->center, shape->radius * cosf(theta), l->w);
		*radius = shape->radius * sinf(theta);
		return;
	}
	int h = CAPSULE_CAP_RINGS;
	bool upper = k < h;
	float theta =
	    upper ? (float)(k + 1) * (0.5f * pi) / (float)h : 0.5f * pi + (float)(k - h) * (0.5f * pi) / (float)h;
	vec3 base = upper ? shape->b : shape->a;
	*center = v3_mul_add(base, shape->radius * cosf(theta), l->w);
	*radius = shape->radius * sinf(theta);
}

static vec3 lathe_vertex(const plait_shape *shape, const lathe *l, int index)
{
	if (index == 0) {
		return l->top;
	}
	if (index == lathe_vertex_count(l->rings) - 1) {
		return l->bottom;
	}
	int ring = (index - 1) / LATHE_SEGMENTS, segment = (index - 1) % LATHE_SEGMENTS;
	vec3 center;
	float radius;
	lathe_ring(shape, l, ring, &center, &radius);
	float phi = 2.0f * PLAIT_PI * (float)segment / (float)LATHE_SEGMENTS;
	return v3_add(center, v3_add(v3_scale(l->u, radius * cosf(phi)), v3_scale(l->v, radius * sinf(phi))));
}

/* Triangle t of a lathe; the caller checks t is in range. Bands between ring k and k + 1 (the
 * poles as rings of one) split each quad (A above, B below, C below and on, D above and on)
 * into (A, B, C) and (A, C, D), which face outward for u x v = w. */
static void lathe_triangle(int rings, int t, int out[3])
{
	const int s = LATHE_SEGMENTS;
	int last = lathe_vertex_count(rings) - 1;
	if (t < s) { /* top cap */
		out[0] = 0;
		out[1] = 1 + t;
		out[2] = 1 + (t + 1) % s;
		return;
	}
	t -= s;
	if (t < 2 * s * (rings - 1)) {
		int band = t / (2 * s), quad = (t % (2 * s)) / 2, half = t % 2;
		int a = 1 + band * s + quad, d = 1 + band * s + (quad + 1) % s;
		int b = a + s, c = d + s;
		out[0] = a;
		out[1] = half == 0 ? b : c;
		out[2] = half == 0 ? c : d;
		return;
	}
	t -= 2 * s * (rings - 1);
	int a = 1 + (rings - 1) * s + t, d = 1 + (rings - 1) * s + (t + 1) % s;
	out[0] = a;
	out[1] = last;
	out[2] = d;
}

static int surface_vertex_count(const plait_shape *shape)
{
	switch (shape->type) {
	case PLAIT_SHAPE_PLANE:
		return 4;
	case PLAIT_SHAPE_SPHERE:
		return lathe_vertex_count(SPHERE_RINGS);
	case PLAIT_SHAPE_CAPSULE:
		return lathe_vertex_count(2 * CAPSULE_CAP_RINGS);
	case PLAIT_SHAPE_BOX:
		return 8;
	case PLAIT_SHAPE_MESH:
		return shape->mesh != NULL ? shape->mesh->vertex_count : 0;
	}
	return 0;
}

static int surface_triangle_count(const plait_shape *shape)
{
	switch (shape->type) {
	case PLAIT_SHAPE_PLANE:
		return 2;
	case PLAIT_SHAPE_SPHERE:
		return lathe_triangle_count(SPHERE_RINGS);
	case PLAIT_SHAPE_CAPSULE:
		return lathe_triangle_count(2 * CAPSULE_CAP_RINGS);
	case PLAIT_SHAPE_BOX:
		return 12;
	case PLAIT_SHAPE_MESH:
		return shape->mesh != NULL ? shape->mesh->triangle_count : 0;
	}
	return 0;
}

int plait_collider_get_surface_vertex_count(plait_object_id id)
{
	plait_result result;
	plait_collider *collider = collider_of(id, &result, NULL);
	return collider != NULL ? surface_vertex_count(&collider->shape) : 0;
}

int plait_collider_get_surface_triangles(plait_object_id id, int *indices, int capacity)
{
	plait_result result;
	plait_collider *collider = collider_of(id, &result, NULL);
	if (collider == NULL) {
		return 0;
	}
	const plait_shape *shape = &collider->shape;
	int count = surface_triangle_count(shape);
	for (int t = 0; indices != NULL && t < count && t < capacity; ++t) {
		int *out = indices + 3 * t;
		switch (shape->type) {
		case PLAIT_SHAPE_PLANE:
			out[0] = 0;
			out[1] = t == 0 ? 1 : 2;
			out[2] = t == 0 ? 2 : 3;
			break;
		case PLAIT_SHAPE_SPHERE:
		case PLAIT_SHAPE_CAPSULE:
			lathe_triangle(shape->type == PLAIT_SHAPE_SPHERE ? SPHERE_RINGS : 2 * CAPSULE_CAP_RINGS, t, out);
			break;
		case PLAIT_SHAPE_BOX: {
			const int *quad = plait_box_faces[t / 2];
			out[0] = quad[0];
			out[1] = quad[t % 2 == 0 ? 1 : 2];
			out[2] = quad[t % 2 == 0 ? 2 : 3];
			break;
		}
		case PLAIT_SHAPE_MESH:
			memcpy(out, shape->mesh->triangles[t], sizeof shape->mesh->triangles[t]);
			break;
		}
	}
	return count;
}

/* Vertex i of the surface in shape space. */
static vec3 surface_vertex(const plait_shape *shape, const lathe *l, int i)
{
	switch (shape->type) {
	case PLAIT_SHAPE_PLANE: {
		/* Corners counter-clockwise seen from the normal's side. */
		vec3 u, v;
		perpendicular_frame(shape->normal, &u, &v);
		float half = 0.5f * PLAIT_COLLIDER_PLANE_SIZE;
		float su = (i == 1 || i == 2) ? half : -half, sv = i >= 2 ? half : -half;
		return v3_add(shape->point, v3_add(v3_scale(u, su), v3_scale(v, sv)));
	}
	case PLAIT_SHAPE_SPHERE:
	case PLAIT_SHAPE_CAPSULE:
		return lathe_vertex(shape, l, i);
	case PLAIT_SHAPE_BOX:
		return plait_shape_box_corner(shape, i);
	case PLAIT_SHAPE_MESH:
		return shape->mesh->positions[i];
	}
	return v3(0.0f, 0.0f, 0.0f);
}

plait_result plait_collider_get_surface_positions(plait_object_id id, int first, int count, plait_vec3 *out,
                                                  plait_error *error)
{
	plait_result result;
	plait_collider *collider = collider_of(id, &result, error);
	if (collider == NULL) {
		return result;
	}
	const plait_shape *shape = &collider->shape;
	int vertex_count = surface_vertex_count(shape);
	if (first < 0 || count < 0 || first > vertex_count - count || (out == NULL && count > 0)) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_ARGUMENT,
		                       "surface vertices %d..%d asked of a collider surface with %d", first,
		                       first + count - 1, vertex_count);
	}
	lathe l = {0};
	if (shape->type == PLAIT_SHAPE_SPHERE || shape->type == PLAIT_SHAPE_CAPSULE) {
		l = lathe_of(shape);
	}
	plait_rigid r = current_rigid(collider);
	for (int k = 0; k < count; ++k) {
		out[k] = plait_rigid_apply(&r, surface_vertex(shape, &l, first + k));
	}
	return PLAIT_OK;
}
