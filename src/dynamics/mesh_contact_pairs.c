/* Which primitive pairs exist: each element pair the traversals meet is walked for the primitive
 * pairs it owns, and each of those is handled as the pass's stage asks (rest pairs, listing,
 * the failsafe's sweep). */
#include "dynamics/mesh_contact_internal.h"

#include <string.h>

#include "collision/closest.h"
#include "dynamics/contact.h"

/* The slots of element pair (b, a)'s rest pairs from those of (a, b): the two elements'
 * parts swapped. */
static uint32_t swap_slots(uint32_t slots)
{
	uint32_t swapped = ((slots >> 3) & 7u) | ((slots & 7u) << 3);
	for (int k = 0; k < 3; ++k) {
		for (int m = 0; m < 3; ++m) {
			swapped |= ((slots >> VERTEX_VERTEX_SLOT(k, m)) & 1u) << VERTEX_VERTEX_SLOT(m, k);
			swapped |= ((slots >> EDGE_EDGE_SLOT(k, m)) & 1u) << EDGE_EDGE_SLOT(m, k);
		}
	}
	return swapped;
}

/* The slots of the rest pairs element pair (a, b) of one object owns, as walked from a (0:
 * none; ALL_REST_SLOTS: excluded whole). */
static uint32_t rest_slots(const plait_mesh_contacts *mc, int a, int b)
{
	if (mc->near_start == NULL) {
		return 0;
	}
	int low = a < b ? a : b, high = a < b ? b : a;
	for (int k = mc->near_start[low]; k < mc->near_start[low + 1]; ++k) {
		if (mc->near_list[k].element >= high) {
			if (mc->near_list[k].element != high) {
				return 0;
			}
			uint32_t slots = mc->near_list[k].rest_slots;
			return a < b || slots == ALL_REST_SLOTS ? slots : swap_slots(slots);
		}
	}
	return 0;
}

static bool shares_vertex(const int *v, int n)
{
	for (int i = 0; i < n; ++i) {
		for (int j = i + 1; j < n; ++j) {
			if (v[i] == v[j]) {
				return true;
			}
		}
	}
	return false;
}

static float mean_radius(const plait_particles *p, const int *v, int n)
{
	float sum = 0.0f;
	for (int k = 0; k < n; ++k) {
		sum += p->radius[v[k]];
	}
	return sum / (float)n;
}

/* Room for twice as many (at least 256): the lists below grow as their traversals meet pairs. */
static int grown_capacity(int capacity)
{
	return capacity < 256 ? 256 : 2 * capacity;
}

static bool add_pair_to(plait_sim *sim, contact_pair **pairs, int *count, int *capacity,
                        const contact_pair *pair)
{
	if (*count == *capacity) {
		int bigger_capacity = grown_capacity(*capacity);
		contact_pair *bigger =
		    plait_alloc_grow(&sim->allocator, *pairs, sizeof *bigger, *count, bigger_capacity);
		if (bigger == NULL) {
			return false;
		}
		*pairs = bigger;
		*capacity = bigger_capacity;
	}
	(*pairs)[(*count)++] = *pair;
	return true;
}

static bool add_rest_pair(plait_sim *sim, plait_mesh_contacts *mc, const rest_pair *pair)
{
	if (mc->rest_count == mc->rest_capacity) {
		int bigger_capacity = grown_capacity(mc->rest_capacity);
		rest_pair *bigger = plait_alloc_grow(&sim->allocator, mc->rest_pairs, sizeof *bigger, mc->rest_count,
		                                     bigger_capacity);
		if (bigger == NULL) {
			return false;
		}
		mc->rest_pairs = bigger;
		mc->rest_capacity = bigger_capacity;
	}
	mc->rest_pairs[mc->rest_count++] = *pair;
	return true;
}

/* The rest pairs found since `first` (those of element pair a, b) as one group. */
static bool add_rest_group(plait_sim *sim, plait_mesh_contacts *mc, int first, int a, int b)
{
	if (mc->rest_group_count == mc->rest_group_capacity) {
		int bigger_capacity = grown_capacity(mc->rest_group_capacity);
		rest_group *bigger = plait_alloc_grow(&sim->allocator, mc->rest_groups, sizeof *bigger,
		                                      mc->rest_group_count, bigger_capacity);
		if (bigger == NULL) {
			return false;
		}
		mc->rest_groups = bigger;
		mc->rest_group_capacity = bigger_capacity;
	}
	mc->rest_groups[mc->rest_group_count++] = (rest_group){first, mc->rest_count - first, a, b, -1.0f, 0.0f};
	return true;
}

