#include "dynamics/mesh_contact.h"

#include "collision/closest.h"
#include "dynamics/contact.h"
#include "dynamics/mesh_contact_internal.h"

#include <string.h>

bool plait_mesh_contacts_prepare(plait_sim *sim, bool *active)
{
	*active = false;
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc == NULL) {
		mc = plait_alloc_zero(&sim->allocator, 1, sizeof *mc);
		if (mc == NULL) {
			return false;
		}
		sim->mesh_contacts = mc;
		sim->mesh_contacts_dirty = true;
		mc->cull_flat = true;
		mc->cull_cross = true;
		mc->cull_own = true;
		mc->skip_smooth = true;
		mc->plan_list = -1;
		mc->plan_failed_list = -1;
		mc->element_flat_serial = -1;
		mc->patches_fitted_for = -1;
	}
	if (sim->mesh_contacts_dirty || mc->rebuild_untangled) {
		if (sim->mesh_contacts_dirty && mc->tangled != NULL) {
			/* Particles may have been renumbered: what was tangled is forgotten. */
			memset(mc->tangled, 0, (size_t)mc->particle_capacity);
			mc->ever_tangled = false;
		}
		mc->rebuild_untangled = false;
		mc->list_valid = false;
		mc->pair_count = 0;
		mc->list_changes += 1;
		sim->mesh_contacts_dirty_objects = true;
		if (!plait_mesh_contacts_build_elements(sim, mc)) {
			return false;
		}
		mc->tangle_check_due = true; /* objects came or went: they may begin tangled */
		sim->mesh_contacts_dirty = false;
	}
	if (mc->active && !plait_mesh_contacts_reserve_particles(sim, mc)) {
		return false;
	}
	if (mc->active && sim->mesh_contacts_dirty_objects) {
		for (int i = 0; i < sim->particles.count; ++i) {
			mc->object_of[i] = -1;
		}
		for (int k = 0; k < mc->object_count; ++k) {
			const collision_object *o = &mc->objects[k];
			for (int e = o->first; e < o->first + o->count; ++e) {
				for (int q = 0; q < mc->elements[e].size; ++q) {
					mc->object_of[mc->elements[e].v[q]] = k;
				}
			}
		}
		sim->mesh_contacts_dirty_objects = false;
	}
	mc->restitution = false;
	for (int k = 0; k < mc->object_count; ++k) {
		const plait_material *m = &sim->materials[mc->objects[k].material];
		mc->restitution = mc->restitution || m->bounce > 0.0f || m->stickiness > 0.0f;
	}
	*active = mc->active;
	return true;
}

bool plait_mesh_contacts_restitution(const plait_sim *sim)
{
	const plait_mesh_contacts *mc = sim->mesh_contacts;
	return sim->mesh_contacts_active && mc != NULL && mc->restitution;
}

void plait_mesh_contacts_destroy(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc == NULL) {
		return;
	}
	const plait_allocator *a = &sim->allocator;
	plait_mesh_contacts_free_elements(mc, a);
	plait_free(a, mc->pairs);
	plait_mesh_contacts_free_carried(mc, a);
	plait_free(a, mc->carry_head);
	plait_free(a, mc->zone_parent);
	plait_free(a, mc->touched);
	plait_free(a, mc->members);
	plait_free(a, mc->x_gather);
	plait_free(a, mc->sweep_end);
	plait_free(a, mc->sweep_motion);
	plait_free(a, mc->path_lower);
	plait_free(a, mc->path_upper);
	plait_free(a, mc->motion);
	plait_free(a, mc->path_end);
	plait_free(a, mc->around);
	plait_free(a, mc->guard);
	plait_free(a, mc->restitution_sum);
	plait_free(a, mc->restitution_weight);
	plait_free(a, mc->tangled);
	plait_free(a, mc->tangle_pushes);
	plait_free(a, mc->tangle_links);
	plait_free(a, mc->object_of);
	plait_mesh_contacts_free_pieces(mc, a);
	plait_mesh_contacts_free_plan(mc, a);
	plait_free(a, mc);
	sim->mesh_contacts = NULL;
}

void plait_mesh_contacts_forget_list(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc != NULL) {
		mc->list_valid = false;
	}
}

