#include "dynamics/surface_contact.h"

#include <string.h>

#include "collision/ccd.h"
#include "collision/mesh_shape.h"

bool plait_sim_reserve_surfaces(plait_sim *sim, int count)
{
	int needed = sim->surface_count + count;
	if (needed <= sim->surface_capacity) {
		return true;
	}
	int capacity = needed < 8 ? 8 : 2 * needed;
	plait_surface *bigger = plait_alloc_zero(&sim->allocator, (size_t)capacity, sizeof *bigger);
	if (bigger == NULL) {
		return false;
	}
	if (sim->surface_count > 0) {
		memcpy(bigger, sim->surfaces, sizeof *bigger * (size_t)sim->surface_count);
	}
	plait_free(&sim->allocator, sim->surfaces);
	sim->surfaces = bigger;
	sim->surface_capacity = capacity;
	return true;
}

/* Boxes of the hierarchy around the triangles' paths over the substep, grown by `grow`. Nodes
 * are stored parents before children, so one backward pass refits the tree. */
static void refit(plait_mesh_shape *shape, const plait_particles *p, int first, float grow)
{
	vec3 margin = {grow, grow, grow};
	for (int n = shape->node_count - 1; n >= 0; --n) {
		plait_bvh_node *node = &shape->nodes[n];
		vec3 lower = {INFINITY, INFINITY, INFINITY}, upper = {-INFINITY, -INFINITY, -INFINITY};
		if (node->count > 0) {
			for (int k = node->first; k < node->first + node->count; ++k) {
				const int *tri = shape->triangles[shape->triangle_order[k]];
				for (int c = 0; c < 3; ++c) {
					int i = first + tri[c];
					lower = v3_min(lower, v3_min(p->point[i].x, p->x_prev[i]));
					upper = v3_max(upper, v3_max(p->point[i].x, p->x_prev[i]));
				}
			}
			lower = v3_sub(lower, margin);
			upper = v3_add(upper, margin);
		} else {
			const plait_bvh_node *left = &shape->nodes[node->first], *right = &shape->nodes[node->first + 1];
			lower = v3_min(left->lower, right->lower);
			upper = v3_max(left->upper, right->upper);
		}
		node->lower = lower;
		node->upper = upper;
	}
}

static vec3 blend(vec3 a, vec3 b, vec3 c, const float *weights)
{
	return v3_add(v3_add(v3_scale(a, weights[0]), v3_scale(b, weights[1])), v3_scale(c, weights[2]));
}

/* Whether the path of vertex i over the substep comes within distance_needed of the moving
 * triangle (the conservative continuous test: never a miss). */
static bool swept_through(const plait_particles *p, int i, const int *corners, float distance_needed)
{
	plait_ccd_motion_float m;
	vec3 start[4] = {p->x_prev[i], p->x_prev[corners[0]], p->x_prev[corners[1]], p->x_prev[corners[2]]};
	vec3 end[4] = {p->point[i].x, p->point[corners[0]].x, p->point[corners[1]].x, p->point[corners[2]].x};
	for (int k = 0; k < 4; ++k) {
		m.start[k][0] = start[k].x;
		m.start[k][1] = start[k].y;
		m.start[k][2] = start[k].z;
		m.end[k][0] = end[k].x;
		m.end[k][1] = end[k].y;
		m.end[k][2] = end[k].z;
	}
	float toi;
	return plait_ccd_vertex_face_float(&m, distance_needed, 1e-4f, 1.0f, &toi);
}

/* Resolves vertex i against triangle (world indices) corners; returns true if it moved them.
 * The vertex must end on the side of the triangle it started on, at least distance_needed
 * from it. Where its end lies over the face, the plane says which side it is on; where it lies
 * beside the triangle, it is pushed only if within reach, or if the continuous test finds that
 * its path crossed the thickened triangle during the substep. */