static bool add_pair(pair_pass *pass, const contact_pair *pair)
{
	if (pass->fixed_capacity && *pass->out_count == *pass->out_capacity) {
		pass->full = true;
		pass->overflow += 1;
		return false;
	}
	if (!add_pair_to(pass->sim, pass->out_pairs, pass->out_count, pass->out_capacity, pair)) {
		pass->mc->out_of_memory = true;
		return false;
	}
	return true;
}

/* Whether pairs of this type within an object of material m push each other: its
 * self-collision flag's choice (seed 000 §4.5.1). The others of vertex-face and edge-edge are
 * still listed for the failsafe, which keeps the object from passing through itself whatever
 * the flag. */
static bool self_pushes(const plait_material *m, int type)
{
	switch (m->self_flag) {
	case PLAIT_SELF_COLLIDE_VERTEX:
		return type == PAIR_VERTEX_VERTEX;
	case PLAIT_SELF_COLLIDE_VERTEX_FACE:
		return type == PAIR_VERTEX_FACE;
	default:
		return type == PAIR_VERTEX_FACE || type == PAIR_EDGE_EDGE;
	}
}

/* Which side of the other primitive the first is on at the start of the substep. */
static void start_side(contact_pair *pair, const vec3 *start, const vec3 *end)
{
	if (pair->type == PAIR_VERTEX_FACE) {
		vec3 n = v3_cross(v3_sub(start[2], start[1]), v3_sub(start[3], start[1]));
		float along = v3_dot(v3_sub(start[0], start[1]), n);
		if (along == 0.0f) {
			/* In the plane: the side it comes from is the one it moves away from. */
			vec3 motion = v3_sub(v3_sub(end[0], start[0]), v3_sub(end[1], start[1]));
			along = -v3_dot(motion, n);
		}
		pair->side = along < 0.0f ? -1.0f : 1.0f;
		return;
	}
	vec3 first, second;
	if (pair->type == PAIR_EDGE_EDGE) {
		float s, t;
		plait_closest_segments(start[0], start[1], start[2], start[3], &s, &t);
		first = v3_lerp(start[0], start[1], s);
		second = v3_lerp(start[2], start[3], t);
	} else if (pair->type == PAIR_VERTEX_EDGE) {
		first = start[0];
		second = v3_lerp(start[1], start[2], plait_closest_on_segment(start[0], start[1], start[2]));
	} else {
		first = start[0];
		second = start[1];
	}
	vec3 d = v3_sub(first, second);
	float length = v3_length(d);
	if (length > 0.0f) {
		pair->direction = v3_scale(d, 1.0f / length);
	} else if (pair->type == PAIR_EDGE_EDGE &&
	           v3_length_sq(v3_cross(v3_sub(start[1], start[0]), v3_sub(start[3], start[2]))) > 0.0f) {
		pair->direction = v3_normalize(v3_cross(v3_sub(start[1], start[0]), v3_sub(start[3], start[2])));
	} else {
		pair->direction = v3(0.0f, 1.0f, 0.0f);
	}
}

/* Whether a re-listing around strayed vertices lists the pair: it has one of them (the others
 * are listed or left out as the gather left them, and still so). */
static bool relisted(const pair_pass *pass, const int *v, int n)
{
	uint8_t any = 0;
	for (int k = 0; k < n; ++k) {
		any |= pass->mc->around[v[k]];
	}
	return any != 0;
}

/* The gather's listing of a primitive pair `now` apart (end: its points now), within its list
 * distance: as a contact, or (pairs that only the failsafe watches: the self-collision flag's
 * others, and edges closest at an end) as a pair to sweep at the end of the substep. Edge
 * pairs come with their closest points' parameters. */