bool plait_mesh_contacts_begin_substep(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc != NULL) {
		mc->gathered = false;
		mc->substep_serial += 1;
		if (sim->substep == 0) {
			plait_mesh_contacts_forget_rest_bounds(mc); /* positions may have been set between frames */
			plait_mesh_contacts_check_plan(sim, mc);    /* and pins */
		}
		if (!sim->settings.untangle) {
			/* Left as they are; searched for when untangling is turned back on. */
			if (mc->tangle_count > 0) {
				for (int i = 0; i < sim->particles.count; ++i) {
					mc->tangled[i] &= (uint8_t)~TANGLED_NOW;
				}
				mc->tangle_check_due = true;
			}
			mc->tangle_count = 0;
			mc->tangle_push_count = 0;
		} else if (mc->active && mc->tangle_check_due && !plait_mesh_contacts_find_tangles(sim, mc)) {
			return false;
		}
	}
	return true;
}

void plait_mesh_contacts_positions_set(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc != NULL) {
		mc->tangle_check_due = true;
	}
}

/* ---- Contacts -------------------------------------------------------------------------------- */

/* The share each of the pair's vertices takes of a push along n (w, its inverse mass, 0 where
 * it does not give way), and how much the push is shortened so that no vertex moves farther than
 * the pair's gap closes; returns the factor that turns the push into the step each vertex moves
 * by w g (0 when none gives way). */
static float push_shares(const plait_particles *p, const contact_pair *pair, const float *g, vec3 n,
                         pair_projection how, float *w)
{
	int count = pair_size[pair->type];
	int first_count = pair->type == PAIR_EDGE_EDGE ? 2 : 1;
	/* After the colliders' pass, which had the last word on the pair's vertices that touched a
	 * collider, those stay, and the others move only away from the collider they touched:
	 * pushing the inner of two layers on an arm toward it would put its triangles into it. */
	vec3 collider_normal = {0.0f, 0.0f, 0.0f};
	if (how == PROJECT_AFTER_COLLIDERS) {
		for (int k = 0; k < count; ++k) {
			if (p->flags[pair->v[k]] & PLAIT_PARTICLE_CONTACT) {
				collider_normal = v3_add(collider_normal, p->contact_normal[pair->v[k]]);
			}
		}
	}
	bool any_free = false;
	for (int k = 0; k < count; ++k) {
		int i = pair->v[k];
		w[k] = pair->gives_way[k < first_count ? 0 : 1] ? p->point[i].w : 0.0f;
		if (how == PROJECT_AFTER_COLLIDERS &&
		    ((p->flags[i] & PLAIT_PARTICLE_CONTACT) || !(g[k] * v3_dot(n, collider_normal) > 0.0f))) {
			w[k] = 0.0f;
			continue;
		}
		/* A vertex resting on a collider (a plane in the last substep, any collider in this one)
		 * does not give way toward it: the collider would only push it back into whatever
		 * pressed on it, and the two would cross. This lets layers stack on the ground and
		 * keeps cloth squeezed against a moving collider (an elbow) out of it. */
		bool on_collider = (p->flags[i] & (PLAIT_PARTICLE_SUPPORTED | PLAIT_PARTICLE_CONTACT)) != 0;
		bool held = on_collider && g[k] * v3_dot(n, p->contact_normal[i]) < 0.0f;
		if (held) {
			w[k] = -w[k]; /* marked; restored if every vertex is held */
		}
		any_free = any_free || w[k] > 0.0f;
	}
	float denominator = 0.0f;
	for (int k = 0; k < count; ++k) {
		w[k] = any_free ? plait_maxf(w[k], 0.0f) : fabsf(w[k]);
		denominator += w[k] * g[k] * g[k];
	}
	if (!(denominator > 0.0f)) {
		return 0.0f;
	}
	/* No vertex moves farther than the gap the pair closes: where the vertices that give way
	 * weigh little in it (one corner of a triangle whose other corners rest on a collider, its
	 * barycentric weight 0.07), closing it all would throw that corner across the cloth. One
	 * was thrown 7 cm, over the box arm's forearm, and its triangles ended wrapped through the
	 * bar (performance.md, session 27). The pair closes in later iterations, or the failsafe
	 * sees to it. */
	float largest_lever = 0.0f;
	for (int k = 0; k < count; ++k) {
		largest_lever = plait_maxf(largest_lever, fabsf(w[k] * g[k]));
	}
	float reach = largest_lever / denominator;
	return reach > 1.0f ? 1.0f / (denominator * reach) : 1.0f / denominator;
}

