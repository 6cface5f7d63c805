/* Geometry of primitive pairs (pair_type, points in contact_pair order): their distance, cheap
 * lower bounds of it, and whether their straight paths over a substep may meet. */
#include "dynamics/mesh_contact_internal.h"

#include "collision/ccd.h"
#include "collision/closest.h"

float plait_mesh_contacts_primitive_distance(int type, const vec3 *x)
{
	switch (type) {
	case PAIR_VERTEX_FACE: {
		int region;
		vec3 q = plait_closest_point_on_triangle(x[0], x[1], x[2], x[3], &region, NULL);
		return v3_length(v3_sub(x[0], q));
	}
	case PAIR_EDGE_EDGE: {
		float s, t;
		return sqrtf(plait_closest_segments(x[0], x[1], x[2], x[3], &s, &t));
	}
	case PAIR_VERTEX_EDGE:
		return v3_length(v3_sub(x[0], v3_lerp(x[1], x[2], plait_closest_on_segment(x[0], x[1], x[2]))));
	default:
		return v3_length(v3_sub(x[0], x[1]));
	}
}

/* Cheap lower bounds of plait_mesh_contacts_primitive_distance (closest.h), less a rounding
 * allowance (scene units, well under every margin): most pairs the traversals meet are neighbours
 * in the cloth, about an edge apart, and these settle them without the closest points. */
float plait_mesh_contacts_distance_lower_bound(int type, const vec3 *x)
{
	switch (type) {
	case PAIR_VERTEX_FACE: {
		vec3 c = v3_scale(v3_add(v3_add(x[1], x[2]), x[3]), 1.0f / 3.0f);
		return plait_point_triangle_gap(x[0], x + 1, c, plait_triangle_normal(x + 1)) - REJECT_SLACK;
	}
	case PAIR_EDGE_EDGE:
		return plait_segments_gap(x[0], x[1], x[2], x[3]) - REJECT_SLACK;
	case PAIR_VERTEX_EDGE:
		return plait_segments_gap(x[0], x[0], x[1], x[2]) - REJECT_SLACK;
	default:
		return v3_length(v3_sub(x[0], x[1])) - REJECT_SLACK;
	}
}

/* Whether the pair's primitives, moving on straight lines from start to end, come within
 * distance of each other (the conservative test: never a miss). */
bool plait_mesh_contacts_paths_meet(int type, const vec3 *start, const vec3 *end, float distance)
{
	/* Vertex-edge is an edge-edge test with a zero-length first edge; vertex-vertex one with
	 * two. */
	static const int source[4][4] = {{0, 1, 2, 3}, {0, 1, 2, 3}, {0, 0, 1, 2}, {0, 0, 1, 1}};
	plait_ccd_motion_float m;
	for (int k = 0; k < 4; ++k) {
		int q = source[type][k];
		m.start[k][0] = start[q].x;
		m.start[k][1] = start[q].y;
		m.start[k][2] = start[q].z;
		m.end[k][0] = end[q].x;
		m.end[k][1] = end[q].y;
		m.end[k][2] = end[q].z;
	}
	float toi;
	if (type == PAIR_VERTEX_FACE) {
		return plait_ccd_vertex_face_float(&m, distance, 1e-2f, 1.0f, &toi);
	}
	return plait_ccd_edge_edge_float(&m, distance, 1e-2f, 1.0f, &toi);
}

/* How much the distance between the primitives can change over the substep. Distances do not
 * change when everything moves together, so motions count relative to the first vertex's;
 * relative to that, the distance changes no faster than the largest motion of a point of the
 * first primitive plus that of the second (the distance is 1-Lipschitz in every vertex). */
float plait_mesh_contacts_largest_motion(int type, const vec3 *start, const vec3 *end)
{
	float first = 0.0f, second = 0.0f;
	int n = pair_size[type];
	int first_count = type == PAIR_EDGE_EDGE ? 2 : 1;
	vec3 common = v3_sub(end[0], start[0]);
	for (int k = 1; k < n; ++k) {
		float d = v3_length(v3_sub(v3_sub(end[k], start[k]), common));
		if (k < first_count) {
			first = plait_maxf(first, d);
		} else {
			second = plait_maxf(second, d);
		}
	}
	return first + second;
}

/* Whether a lower bound of the distance between the primitives over the substep exceeds
 * `distance`: from the cheap bounds first, from the closest points when they do not settle
 * it. */
bool plait_mesh_contacts_paths_apart(int type, const vec3 *start, const vec3 *end, float distance)
{
	float motion = plait_mesh_contacts_largest_motion(type, start, end);
	float quick = plait_mesh_contacts_distance_lower_bound(type, start) +
	              plait_mesh_contacts_distance_lower_bound(type, end) - motion;
	if (0.5f * quick > distance) {
		return true;
	}
	float d0 = plait_mesh_contacts_primitive_distance(type, start),
	      d1 = plait_mesh_contacts_primitive_distance(type, end);
	return 0.5f * (d0 + d1 - motion) > distance;
}