static void list_pair(pair_pass *pass, int type, const int *v, const vec3 *end, float now, float edge_s,
                      float edge_t, const plait_material *first, const plait_material *second, bool self)
{
	/* Edges whose closest points are an end of either are in reach of a vertex-face pair of
	 * the triangles round that end: only the failsafe watches them. */
	bool pushes = !self || self_pushes(first, type);
	bool at_end =
	    type == PAIR_EDGE_EDGE && (edge_s <= 0.0f || edge_s >= 1.0f || edge_t <= 0.0f || edge_t >= 1.0f);
	/* While the list covers, the pair's vertices stay within their guards (and its objects
	 * within their allowance) of here, so its paths stay this far apart (the failsafe's
	 * bound). A pair only the failsafe watches that stays farther apart than the failsafe's
	 * distance would never be swept (sweep_listed): it is left out, before any more work. */
	float lower = now - pass->pair_slack;
	if ((!pushes || at_end) && lower > FAILSAFE_DISTANCE) {
		return;
	}
	plait_sim *sim = pass->sim;
	plait_particles *p = &sim->particles;
	int n = pair_size[type];
	int first_count = type == PAIR_EDGE_EDGE ? 2 : 1;
	float distance = 0.0f;
	if (pushes) {
		distance = mean_radius(p, v, first_count) + mean_radius(p, v + first_count, n - first_count);
		if (self) {
			distance *= first->self_width_scale;
		}
	}
	/* Rest pairs (the failsafe watches them: mc->rest_pairs) never get here: the walk passes
	 * over their slots (rest_slots). */
	vec3 start[4] = {{0}};
	gather_points(p->x_prev, v, n, start);
	contact_pair pair = {
	    {v[0], v[1], n > 2 ? v[2] : v[1], n > 3 ? v[3] : v[1]},
	    (uint8_t)type,
	    (uint8_t)self,
	    (uint8_t)(first->bounce + second->bounce > 0.0f || first->stickiness + second->stickiness > 0.0f),
	    0,
	    0,
	    {1, 1},
	    0,
	    distance,
	    plait_combined_friction(first->friction, second->friction),
	    0.0f,
	    1.0f,
	    {0.0f, 1.0f, 0.0f},
	    0.0f,
	    {0.0f, 0.0f, 0.0f},
	    -1.0f};
	/* The thickness between two primitives never exceeds their separation at the start frame
	 * (seed 000 §4.5): a pair of two objects that started closer keeps that closeness. (Within
	 * one object such pairs are rest pairs.) */
	const plait_mesh_contacts *mc = pass->mc;
	if (distance > 0.0f && !self &&
	    !(mc->ever_tangled && plait_mesh_contacts_pair_tangled(mc, type, v, TANGLED_EVER))) {
		vec3 initial[4];
		gather_points(p->x_start, v, n, initial);
		/* The cheap bound first: most pairs of two objects started far apart. */
		if (plait_mesh_contacts_distance_lower_bound(type, initial) < distance) {
			pair.distance = plait_minf(distance, plait_mesh_contacts_primitive_distance(type, initial));
		}
	}
	if (at_end) {
		pair.distance = 0.0f;
	}
	pair.lower = lower;
	if (pair.distance <= 0.0f && pair.lower > FAILSAFE_DISTANCE) {
		return;
	}
	if (first->collision_layer != second->collision_layer) {
		pair.gives_way[first->collision_layer < second->collision_layer ? 0 : 1] = 0;
	}
	start_side(&pair, start, end);
	plait_mesh_contacts_take_carried(mc, &pair);
	(void)add_pair(pass, &pair);
}

/* A primitive pair met by the traversal: in the failsafe it is swept; at the rest stage it is
 * kept when nearer than its contact distance at the start; in the gather, the pairs of curves
 * and points (vertex-edge, vertex-vertex) are listed from here, box first (the walk lists the
 * others itself: list_face, list_edges). */
static void visit_primitives(pair_pass *pass, int type, const int *v, const plait_material *first,
                             const plait_material *second, bool self)
{
	int n = pair_size[type];
	if (shares_vertex(v, n)) {
		return;
	}
	if (pass->around_only && !relisted(pass, v, n)) {
		return;
	}
	if (pass->stage == STAGE_FAILSAFE) {
		plait_mesh_contacts_sweep_pair(pass, type, v);
		return;
	}
	plait_sim *sim = pass->sim;
	plait_mesh_contacts *mc = pass->mc;
	plait_particles *p = &sim->particles;
	int first_count = type == PAIR_EDGE_EDGE ? 2 : 1;
	if (pass->stage == STAGE_REST) {
		if (mc->ever_tangled && plait_mesh_contacts_pair_tangled(mc, type, v, TANGLED_EVER)) {
			pass->all_rest = false; /* it began crossing: its start distance is no rest */
			return;
		}
		float distance = mean_radius(p, v, first_count) + mean_radius(p, v + first_count, n - first_count);
		if (self) {
			distance *= first->self_width_scale;
		}
		vec3 initial[4] = {{0}};
		gather_points(p->x_start, v, n, initial);
		/* The cheap bound first: most pairs met are an edge apart. */
		if (plait_mesh_contacts_distance_lower_bound(type, initial) >= distance ||
		    plait_mesh_contacts_primitive_distance(type, initial) >= distance) {
			pass->all_rest = false;
			return;
		}
		pass->rest_slots |= 1u << pass->slot;
		if (type == PAIR_VERTEX_VERTEX) {
			return; /* no crossing to watch */
		}
		rest_pair pair = {{v[0], v[1], n > 2 ? v[2] : v[1], n > 3 ? v[3] : v[1]}, -1.0f, (uint8_t)type, 0};
		if (!add_rest_pair(sim, mc, &pair)) {
			pass->failed = true;
		}
		return;
	}
	bool pushes = !self || self_pushes(first, type);
	float list_distance = pushes ? pass->list_distance : pass->failsafe_reach;
	vec3 end[4] = {{0}};
	gather_current(p->point, v, n, end);
	/* Boxes first: most pairs of neighbouring elements are rejected without a distance. */
	vec3 lower_a = end[0], upper_a = end[0], lower_b = end[first_count], upper_b = end[first_count];
	for (int k = 1; k < n; ++k) {
		if (k < first_count) {
			lower_a = v3_min(lower_a, end[k]);
			upper_a = v3_max(upper_a, end[k]);
		} else {
			lower_b = v3_min(lower_b, end[k]);
			upper_b = v3_max(upper_b, end[k]);
		}
	}
	if (lower_a.x - upper_b.x > list_distance || lower_b.x - upper_a.x > list_distance ||
	    lower_a.y - upper_b.y > list_distance || lower_b.y - upper_a.y > list_distance ||
	    lower_a.z - upper_b.z > list_distance || lower_b.z - upper_a.z > list_distance) {
		return;
	}
	float now = plait_mesh_contacts_primitive_distance(type, end);
	if (now > list_distance) {
		return;
	}
	list_pair(pass, type, v, end, now, 0.0f, 0.0f, first, second, self);
}