/* The pair's relative velocity along n: sum g_k v_k . n (< 0 when closing). */
static float normal_speed(const plait_particles *p, const contact_pair *pair, const float *g, vec3 n)
{
	vec3 relative = {0.0f, 0.0f, 0.0f};
	for (int k = 0; k < pair_size[pair->type]; ++k) {
		relative = v3_mul_add(relative, g[k], p->v[pair->v[k]]);
	}
	return v3_dot(relative, n);
}

/* The pair's sums (push_sum, rubbed) made the substep's: zeroed at its first projection in a
 * substep (plait_mesh_contacts_project_pair, before anything reads them; the untangling's pairs
 * are made anew for each push). Every collision iteration projects every listed pair, so a
 * pair's mark is never more than a substep old, and its 8 bits cannot wrap round to a stale
 * substep's. */
static void sums_of_this_substep(const plait_sim *sim, contact_pair *pair)
{
	const plait_mesh_contacts *mc = sim->mesh_contacts;
	uint8_t substep = mc != NULL ? (uint8_t)mc->substep_serial : 0;
	if (pair->sums_substep != substep) {
		pair->sums_substep = substep;
		pair->push_sum = 0.0f;
		pair->rubbed = v3(0.0f, 0.0f, 0.0f);
	}
}

/* The pair's relative motion over the substep, less its part along n (the g-weighted sum of its
 * vertices' motions since the substep's start, as its separation weighs them). */
static vec3 tangential_motion(const plait_particles *p, const contact_pair *pair, const float *g, vec3 n)
{
	vec3 relative = {0.0f, 0.0f, 0.0f};
	for (int k = 0; k < pair_size[pair->type]; ++k) {
		int i = pair->v[k];
		relative = v3_mul_add(relative, g[k], v3_sub(p->point[i].x, p->x_prev[i]));
	}
	return v3_mul_add(relative, -v3_dot(relative, n), n);
}

/* After the colliders' pass (PROJECT_AFTER_COLLIDERS), the vertices a pair moves (w != 0) are
 * marked in mc->around (all 0 between the failsafe's sweeps and outside them), to go through
 * the colliders again (plait_mesh_contacts_project_on_colliders). Pairs projected side by side
 * share no vertex that moves (mesh_contact_plan.c), so no two write one byte. */
static void note_moved_after_colliders(plait_sim *sim, const contact_pair *pair, const float *w,
                                       pair_projection how)
{
	if (how != PROJECT_AFTER_COLLIDERS) {
		return;
	}
	plait_mesh_contacts *mc = sim->mesh_contacts;
	for (int k = 0; k < pair_size[pair->type]; ++k) {
		if (w[k] != 0.0f) {
			mc->around[pair->v[k]] = 1;
		}
	}
}

/* Coulomb's law over the substep: friction takes off the pair's relative tangential motion of
 * the substep, all of it while what it took off in all (the vector `rubbed`) stays within its
 * value times all the pushes of the substep (push_sum, this one's included). The clamp is on
 * that total, as sequential impulses clamp an accumulated impulse: what the constraint
 * iterations carry to and fro between passes is taken off again without spending the limit
 * again, and a later pass may give back what an earlier one took too much of. With one push a
 * substep that is the push's own share. With each pass's own push as its limit, a push of a few
 * micrometres after stretch iterations could not hold what the substep's motion had carried:
 * cloth resting on cloth crept down a slope, 37 mm in 2 s at 20 degrees with friction 0.5.
 * tangential: the relative motion left, off the normal n. Returns the motion to take off. */
static vec3 rub(contact_pair *pair, vec3 tangential, vec3 n)
{
	vec3 total = v3_add(pair->rubbed, tangential);
	total = v3_mul_add(total, -v3_dot(total, n), n);
	float length = v3_length(total);
	float limit = pair->friction * pair->push_sum;
	if (!(length <= limit)) {
		total = length > 0.0f && limit > 0.0f ? v3_scale(total, limit / length) : v3(0.0f, 0.0f, 0.0f);
	}
	vec3 taken = v3_sub(total, pair->rubbed);
	pair->rubbed = total;
	return taken;
}

/* Moves the pair's vertices so that C = (separation along n) - distance becomes 0: the vertices
 * move along n by their inverse mass times their weight g (the constraint's gradient), and
 * friction (rub) takes off relative tangential motion of the substep. Unlike a collider's contact
 * pass, a pair rubs in contact passes too: without it a coarse sheet balanced on a mesh
 * spike's tip (friction 0.1) slid off it, and cloth slid down cloth at 35 degrees with friction
 * 0.5 as with 0.4 (performance.md, session 33). A pair whose surfaces bounce or stick notes its
 * first push of the substep, with its approach (v still holds the velocities of the substep's
 * start). */