static bool resolve_pair(plait_particles *p, int i, const int *corners, float distance_needed, float friction,
                         bool fast)
{
	vec3 a = p->point[corners[0]].x, b = p->point[corners[1]].x, c = p->point[corners[2]].x;
	vec3 a0 = p->x_prev[corners[0]], b0 = p->x_prev[corners[1]], c0 = p->x_prev[corners[2]];
	int region;
	float start_weights[3];
	vec3 q0 = plait_closest_point_on_triangle(p->x_prev[i], a0, b0, c0, &region, start_weights);
	vec3 face0 = v3_normalize(v3_cross(v3_sub(b0, a0), v3_sub(c0, a0)));
	float weights[3];
	vec3 q = plait_closest_point_on_triangle(p->point[i].x, a, b, c, &region, weights);
	vec3 face = v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
	if (v3_length_sq(face) == 0.0f || v3_length_sq(face0) == 0.0f) {
		return false;
	}
	float side = v3_dot(v3_sub(p->x_prev[i], q0), face0) >= 0.0f ? 1.0f : -1.0f;
	vec3 n = v3_scale(face, side);
	float distance = v3_dot(v3_sub(p->point[i].x, q), n);
	float reach = v3_length(v3_sub(p->point[i].x, q));
	bool beside = region != 0 && reach >= distance_needed;
	/* Ending beside the triangle out of reach, or far behind its plane, is a crossing only if
	 * the path really went through the thickened triangle: ask the continuous test. (A vertex
	 * may end behind the plane of a triangle it never touched, having gone round the sheet.) */
	if (beside || distance < -distance_needed) {
		if (beside && !fast) {
			return false;
		}
		if (!swept_through(p, i, corners, distance_needed)) {
			return false;
		}
	} else if (region != 0) {
		/* Within reach of an edge or corner: apart along the line to it (for a vertex in the
		 * sheet's own plane, that is within the plane, not out of it). */
		if (reach > 1e-7f) {
			n = v3_scale(v3_sub(p->point[i].x, q), 1.0f / reach);
		}
		distance = reach;
	}
	float depth = distance_needed - distance;
	if (depth <= 0.0f) {
		return false;
	}
	/* A vertex that rested on a plane collider (the ground, a table) in the last substep is
	 * held by it against being pushed into it: it does not give way in that direction (the
	 * plane would only push it back), which lets layers stack on the ground. Pushed away from
	 * it, it moves as usual; were every participant held, the real masses decide. Curved
	 * colliders do not hold: on them the last normal is a poor guide where cloth folds, and
	 * holding there tangled draped cloths. */
	const vec3 *toward = p->contact_normal;
	float wi = p->point[i].w, wk[3];
	bool i_held = (p->flags[i] & PLAIT_PARTICLE_SUPPORTED) && v3_dot(n, toward[i]) < 0.0f;
	bool k_held[3];
	bool any_free = !i_held && wi > 0.0f;
	for (int k = 0; k < 3; ++k) {
		wk[k] = p->point[corners[k]].w;
		k_held[k] = (p->flags[corners[k]] & PLAIT_PARTICLE_SUPPORTED) && v3_dot(n, toward[corners[k]]) > 0.0f;
		any_free = any_free || (!k_held[k] && wk[k] > 0.0f);
	}
	if (any_free) {
		wi = i_held ? 0.0f : wi;
		for (int k = 0; k < 3; ++k) {
			wk[k] = k_held[k] ? 0.0f : wk[k];
		}
	}
	float denominator = wi;
	for (int k = 0; k < 3; ++k) {
		denominator += weights[k] * weights[k] * wk[k];
	}
	if (!(denominator > 0.0f)) {
		return false;
	}
	/* Friction on the relative tangential motion of the substep, within friction x depth. */
	vec3 relative =
	    v3_sub(v3_sub(p->point[i].x, p->x_prev[i]),
	           v3_sub(blend(p->point[corners[0]].x, p->point[corners[1]].x, p->point[corners[2]].x, weights),
	                  blend(p->x_prev[corners[0]], p->x_prev[corners[1]], p->x_prev[corners[2]], weights)));
	vec3 tangential = v3_mul_add(relative, -v3_dot(relative, n), n);
	float tangential_length = v3_length(tangential);
	vec3 move = v3_scale(n, depth);
	if (tangential_length > 0.0f && friction > 0.0f) {
		float limit = friction * depth;
		float removed = tangential_length < limit ? 1.0f : limit / tangential_length;
		move = v3_mul_add(move, -removed, tangential);
	}
	/* Shared by inverse mass; the triangle's share spread by barycentric weight. */
	vec3 step = v3_scale(move, 1.0f / denominator);
	p->point[i].x = v3_mul_add(p->point[i].x, wi, step);
	for (int k = 0; k < 3; ++k) {
		p->point[corners[k]].x = v3_mul_add(p->point[corners[k]].x, -weights[k] * wk[k], step);
	}
	return true;
}