/* Whether boxes [la, ua] and [lb, ub] are farther apart than `gap` along an axis. */
static bool boxes_apart(vec3 la, vec3 ua, vec3 lb, vec3 ub, float gap)
{
	return la.x - ub.x > gap || lb.x - ua.x > gap || la.y - ub.y > gap || lb.y - ua.y > gap ||
	       la.z - ub.z > gap || lb.z - ua.z > gap;
}

/* Whether a point is surely farther than `gap` from an element (its box, then a cheap bound). */
static bool point_far(vec3 x, const element *el, const element_shape *shape, const vec3 *t, float gap)
{
	if (boxes_apart(x, x, shape->lower, shape->upper, gap)) {
		return true;
	}
	float bound = el->size == 3   ? plait_point_triangle_gap(x, t, shape->centre, shape->normal)
	              : el->size == 2 ? plait_segments_gap(x, x, t[0], t[1])
	                              : v3_length(v3_sub(x, t[0]));
	return bound - REJECT_SLACK > gap;
}

/* Whether segments p-q and r-s are surely farther apart than `gap`. */
static bool segments_far(vec3 p, vec3 q, vec3 r, vec3 s, float gap)
{
	return boxes_apart(v3_min(p, q), v3_max(p, q), v3_min(r, s), v3_max(r, s), gap) ||
	       plait_segments_gap(p, q, r, s) - REJECT_SLACK > gap;
}

/* The gather's test of vertex v[0] at x against triangle v[1..3] at t, the walk's cheap
 * rejections passed: their distance now, then list_pair. */
static void list_face(pair_pass *pass, const int *v, vec3 x, const vec3 *t, const plait_material *first,
                      const plait_material *second, bool self)
{
	if (pass->around_only && !relisted(pass, v, 4)) {
		return;
	}
	bool pushes = !self || self_pushes(first, PAIR_VERTEX_FACE);
	vec3 end[4] = {x, t[0], t[1], t[2]};
	float now = plait_mesh_contacts_primitive_distance(PAIR_VERTEX_FACE, end);
	if (now > (pushes ? pass->list_distance : pass->failsafe_reach)) {
		return;
	}
	list_pair(pass, PAIR_VERTEX_FACE, v, end, now, 0.0f, 0.0f, first, second, self);
}

/* The gather's test of edges v[0]-v[1] (p-q) and v[2]-v[3] (r-s), the walk's cheap rejections
 * passed. Edges closest at an end of either are only watched (list_pair), within the
 * failsafe's reach: those farther off are left out before their closest points. */
static void list_edges(pair_pass *pass, const int *v, vec3 p, vec3 q, vec3 r, vec3 s,
                       const plait_material *first, const plait_material *second, bool self)
{
	if (pass->around_only && !relisted(pass, v, 4)) {
		return;
	}
	bool pushes = !self || self_pushes(first, PAIR_EDGE_EDGE);
	if (boxes_apart(v3_min(p, q), v3_max(p, q), v3_min(r, s), v3_max(r, s), pass->failsafe_reach) &&
	    !(pushes && plait_closest_segments_inside(p, q, r, s))) {
		return;
	}
	float edge_s, edge_t;
	float now = sqrtf(plait_closest_segments(p, q, r, s, &edge_s, &edge_t));
	if (now > (pushes ? pass->list_distance : pass->failsafe_reach)) {
		return;
	}
	vec3 end[4] = {p, q, r, s};
	list_pair(pass, PAIR_EDGE_EDGE, v, end, now, edge_s, edge_t, first, second, self);
}