bool plait_mesh_contacts_respond(plait_sim *sim, contact_pair *pair, const float *g, vec3 n, float c,
                                 pair_projection how)
{
	plait_particles *p = &sim->particles;
	int count = pair_size[pair->type];
	float w[4];
	float shortened = push_shares(p, pair, g, n, how, w);
	if (shortened == 0.0f) {
		return false;
	}
	float depth = -c;
	pair->push_sum += depth;
	vec3 move = v3_scale(n, depth);
	if (pair->friction > 0.0f) {
		move = v3_sub(move, rub(pair, tangential_motion(p, pair, g, n), n));
	}
	vec3 step = v3_scale(move, shortened);
	/* Only vertices that give way are written: one that never moves (inverse mass 0) may be
	 * read by pairs projected side by side (mesh_contact_plan.c). */
	for (int k = 0; k < count; ++k) {
		int i = pair->v[k];
		if (w[k] != 0.0f) {
			p->point[i].x = v3_mul_add(p->point[i].x, w[k] * g[k], step);
		}
	}
	note_moved_after_colliders(sim, pair, w, how);
	if (pair->restitutes && !pair->pushed) {
		pair->pushed = 1;
		pair->approach = normal_speed(p, pair, g, n);
	}
	return true;
}

/* Within this share of its contact distance past it, a pair pushed earlier in the substep still
 * rests on what it pressed on, and its friction still acts (contact.c's RESTING_SLACK for
 * colliders): the stretch iterations after a push lift resting cloth a little. */
#define RESTING_SLACK 0.05f

/* A pair at separation `separation` along n, not pressing: friction still takes off the
 * substep's tangential motion, within what the substep's pushes allow, if it was pushed in the
 * substep and rests within RESTING_SLACK; no push. Such a pair counts as pushed for the contact
 * passes that follow (pushed_last), as a particle resting on a collider does (contact.c,
 * rub_resting): left out, a vertex the constraints had lifted off the sheet below was not held
 * out by the next contact passes while its neighbours were, the constraints carried part of its
 * weight, and a sheet on a sheet on a slope below its friction angle crept down it. */
static void rub_resting(plait_sim *sim, contact_pair *pair, const float *g, vec3 n, float separation,
                        pair_projection how)
{
	if (how == PROJECT_AGAIN || !(separation < pair->distance * (1.0f + RESTING_SLACK)) ||
	    !(pair->push_sum > 0.0f)) {
		return;
	}
	pair->pushed_last = 1;
	if (!(pair->friction > 0.0f)) {
		return;
	}
	plait_particles *p = &sim->particles;
	float w[4];
	float shortened = push_shares(p, pair, g, n, how, w);
	if (shortened == 0.0f) {
		return;
	}
	vec3 step = v3_scale(rub(pair, tangential_motion(p, pair, g, n), n), -shortened);
	for (int k = 0; k < pair_size[pair->type]; ++k) {
		if (w[k] != 0.0f) {
			int i = pair->v[k];
			p->point[i].x = v3_mul_add(p->point[i].x, w[k] * g[k], step);
		}
	}
	note_moved_after_colliders(sim, pair, w, how);
}

/* For an edge-edge, vertex-edge or vertex-vertex pair at points x: the vector from the second
 * primitive's closest point to the first's, and the weights g of the vertices in it. */
static vec3 closest_between(int type, const vec3 *x, float *g)
{
	if (type == PAIR_EDGE_EDGE) {
		float s, t;
		plait_closest_segments(x[0], x[1], x[2], x[3], &s, &t);
		g[0] = 1.0f - s;
		g[1] = s;
		g[2] = -(1.0f - t);
		g[3] = -t;
		return v3_sub(v3_lerp(x[0], x[1], s), v3_lerp(x[2], x[3], t));
	}
	if (type == PAIR_VERTEX_EDGE) {
		float t = plait_closest_on_segment(x[0], x[1], x[2]);
		g[0] = 1.0f;
		g[1] = -(1.0f - t);
		g[2] = -t;
		return v3_sub(x[0], v3_lerp(x[1], x[2], t));
	}
	g[0] = 1.0f;
	g[1] = -1.0f;
	return v3_sub(x[0], x[1]);
}

