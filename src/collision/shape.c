#include "collision/shape.h"

const int plait_box_faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                   {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

vec3 plait_shape_box_corner(const plait_shape *box, int i)
{
	vec3 h = box->half_extents;
	vec3 local = {(i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z};
	return v3_add(box->center, m3_mul_v3(&box->rotation, local));
}

plait_rigid plait_rigid_from_transform(plait_transform transform)
{
	plait_rigid r;
	r.translate = transform.translate;
	r.rotation = m3_from_euler_deg(transform.rotate_deg);
	r.scale = transform.scale > 0.0f ? transform.scale : 1.0f;
	r.inverse_scale = 1.0f / r.scale;
	return r;
}

static float box_distance(const plait_shape *shape, vec3 p, vec3 *normal)
{
	vec3 q = m3_tmul_v3(&shape->rotation, v3_sub(p, shape->center));
	vec3 h = shape->half_extents;
	vec3 d = {fabsf(q.x) - h.x, fabsf(q.y) - h.y, fabsf(q.z) - h.z};
	vec3 sign = {q.x < 0.0f ? -1.0f : 1.0f, q.y < 0.0f ? -1.0f : 1.0f, q.z < 0.0f ? -1.0f : 1.0f};
	float distance;
	vec3 local_normal;
	if (d.x > 0.0f || d.y > 0.0f || d.z > 0.0f) {
		vec3 outside = {plait_maxf(d.x, 0.0f) * sign.x, plait_maxf(d.y, 0.0f) * sign.y,
		                plait_maxf(d.z, 0.0f) * sign.z};
		distance = v3_length(outside);
		local_normal = v3_scale(outside, 1.0f / distance);
	} else {
		/* Inside: the nearest face is the one with the largest (least negative) d. */
		if (d.x >= d.y && d.x >= d.z) {
			distance = d.x;
			local_normal = v3(sign.x, 0.0f, 0.0f);
		} else if (d.y >= d.z) {
			distance = d.y;
			local_normal = v3(0.0f, sign.y, 0.0f);
		} else {
			distance = d.z;
			local_normal = v3(0.0f, 0.0f, sign.z);
		}
	}
	*normal = m3_mul_v3(&shape->rotation, local_normal);
	return distance;
}

static float point_distance(vec3 p, vec3 center, float radius, vec3 fallback_normal, vec3 *normal)
{
	vec3 d = v3_sub(p, center);
	float length = v3_length(d);
	*normal = length > 1e-12f ? v3_scale(d, 1.0f / length) : fallback_normal;
	return length - radius;
}

float plait_shape_distance_general(const plait_shape *shape, vec3 p, vec3 *normal)
{
	switch (shape->type) {
	case PLAIT_SHAPE_PLANE:
	case PLAIT_SHAPE_SPHERE:
		return plait_shape_distance(shape, p, normal); /* inline in shape.h */
	case PLAIT_SHAPE_CAPSULE: {
		vec3 ab = v3_sub(shape->b, shape->a);
		float length_sq = v3_length_sq(ab);
		float t = length_sq > 0.0f ? v3_dot(v3_sub(p, shape->a), ab) / length_sq : 0.0f;
		t = plait_minf(plait_maxf(t, 0.0f), 1.0f);
		vec3 closest = v3_mul_add(shape->a, t, ab);
		/* On the axis itself any direction perpendicular to it is outward. */
		vec3 fallback =
		    v3_normalize(v3_cross(ab, fabsf(ab.x) < 0.9f * sqrtf(length_sq) ? v3(1, 0, 0) : v3(0, 1, 0)));
		if (length_sq == 0.0f) {
			fallback = v3(0.0f, 1.0f, 0.0f);
		}
		return point_distance(p, closest, shape->radius, fallback, normal);
	}
	case PLAIT_SHAPE_BOX:
		return box_distance(shape, p, normal);
	case PLAIT_SHAPE_MESH:
		if (shape->mesh != NULL) {
			return plait_mesh_shape_distance(shape->mesh, p, normal);
		}
		break;
	}
	*normal = v3(0.0f, 1.0f, 0.0f);
	return INFINITY;
}

bool plait_shape_bounds(const plait_shape *shape, vec3 *lower, vec3 *upper)
{
	switch (shape->type) {
	case PLAIT_SHAPE_SPHERE: {
		vec3 r = {shape->radius, shape->radius, shape->radius};
		*lower = v3_sub(shape->center, r);
		*upper = v3_add(shape->center, r);
		return true;
	}
	case PLAIT_SHAPE_CAPSULE: {
		vec3 r = {shape->radius, shape->radius, shape->radius};
		*lower = v3_sub(v3_min(shape->a, shape->b), r);
		*upper = v3_add(v3_max(shape->a, shape->b), r);
		return true;
	}
	case PLAIT_SHAPE_BOX: {
		vec3 extent = {0};
		for (int row = 0; row < 3; ++row) {
			float e = fabsf(shape->rotation.m[row][0]) * shape->half_extents.x +
			          fabsf(shape->rotation.m[row][1]) * shape->half_extents.y +
			          fabsf(shape->rotation.m[row][2]) * shape->half_extents.z;
			if (row == 0) {
				extent.x = e;
			} else if (row == 1) {
				extent.y = e;
			} else {
				extent.z = e;
			}
		}
		*lower = v3_sub(shape->center, extent);
		*upper = v3_add(shape->center, extent);
		return true;
	}
	case PLAIT_SHAPE_MESH:
		if (shape->mesh == NULL || shape->mesh->node_count == 0) {
			return false;
		}
		*lower = shape->mesh->nodes[0].lower;
		*upper = shape->mesh->nodes[0].upper;
		return true;
	default:
		return false;
	}
}

bool plait_shape_sweep_general(const plait_shape *shape, vec3 p0, vec3 p1, float radius, float *toi)
{
	/* Planes and spheres are solved exactly in shape.h. */
	vec3 normal;
	vec3 motion = v3_sub(p1, p0);
	float travel = v3_length(motion);
	/* Stop advancing within a small fraction of the radius (or of the path for radius 0). */
	float tolerance = plait_maxf(1e-3f * radius, 1e-6f * (travel + 1.0f));
	float t = 0.0f;
	for (int step = 0; step < 64; ++step) {
		vec3 p = v3_mul_add(p0, t, motion);
		float gap = plait_shape_distance(shape, p, &normal) - radius;
		if (gap <= tolerance) {
			*toi = t;
			return true;
		}
		if (travel <= 0.0f) {
			return false;
		}
		t += gap / travel;
		if (t > 1.0f) {
			return false;
		}
	}
	/* Still approaching after many steps: a grazing path. Report the (safe) point reached. */
	*toi = t;
	return true;
}