/* Whether a vertex of material mv meets a triangle of material mo here. A collider's faces
 * meet other objects' vertices in the collider pass (contact.c: continuous, with the trapped
 * check); here they meet only their edges, and their corners the others' triangles. */
static bool vertex_meets_face(const plait_material *mv, const plait_material *mo)
{
	return mo->type != PLAIT_OBJECT_COLLIDER || mv->type == PLAIT_OBJECT_COLLIDER;
}

static int bits3(unsigned bits)
{
	return (int)(bits & 1u) + (int)((bits >> 1) & 1u) + (int)((bits >> 2) & 1u);
}

/* The primitive pairs an element pair owns, each handed to visit_primitives (the rest pairs'
 * stage, the failsafe) or, in the gather, tested from the elements' points (loaded once) and
 * shapes: vertex-face pairs rejected by point_far go no further, the others go to list_face
 * and list_edges. The failsafe leaves vertex-vertex pairs out (nothing to cross). A cloth's own
 * triangle pairs take gather_triangle_pair in the gather, the same tests in the same order. */
static void walk_element_pair(pair_pass *pass, int a, int b, const plait_material *ma,
                              const plait_material *mb, bool self)
{
	const element *ea = &pass->mc->elements[a], *eb = &pass->mc->elements[b];
	bool cull = pass->stage == STAGE_GATHER, failsafe = pass->stage == STAGE_FAILSAFE;
	/* The gather passes over the rest pairs (never listed) before any distance. */
	uint32_t skip = cull ? pass->rest_slots : 0u;
	const element_shape *shape[2] = {&pass->mc->shapes[a], &pass->mc->shapes[b]};
	float gap = pass->list_distance;
	/* Pairs the self-collision flag leaves to the failsafe are culled within its reach. */
	bool face_pushes = !self || self_pushes(ma, PAIR_VERTEX_FACE);
	float edge_gap = !self || self_pushes(ma, PAIR_EDGE_EDGE) ? gap : pass->failsafe_reach;
	/* A filtered collider's corners and edges that its smooth reach keeps from this cloth's. */
	uint8_t own_vertices[2] = {ea->own_vertices, eb->own_vertices},
	        own_edges[2] = {ea->own_edges, eb->own_edges};
	const plait_mesh_contacts *mc = pass->mc;
	int collider = self                                ? -1
	               : ma->type == PLAIT_OBJECT_COLLIDER ? 0
	               : mb->type == PLAIT_OBJECT_COLLIDER ? 1
	                                                   : -1;
	if (collider >= 0) {
		int all = bits3(own_vertices[collider]) + bits3(own_edges[collider]);
		if (mc->features != NULL &&
		    mc->objects[mc->object_of[(collider == 0 ? ea : eb)->v[0]]].features >= 0) {
			uint8_t vertices, edges;
			plait_mesh_contacts_live_features(mc, collider == 0 ? a : b, collider == 0 ? b : a, &vertices,
			                                  &edges);
			own_vertices[collider] &= vertices;
			own_edges[collider] &= edges;
		}
		if (pass->stage == STAGE_GATHER) {
			int kept = bits3(own_vertices[collider]) + bits3(own_edges[collider]);
			pass->features_kept += kept;
			pass->features_left_out += all - kept;
			/* No corner or edge of the collider's triangle is left, and this element's own
			 * vertices meet collider faces in contact.c: nothing to list (a third of the cloth
			 * and collider element pairs in hang-self --stiff). */
			if (kept == 0) {
				return;
			}
		}
	}
	/* Elements whose boxes lie apart by more than every gap below (gather_triangle_pair). */
	if (cull && boxes_apart(shape[0]->lower, shape[0]->upper, shape[1]->lower, shape[1]->upper,
	                        plait_maxf(gap, edge_gap))) {
		return;
	}
	vec3 x[2][3] = {{{0}}};
	if (cull) {
		const plait_particles *p = &pass->sim->particles;
		for (int k = 0; k < 3; ++k) {
			x[0][k] = p->point[ea->v[k]].x;
			x[1][k] = p->point[eb->v[k]].x;
		}
	}
	int v[4];
	for (int turn = 0; turn < 2; ++turn) {
		const element *vertex_side = turn == 0 ? ea : eb, *other = turn == 0 ? eb : ea;
		const element_shape *os = shape[1 - turn];
		const vec3 *vx = x[turn], *ox = x[1 - turn];
		const plait_material *mv = turn == 0 ? ma : mb, *mo = turn == 0 ? mb : ma;
		for (int k = 0; k < vertex_side->size; ++k) {
			if (!(own_vertices[turn] & (1u << k))) {
				continue;
			}
			v[0] = vertex_side->v[k];
			/* A vertex of the other element (neighbours in one object): every pair with it
			 * but one vertex-vertex pair shares a vertex, which visit_primitives passes over;
			 * skipped here before any distance. */
			bool shared = self && (v[0] == other->v[0] || v[0] == other->v[1] || v[0] == other->v[2]);
			if (shared && !(turn == 0 && self_pushes(ma, PAIR_VERTEX_VERTEX))) {
				continue;
			}
			int slot = VERTEX_SLOT(turn, k);
			bool to_face = other->size == 3 && vertex_meets_face(mv, mo) && !shared && !(skip & (1u << slot));
			bool to_edge = other->size == 2 && vertex_side->size == 1 && !shared && !(skip & (1u << slot));
			bool to_vertices = turn == 0 && self && !failsafe && self_pushes(ma, PAIR_VERTEX_VERTEX);
			if (!to_face && !to_edge && !to_vertices) {
				continue;
			}
			bool far = cull && !shared && point_far(vx[k], other, os, ox, gap);
			/* A face the flag leaves to the failsafe: within its smaller reach. */
			bool far_face = far || (cull && to_face && !face_pushes &&
			                        point_far(vx[k], other, os, ox, pass->failsafe_reach));
			pass->slot = slot;
			if (to_face && !far_face) {
				v[1] = other->v[0];
				v[2] = other->v[1];
				v[3] = other->v[2];
				if (cull) {
					list_face(pass, v, vx[k], ox, mv, mo, self);
				} else {
					visit_primitives(pass, PAIR_VERTEX_FACE, v, mv, mo, self);
				}
			}
			if (to_edge && !far) {
				v[1] = other->v[0];
				v[2] = other->v[1];
				visit_primitives(pass, PAIR_VERTEX_EDGE, v, mv, mo, self);
			}
			if (to_vertices && !far) {
				for (int m = 0; m < other->size; ++m) {
					int pair_slot = VERTEX_VERTEX_SLOT(k, m);
					if ((other->own_vertices & (1u << m)) && !(skip & (1u << pair_slot)) &&
					    !(cull && boxes_apart(vx[k], vx[k], ox[m], ox[m], gap))) {
						v[1] = other->v[m];
						pass->slot = pair_slot;
						visit_primitives(pass, PAIR_VERTEX_VERTEX, v, mv, mo, self);
					}
				}
			}
		}
	}
	if (ea->size >= 2 && eb->size >= 2) {
		int edges_a = ea->size == 2 ? 1 : 3, edges_b = eb->size == 2 ? 1 : 3;
		for (int i = 0; i < edges_a; ++i) {
			if (!(own_edges[0] & (1u << i))) {
				continue;
			}
			int i1 = i + 1 < ea->size ? i + 1 : 0;
			for (int j = 0; j < edges_b; ++j) {
				int j1 = j + 1 < eb->size ? j + 1 : 0;
				if (!(own_edges[1] & (1u << j))) {
					continue;
				}
				/* Edges with an end in common (neighbours): passed over before any distance. */
				if (self && (ea->v[i] == eb->v[j] || ea->v[i] == eb->v[j1] || ea->v[i1] == eb->v[j] ||
				             ea->v[i1] == eb->v[j1])) {
					continue;
				}
				int slot = EDGE_EDGE_SLOT(i, j);
				if ((skip & (1u << slot)) ||
				    (cull && segments_far(x[0][i], x[0][i1], x[1][j], x[1][j1], edge_gap))) {
					continue;
				}
				pass->slot = slot;
				v[0] = ea->v[i];
				v[1] = ea->v[i1];
				v[2] = eb->v[j];
				v[3] = eb->v[j1];
				if (cull) {
					list_edges(pass, v, x[0][i], x[0][i1], x[1][j], x[1][j1], ma, mb, self);
				} else {
					visit_primitives(pass, PAIR_EDGE_EDGE, v, ma, mb, self);
				}
			}
		}
	}
}