int plait_mesh_contacts_project_pair(plait_sim *sim, contact_pair *pair, pair_projection how, int *ccd_hits)
{
	plait_particles *p = &sim->particles;
	int type = pair->type, n = pair_size[type];
	const plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc != NULL && mc->tangle_count > 0 &&
	    plait_mesh_contacts_pair_tangled(mc, type, pair->v, TANGLED_NOW)) {
		return 0; /* where surfaces begin through each other, their start side is no truth */
	}
	sums_of_this_substep(sim, pair);
	vec3 x[4];
	gather_current(p->point, pair->v, n, x);
	float g[4];
	vec3 normal;
	float separation;
	if (type == PAIR_VERTEX_FACE) {
		int region;
		float weights[3];
		vec3 q = plait_closest_point_on_triangle(x[0], x[1], x[2], x[3], &region, weights);
		vec3 face = v3_cross(v3_sub(x[2], x[1]), v3_sub(x[3], x[1]));
		float face_length = v3_length(face);
		if (!(face_length > 0.0f)) {
			return 0;
		}
		face = v3_scale(face, 1.0f / face_length);
		vec3 r = v3_sub(x[0], q);
		float along = v3_dot(r, face) * pair->side;
		float reach = v3_length(r);
		g[0] = 1.0f;
		g[1] = -weights[0];
		g[2] = -weights[1];
		g[3] = -weights[2];
		if (region != 0 && reach >= pair->distance && along >= 0.0f) {
			/* Beside the triangle, out of reach, on its side. */
			if (reach > 1e-9f) {
				rub_resting(sim, pair, g, v3_scale(r, 1.0f / reach), reach, how);
			}
			return 0;
		}
		bool crossed = false;
		if (along < 0.0f) {
			/* On the other side of the plane: through the triangle, or round it? */
			vec3 start[4];
			gather_points(p->x_prev, pair->v, n, start);
			crossed = plait_mesh_contacts_paths_meet(type, start, x, 0.0f);
			if (crossed) {
				*ccd_hits += 1;
			} else {
				pair->side = -pair->side;
				along = -along;
			}
		}
		if (region == 0 || crossed) {
			normal = v3_scale(face, pair->side);
			separation = along;
		} else {
			normal = reach > 1e-9f ? v3_scale(r, 1.0f / reach) : v3_scale(face, pair->side);
			separation = reach;
		}
	} else {
		vec3 r = closest_between(type, x, g);
		float length = v3_length(r);
		if (length >= pair->distance && v3_dot(r, pair->direction) >= 0.0f) {
			if (length > 1e-9f) {
				rub_resting(sim, pair, g, v3_scale(r, 1.0f / length), length, how);
			}
			return 0;
		}
		bool crossed = false;
		if (v3_dot(r, pair->direction) < 0.0f) {
			vec3 start[4];
			gather_points(p->x_prev, pair->v, n, start);
			crossed = plait_mesh_contacts_paths_meet(type, start, x, 0.0f);
			*ccd_hits += crossed;
		}
		if (crossed) {
			normal = pair->direction;
			separation = v3_dot(r, normal);
		} else {
			normal = length > 1e-9f ? v3_scale(r, 1.0f / length) : pair->direction;
			separation = length;
			pair->direction = normal;
		}
	}
	if (separation >= pair->distance) {
		rub_resting(sim, pair, g, normal, separation, how);
		return 0;
	}
	return plait_mesh_contacts_respond(sim, pair, g, normal, separation - pair->distance, how);
}

/* ---- Bounce and stickiness ------------------------------------------------------------------ */

/* The pair's separation at points x along the line between its closest points, oriented as
 * its projection orients it (vertex-face: the side it is on, through the face when the vertex
 * is over it; the others: their last direction when the points meet), with the weights g of
 * its vertices in that separation. */
static float pair_geometry(const contact_pair *pair, const vec3 *x, float *g, vec3 *normal)
{
	vec3 r;
	if (pair->type == PAIR_VERTEX_FACE) {
		int region;
		float weights[3];
		vec3 q = plait_closest_point_on_triangle(x[0], x[1], x[2], x[3], &region, weights);
		vec3 face = v3_normalize(v3_cross(v3_sub(x[2], x[1]), v3_sub(x[3], x[1])));
		g[0] = 1.0f;
		g[1] = -weights[0];
		g[2] = -weights[1];
		g[3] = -weights[2];
		r = v3_sub(x[0], q);
		if (region == 0 || !(v3_length(r) > 1e-9f)) {
			*normal = v3_scale(face, pair->side);
			return v3_dot(r, *normal);
		}
	} else {
		r = closest_between(pair->type, x, g);
		if (!(v3_length(r) > 1e-9f)) {
			*normal = pair->direction;
			return 0.0f;
		}
	}
	float length = v3_length(r);
	*normal = v3_scale(r, 1.0f / length);
	return length;
}

