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
	float scale;
} plait_rigid;

plait_rigid plait_rigid_from_transform(plait_transform transform);
static inline vec3 plait_rigid_apply(const plait_rigid *r, vec3 p)
{
	return v3_add(r->translate, v3_scale(m3_mul_v3(&r->rotation, p), r->scale));
}
static inline vec3 plait_rigid_apply_inverse(const plait_rigid *r, vec3 p)
{
	return v3_scale(m3_tmul_v3(&r->rotation, v3_sub(p, r->translate)), 1.0f / r->scale);
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
 * the nearest surface point (never zero). */
float plait_shape_distance(const plait_shape *shape, vec3 p, vec3 *normal);

/* Shape-space bounding box (planes are unbounded: returns false). */
bool plait_shape_bounds(const plait_shape *shape, vec3 *lower, vec3 *upper);

/* First time t in [0, 1] at which the point p0 + t (p1 - p0) comes within radius of the
 * surface (analytic shapes; meshes are handled triangle by triangle in dynamics/contact.c),
 * found by conservative advancement: every step is at most the distance to the
 * surface, so a step can never cross it. Returns false when the whole path stays farther than
 * radius. When the path starts inside (distance < radius) the hit is at t = 0. */
bool plait_shape_sweep(const plait_shape *shape, vec3 p0, vec3 p1, float radius, float *toi);

#endif