/* The edge pairs (bit 3i + j: edge i of one triangle, edge j of the other) with an end in
 * common, from which vertices are one (bit 3k + m: vertex k of the one is vertex m of the
 * other). Edge i joins vertices i and i + 1. */
static unsigned edge_pairs_touching(unsigned same)
{
	unsigned touching = 0u;
	for (int k = 0; k < 3; ++k) {
		for (int m = 0; m < 3; ++m) {
			if (same & (1u << (3 * k + m))) {
				unsigned edges_k = (1u << k) | (1u << ((k + 2) % 3)),
				         edges_m = (1u << m) | (1u << ((m + 2) % 3));
				for (int i = 0; i < 3; ++i) {
					touching |= (edges_k & (1u << i)) ? edges_m << (3 * i) : 0u;
				}
			}
		}
	}
	return touching;
}

/* walk_element_pair for the gather's most common case, two triangles of one cloth whose
 * self-collision flag pushes no vertex-vertex pairs: which primitive pairs to test is decided
 * in bit masks (ownership, shared vertices, rest slots), then only those are tested, in the
 * walk's order (so the same list). */
static void gather_triangle_pair(pair_pass *pass, int a, int b, const plait_material *m)
{
	const plait_mesh_contacts *mc = pass->mc;
	const element *ea = &mc->elements[a], *eb = &mc->elements[b];
	float gap = pass->list_distance;
	bool face_pushes = self_pushes(m, PAIR_VERTEX_FACE);
	float edge_gap = self_pushes(m, PAIR_EDGE_EDGE) ? gap : pass->failsafe_reach;
	/* Triangles whose boxes lie apart by more than every gap below: each primitive's box is
	 * inside its triangle's, so each test below would find it far (a seventh of the pairs met
	 * in hang-self --stiff). */
	if (boxes_apart(mc->shapes[a].lower, mc->shapes[a].upper, mc->shapes[b].lower, mc->shapes[b].upper,
	                plait_maxf(gap, edge_gap))) {
		return;
	}
	const plait_point *point = pass->sim->particles.point;
	uint32_t skip = pass->rest_slots;
	unsigned same = 0u;
	for (int k = 0; k < 3; ++k) {
		for (int mm = 0; mm < 3; ++mm) {
			same |= (unsigned)(ea->v[k] == eb->v[mm]) << (3 * k + mm);
		}
	}
	unsigned shared_a = (unsigned)((same & 0007u) != 0) | (unsigned)((same & 0070u) != 0) << 1 |
	                    (unsigned)((same & 0700u) != 0) << 2;
	unsigned shared_b = (unsigned)((same & 0111u) != 0) | (unsigned)((same & 0222u) != 0) << 1 |
	                    (unsigned)((same & 0444u) != 0) << 2;
	unsigned faces_a = ea->own_vertices & ~shared_a & ~skip & 7u;
	unsigned faces_b = eb->own_vertices & ~shared_b & ~(skip >> 3) & 7u;
	unsigned edges = 0u;
	for (int i = 0; i < 3; ++i) {
		edges |= (ea->own_edges & (1u << i)) ? (unsigned)(eb->own_edges & 7u) << (3 * i) : 0u;
	}
	edges &= ~(skip >> 15) & 0777u;
	if (same != 0u) {
		edges &= ~edge_pairs_touching(same);
	}
	if ((faces_a | faces_b | edges) == 0u) {
		return;
	}
	vec3 x[2][3];
	for (int k = 0; k < 3; ++k) {
		x[0][k] = point[ea->v[k]].x;
		x[1][k] = point[eb->v[k]].x;
	}
	int v[4];
	for (int turn = 0; turn < 2; ++turn) {
		const element *vertex_side = turn == 0 ? ea : eb, *other = turn == 0 ? eb : ea;
		const element_shape *os = &mc->shapes[turn == 0 ? b : a];
		const vec3 *vx = x[turn], *ox = x[1 - turn];
		for (unsigned bits = turn == 0 ? faces_a : faces_b; bits != 0u; bits &= bits - 1u) {
			int k = __builtin_ctz(bits);
			if (point_far(vx[k], other, os, ox, gap) ||
			    (!face_pushes && point_far(vx[k], other, os, ox, pass->failsafe_reach))) {
				continue;
			}
			v[0] = vertex_side->v[k];
			v[1] = other->v[0];
			v[2] = other->v[1];
			v[3] = other->v[2];
			list_face(pass, v, vx[k], ox, m, m, true);
		}
	}
	for (unsigned bits = edges; bits != 0u; bits &= bits - 1u) {
		int slot = __builtin_ctz(bits), i = slot / 3, j = slot % 3;
		int i1 = i < 2 ? i + 1 : 0, j1 = j < 2 ? j + 1 : 0;
		if (segments_far(x[0][i], x[0][i1], x[1][j], x[1][j1], edge_gap)) {
			continue;
		}
		v[0] = ea->v[i];
		v[1] = ea->v[i1];
		v[2] = eb->v[j];
		v[3] = eb->v[j1];
		list_edges(pass, v, x[0][i], x[0][i1], x[1][j], x[1][j1], m, m, true);
	}
}