/* The mean of a pair's two surfaces' bounce and stickiness (seed 000 §5.5: a contact's surface
 * values are the two objects' mean). */
static void pair_surfaces(const plait_sim *sim, const plait_mesh_contacts *mc, const contact_pair *pair,
                          float *bounce, float *stickiness)
{
	int second = pair->type == PAIR_EDGE_EDGE ? 2 : 1;
	const plait_material *a = &sim->materials[mc->objects[mc->object_of[pair->v[0]]].material];
	const plait_material *b = &sim->materials[mc->objects[mc->object_of[pair->v[second]]].material];
	*bounce = 0.5f * (a->bounce + b->bounce);
	*stickiness = 0.5f * (a->stickiness + b->stickiness);
}

/* Whether the pair acts at the substep's end: it pushed in the substep, or (for stickiness) began
 * it within its contact distance, as a collider's contact does; *pushed says which. */
static bool restitution_acts(const plait_particles *p, contact_pair *pair, float stickiness, bool *pushed)
{
	*pushed = pair->pushed;
	pair->pushed = 0;
	if (*pushed || !(stickiness > 0.0f)) {
		return *pushed;
	}
	vec3 x[4];
	float g[4];
	vec3 normal;
	gather_points(p->x_prev, pair->v, pair_size[pair->type], x);
	return pair_geometry(pair, x, g, &normal) <= pair->distance;
}

void plait_mesh_contacts_restitute(plait_sim *sim)
{
	if (!plait_mesh_contacts_restitution(sim)) {
		return;
	}
	plait_mesh_contacts *mc = sim->mesh_contacts;
	plait_particles *p = &sim->particles;
	float resting_speed = plait_resting_speed(sim);
	/* Every pair asks its change of the velocities the substep ended with, and each vertex takes
	 * the mean of what its pairs ask of it, weighted by its share in each (Jacobi). One pair
	 * after another instead (Gauss-Seidel), a vertex met by several (its face pairs and its
	 * edges' pairs, landing flat) takes the change once from the first and again, shared with a
	 * neighbour that has not, from the next: a sheet dropped 0.3 m onto a cloth climbed back
	 * 0.52 m at bounce 1. */
	for (int k = 0; k < mc->pair_count; ++k) {
		contact_pair *pair = &mc->pairs[k];
		if (!pair->restitutes) {
			continue;
		}
		float bounce, stickiness;
		pair_surfaces(sim, mc, pair, &bounce, &stickiness);
		bool pushed;
		/* (A pair only the failsafe watches, distance 0, pushes back only when it crossed: no
		 * contact.) */
		if (!restitution_acts(p, pair, stickiness, &pushed) || pair->distance <= 0.0f) {
			continue;
		}
		int n = pair_size[pair->type];
		vec3 x[4];
		float g[4];
		vec3 normal;
		gather_current(p->point, pair->v, n, x);
		(void)pair_geometry(pair, x, g, &normal);
		float speed = normal_speed(p, pair, g, normal);
		float change = 0.0f;
		if (pushed && bounce > 0.0f && pair->approach < -resting_speed) {
			/* Elastic in the share `bounce`: it leaves at that share of the speed it came at. */
			change = plait_maxf(-bounce * pair->approach - speed, 0.0f);
		} else if (speed > 0.0f && stickiness > 0.0f) {
			change = -stickiness * speed;
		}
		float w[4];
		float shortened = change != 0.0f ? push_shares(p, pair, g, normal, PROJECT_FULL, w) : 0.0f;
		if (shortened == 0.0f) {
			continue;
		}
		/* Shared as the pair's pushes are: its relative normal speed would change by `change`
		 * (less where a light vertex would take it all). */
		for (int q = 0; q < n; ++q) {
			int i = pair->v[q];
			float share = fabsf(g[q]);
			if (w[q] != 0.0f && share > 0.0f) {
				mc->restitution_sum[i] =
				    v3_mul_add(mc->restitution_sum[i], share * w[q] * g[q] * change * shortened, normal);
				mc->restitution_weight[i] += share;
			}
		}
	}
	for (int k = 0; k < mc->pair_count; ++k) {
		const contact_pair *pair = &mc->pairs[k];
		if (!pair->restitutes) {
			continue;
		}
		for (int q = 0; q < pair_size[pair->type]; ++q) {
			int i = pair->v[q];
			if (mc->restitution_weight[i] > 0.0f) {
				p->v[i] = v3_mul_add(p->v[i], 1.0f / mc->restitution_weight[i], mc->restitution_sum[i]);
				mc->restitution_sum[i] = v3(0.0f, 0.0f, 0.0f);
				mc->restitution_weight[i] = 0.0f;
			}
		}
	}
}

