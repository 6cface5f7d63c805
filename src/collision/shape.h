/* Analytic collider shapes (nRigid): plane, sphere, capsule, box. Each is described in its own
 * "shape space"; the collider's keyframed transform maps shape space to the world. Queries are
 * signed distances (negative inside) with the outward unit normal, and a swept test of a moving
 * thickened point (the space-time view of paper §7 for points against a rigid shape). */
#ifndef PLAIT_COLLISION_SHAPE_H
#define PLAIT_COLLISION_SHAPE_H

#include "collision/mesh_shape.h"
#include "core/math.h"

typedef struct plait_shape {
	plait_shape_type type;
	vec3 point, normal;     /* plane */
	vec3 center;            /* sphere, box */
	float radius;           /* sphere, capsule */
	vec3 a, b;              /* capsule */
	vec3 half_extents;      /* box */
	mat3 rotation;          /* box orientation: box space -> shape space */
	plait_mesh_shape *mesh; /* mesh colliders: owned by the collider */
} plait_shape;

/* Rigid transform with uniform scale: world = translate + scale * rotation * shape. */
typedef struct plait_rigid {
	vec3 translate;
	mat3 rotation;
	float scale, inverse_scale;
} plait_rigid;

plait_rigid plait_rigid_from_transform(plait_transform transform);

/* A box's corner i in shape space: bit 0 picks +x, bit 1 +y, bit 2 +z (box space). Its faces as
 * corner quads, wound counter-clockwise seen from outside. */
vec3 plait_shape_box_corner(const plait_shape *box, int i);
extern const int plait_box_faces[6][4];
static inline vec3 plait_rigid_apply(const plait_rigid *r, vec3 p)
{
	return v3_add(r->translate, v3_scale(m3_mul_v3(&r->rotation, p), r->scale));
}
static inline vec3 plait_rigid_apply_inverse(const plait_rigid *r, vec3 p)
{
	return v3_scale(m3_tmul_v3(&r->rotation, v3_sub(p, r->translate)), r->inverse_scale);
}
static inline vec3 plait_rigid_rotate(const plait_rigid *r, vec3 v)
{
	return m3_mul_v3(&r->rotation, v);
}
static inline vec3 plait_rigid_rotate_inverse(const plait_rigid *r, vec3 v)
{
	return m3_tmul_v3(&r->rotation, v);
}

/* Signed distance from p (shape space) to the surface; *normal receives the outward normal of
 * the nearest surface point (never zero). Spheres and planes are answered inline: they are what
 * the collider pass meets for most contacts. */
float plait_shape_distance_general(const plait_shape *shape, vec3 p, vec3 *normal);
static inline float plait_shape_distance(const plait_shape *shape, vec3 p, vec3 *normal)
{
	if (shape->type == PLAIT_SHAPE_SPHERE) {
		vec3 d = v3_sub(p, shape->center);
		float length = v3_length(d);
		*normal = length > 1e-12f ? v3_scale(d, 1.0f / length) : v3(0.0f, 1.0f, 0.0f);
		return length - shape->radius;
	}
	if (shape->type == PLAIT_SHAPE_PLANE) {
		*normal = shape->normal;
		return v3_dot(shape->normal, v3_sub(p, shape->point));
	}
	return plait_shape_distance_general(shape, p, normal);
}

/* Shape-space bounding box (planes are unbounded: returns false). */
bool plait_shape_bounds(const plait_shape *shape, vec3 *lower, vec3 *upper);

/* First time t in [0, 1] at which the point p0 + t (p1 - p0) comes within radius of the
 * surface (analytic shapes; meshes are handled triangle by triangle in dynamics/contact.c),
 * found by conservative advancement: every step is at most the distance to the
 * surface, so a step can never cross it. Returns false when the whole path stays farther than
 * radius. When the path starts inside (distance < radius) the hit is at t = 0. */
bool plait_shape_sweep_general(const plait_shape *shape, vec3 p0, vec3 p1, float radius, float *toi);
static inline bool plait_shape_sweep(const plait_shape *shape, vec3 p0, vec3 p1, float radius, float *toi)
{
	vec3 motion = v3_sub(p1, p0);
	if (shape->type == PLAIT_SHAPE_PLANE) {
		/* Exact for a plane: distance is linear in t. */
		float d0 = v3_dot(shape->normal, v3_sub(p0, shape->point)) - radius;
		float d1 = v3_dot(shape->normal, v3_sub(p1, shape->point)) - radius;
		if (d0 <= 0.0f) {
			*toi = 0.0f;
			return true;
		}
		if (d1 > 0.0f) {
			return false;
		}
		*toi = d0 / (d0 - d1);
		return true;
	}
	if (shape->type == PLAIT_SHAPE_SPHERE) {
		/* Exact for a sphere: |p0 + t d - c| = R is a quadratic in t. */
		vec3 m = v3_sub(p0, shape->center);
		float reach = shape->radius + radius;
		float c = v3_dot(m, m) - reach * reach;
		if (c <= 0.0f) {
			*toi = 0.0f;
			return true;
		}
		float a = v3_dot(motion, motion), b = v3_dot(m, motion);
		if (a <= 0.0f || b >= 0.0f) {
			return false;
		}
		float discriminant = b * b - a * c;
		if (discriminant < 0.0f) {
			return false;
		}
		float t_hit = (-b - sqrtf(discriminant)) / a;
		if (t_hit > 1.0f) {
			return false;
		}
		*toi = t_hit > 0.0f ? t_hit : 0.0f;
		return true;
	}
	return plait_shape_sweep_general(shape, p0, p1, radius, toi);
}

#endif