static void visit_elements(int a, int b, void *context)
{
	pair_pass *pass = context;
	pass->met += 1;
	const plait_mesh_contacts *mc = pass->mc;
	const element *ea = &mc->elements[a], *eb = &mc->elements[b];
	const plait_material *ma = &pass->sim->materials[ea->material];
	const plait_material *mb = &pass->sim->materials[eb->material];
	bool self = ma->object == mb->object;
	if (self && pass->stage == STAGE_GATHER && plait_mesh_contacts_culls_flat(mc, pass)) {
		/* Within one flat cross patch (mesh_contact_cross.c): passed over, as a flat node's. */
		collision_object *o = &pass->mc->objects[mc->object_of[ea->v[0]]];
		if (o->cross_fitted && plait_mesh_contacts_in_cross(o, a - o->first, b - o->first)) {
			pass->cross_skipped += 1;
			return;
		}
	}
	uint32_t slots = self ? rest_slots(mc, a, b) : 0u;
	if (slots == ALL_REST_SLOTS) {
		return;
	}
	pass->all_rest = true;
	pass->rest_slots = pass->stage == STAGE_GATHER ? slots : 0u;
	if (pass->stage == STAGE_GATHER) {
		/* One list distance for every primitive pair of the two elements, from their largest
		 * radii and guards: a little generous, and no lookups per primitive pair. */
		float scale = self ? ma->self_width_scale : 1.0f;
		/* How far their motions may bring them closer (plait_mesh_contacts_gather). */
		float relative = mc->element_spread[a] + mc->element_spread[b] +
		                 v3_length(v3_sub(mc->element_motion[a], mc->element_motion[b]));
		/* Re-listing around strayed vertices measures from now, when the others may already
		 * be a guard off their paths. */
		float guards = (pass->around_only ? 2.0f : 1.0f) * (mc->element_guard[a] + mc->element_guard[b]);
		float contact = LIST_SCALE * scale * (mc->element_reach[a] + mc->element_reach[b]);
		/* Over the substep so far (back) and the substeps the list serves on. */
		float window = (float)(mc->list_serves > 1 ? mc->list_serves : 1);
		pass->pair_slack = window * relative + guards;
		pass->failsafe_reach = pass->pair_slack + 2.0f * FAILSAFE_DISTANCE;
		/* A list that serves on holds the pairs that may come within their contact distance
		 * meanwhile; one that serves only its substep, those within it now, and those that may
		 * have crossed since the substep began (pushed back to their side). */
		pass->list_distance = mc->list_serves > 0
		                          ? contact + pass->pair_slack + 2.0f * FAILSAFE_DISTANCE
		                          : plait_maxf(contact, relative) + guards + 2.0f * FAILSAFE_DISTANCE;
	}
	if (pass->stage == STAGE_GATHER && ma == mb && ea->size == 3 && eb->size == 3 &&
	    !self_pushes(ma, PAIR_VERTEX_VERTEX) && ma->type != PLAIT_OBJECT_COLLIDER) {
		gather_triangle_pair(pass, a, b, ma);
		return;
	}
	int rest_before = mc->rest_count;
	walk_element_pair(pass, a, b, ma, mb, self);
	if (pass->stage == STAGE_REST && mc->rest_count > rest_before && !pass->failed &&
	    !add_rest_group(pass->sim, pass->mc, rest_before, a, b)) {
		pass->failed = true;
	}
	if (pass->stage == STAGE_REST && (pass->all_rest || pass->rest_slots != 0) && !pass->failed) {
		if (pass->near_count == pass->near_capacity) {
			int capacity = pass->near_capacity < 1024 ? 1024 : 2 * pass->near_capacity;
			near_pair *bigger = plait_alloc_grow(&pass->sim->allocator, pass->near, sizeof *bigger,
			                                     pass->near_count, capacity);
			if (bigger == NULL) {
				pass->failed = true;
				return;
			}
			pass->near = bigger;
			pass->near_capacity = capacity;
		}
		uint32_t found = pass->all_rest ? ALL_REST_SLOTS : pass->rest_slots;
		pass->near[pass->near_count++] =
		    (near_pair){a < b ? a : b, a < b ? b : a, a < b || pass->all_rest ? found : swap_slots(found)};
	}
}

void plait_mesh_contacts_visit_object_elements(int a, int b, void *context)
{
	const object_pass *o = context;
	visit_elements(o->first_a + a, o->first_b + b, o->pass);
}