/* After a collision iteration's pass over the colliders, which has the last word, the pairs with
 * a vertex on a collider are projected once more. The colliders pushed the lower of two resting
 * layers up into the upper one after the pairs had pushed them apart, and their friction held
 * the lower one back where the substep's motion had carried both (down a slope), while the pairs
 * had found the two moving together and taken nothing off. Left to the next substep, the upper
 * layer bounced on the lower in a cycle of two substeps, pressing lightly in every other one,
 * and slid in those: a sheet on a sheet on a 20 degree slope, friction 0.5, crept 37 mm in 2 s.
 * Vertices on a collider stay, the others move only away from it (push_shares), and those moved
 * go through the colliders again (plait_collide_listed_with_colliders, in the failsafe's
 * scratch, which is empty between its runs): on the arm, a vertex pushed away from one capsule
 * ended in the other one. In the plan's order and on the workers, as the collision iteration's
 * projection. */
int plait_mesh_contacts_project_on_colliders(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc == NULL || !mc->active || mc->pair_count == 0 || mc->tangle_count > 0) {
		return 0;
	}
	int contacts = plait_mesh_contacts_project_list(sim, mc, PROJECT_AFTER_COLLIDERS);
	int count = sim->particles.count;
	for (int i = 0; i < count; ++i) {
		if (mc->around[i]) {
			mc->around[i] = 0;
			mc->zone_parent[i] = i;
			mc->touched[mc->touched_count++] = i;
		}
	}
	if (mc->touched_count > 0) {
		contacts +=
		    plait_collide_listed_with_colliders(sim, mc->touched, &mc->touched_count, mc->zone_parent);
		for (int k = 0; k < mc->touched_count; ++k) {
			mc->zone_parent[mc->touched[k]] = -1;
		}
		mc->touched_count = 0;
	}
	return contacts;
}

void plait_mesh_contacts_project_again(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc != NULL && mc->active && mc->pair_count > 0 && mc->tangle_count == 0) {
		(void)plait_mesh_contacts_project_list(sim, mc, PROJECT_AGAIN);
	}
}

int plait_mesh_contacts_project(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc == NULL || !mc->active) {
		return 0;
	}
	if (!mc->gathered) {
		/* A list that holds but for a few vertices pushed off their paths is mended around
		 * them, unless a gather is expected to meet fewer element pairs (a cloth falling free,
		 * whose flat patches a gather passes over whole, while a mending meets each strayed
		 * vertex's neighbours); otherwise it is gathered again. */
		int strays = 0, count = sim->particles.count;
		bool holds = plait_mesh_contacts_list_covers_except(sim, mc, mc->around, &strays);
		if (mc->list_valid && mc->substep_serial - mc->gather_serial == 1) {
			/* Whether the last list's vertices kept to their paths for the substep after its
			 * gather's: if not, the next lists serve only their own substep, and reach only as
			 * far as that needs (plait_mesh_contacts_gather). */
			mc->short_lists = !mc->paths_kept;
		}
		if (holds && plait_mesh_contacts_few_strays(strays, count) && plait_mesh_contacts_mending_pays(mc)) {
			plait_mesh_contacts_relist_around(sim, mc);
		} else if (!holds || strays > 0) {
			plait_mesh_contacts_gather(sim, mc);
		}
		if (strays > 0) {
			memset(mc->around, 0, (size_t)count);
		}
		mc->gathered = true;
	}
	int contacts = plait_mesh_contacts_project_list(sim, mc, PROJECT_FULL);
	if (mc->tangle_push_count > 0) {
		contacts += plait_mesh_contacts_push_through(sim, mc);
	}
	return contacts;
}