/* One vertex against the triangles of one surface, triangle by triangle. */
typedef struct surface_pass {
	plait_particles *p;
	int vertex, first;
	const plait_mesh_shape *shape;
	float distance_needed, friction;
	int own_vertex; /* the vertex's index in this cloth when it is one of its own, else -1 */
	int contacts;
} surface_pass;

static float friction_of(const plait_material *a, const plait_material *b)
{
	float friction = 0.5f * (a->friction + b->friction);
	return friction > 1.0f ? 1.0f : friction;
}

static void visit_triangle(int t, void *context)
{
	surface_pass *pass = context;
	const int *tri = pass->shape->triangles[t];
	int corners[3] = {pass->first + tri[0], pass->first + tri[1], pass->first + tri[2]};
	plait_particles *p = pass->p;
	int i = pass->vertex;
	float distance_needed = pass->distance_needed;
	if (pass->own_vertex >= 0) {
		/* Self-collision: never against a triangle of the vertex itself, nor against one that
		 * was within twice the contact distance of it in the rest shape (so neighbours, and a
		 * cloth modelled folded, do not push apart: seed 000 §4.5). */
		if (tri[0] == pass->own_vertex || tri[1] == pass->own_vertex || tri[2] == pass->own_vertex) {
			return;
		}
		const vec3 *rest = pass->shape->positions;
		int region;
		vec3 q = plait_closest_point_on_triangle(rest[pass->own_vertex], rest[tri[0]], rest[tri[1]],
		                                         rest[tri[2]], &region, NULL);
		float rest_separation = v3_length(v3_sub(rest[pass->own_vertex], q));
		/* Neighbours in the rest shape lie nearly in one plane, where "which side" is ill
		 * defined and pushing makes cloth buckle and gain energy; they are left to the
		 * cloth's own stretch and bend. */
		if (rest_separation < 2.0f * distance_needed) {
			return;
		}
	}
	/* Fast relative motion may cross a triangle and end beside it: checked continuously. */
	vec3 relative =
	    v3_sub(v3_sub(p->point[i].x, p->x_prev[i]), v3_sub(p->point[corners[0]].x, p->x_prev[corners[0]]));
	bool fast = v3_length(relative) >= distance_needed;
	pass->contacts += resolve_pair(p, i, corners, distance_needed, pass->friction, fast);
}

int plait_collide_surfaces(plait_sim *sim)
{
	plait_particles *p = &sim->particles;
	float max_radius = 0.0f;
	for (int i = 0; i < p->count; ++i) {
		max_radius = plait_maxf(max_radius, p->radius[i]);
	}
	int contacts = 0;
	for (int s = 0; s < sim->surface_count; ++s) {
		plait_surface *surface = &sim->surfaces[s];
		const plait_material *surface_material = &sim->materials[surface->material];
		bool self = surface_material->self_collide;
		bool others = sim->settings.cloth_contacts && p->count > surface->shape->vertex_count;
		if (!surface_material->collide || (!others && !self)) {
			continue; /* nothing to touch it */
		}
		float thickness = surface_material->thickness;
		/* Grown by the thickest possible pair, so a vertex is found from its own swept box. */
		refit(surface->shape, p, surface->first, thickness + max_radius);
		int last = surface->first + surface->shape->vertex_count;
		for (int i = 0; i < p->count; ++i) {
			bool own = i >= surface->first && i < last;
			if (!(p->flags[i] & PLAIT_PARTICLE_COLLIDE) || (own && !self) || (!own && !others)) {
				continue;
			}
			const plait_material *mat = &sim->materials[p->material[i]];
			if (!mat->collide) {
				continue;
			}
			surface_pass pass = {p,
			                     i,
			                     surface->first,
			                     surface->shape,
			                     p->radius[i] + thickness,
			                     friction_of(mat, surface_material),
			                     own ? i - surface->first : -1,
			                     0};
			plait_mesh_shape_visit(surface->shape, v3_min(p->point[i].x, p->x_prev[i]),
			                       v3_max(p->point[i].x, p->x_prev[i]), false, visit_triangle, &pass);
			contacts += pass.contacts;
		}
	}
	return contacts;
}
