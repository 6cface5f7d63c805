/* States that begin tangled (issue 3 item 5, seed 000 §4.4): cloth triangles and curve segments
 * that cross other cloths' triangles, or their own cloth's when it self-collides, at a substep's
 * start. Everything else in mesh contacts takes the substep's start to be free of crossings and
 * keeps it so; a scene that began tangled (layers modelled through each other, a cord through a
 * sheet, positions set through another cloth) stayed tangled for good, its contacts and
 * failsafe holding the tangle in place.
 *
 * A search runs when one is due: at the stage's first substep, after positions are set from
 * outside, and at every substep while crossings remain. A self-traversal of a tree over the
 * cloth triangles and curve segments at the substep's start finds every edge or segment that
 * crosses a triangle, and every vertex that lies in one (nearer than the failsafe leaves
 * anything). Then:
 *   - Trapped check. Each crossing's vertices are linked with those of the triangle it
 *     crosses; a pair of primitives with a linked vertex on each side is neither pushed nor
 *     swept by the failsafe for the substep (Maya's self trapped check: collisions step aside
 *     where surfaces already pass through each other). Everything else is held as usual: looser
 *     rules let tangles spread (architecture.md).
 *   - Pushes through. Each cloth and curve is cut along its crossing edges into pieces
 *     (union-find over its other edges); a crossing edge whose ends lie in different pieces
 *     pushes its end in the smaller one through the triangle it crosses, to the other end's
 *     side (global intersection analysis after Baraff, Witkin and Kass 2003), a contact
 *     distance per collision iteration at most. Where a crossing cuts its cloth in no two
 *     pieces (sheets crossed like an X), its ends are weighed by which side of the triangle
 *     more of the cloth around them is on. The contour moves over the smaller side until it is
 *     gone.
 *   - After. Pairs that began crossing are never rest pairs nor clipped to their start
 *     separation (TANGLED_EVER); once none is left, the stage is built again.
 * Crossings with mesh and box colliders are not searched: a cloth vertex inside a collider is
 * the collider pass's to push out (architecture.md, "What is not here yet"). */
#include "dynamics/mesh_contact_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "collision/intersect.h"
#include "collision/element_tree.h"
#include "collision/mesh_shape.h"

/* An edge of a triangle crossing another triangle at the substep's start. */
typedef struct tangle_crossing {
	int a, b;      /* the edge */
	int target[3]; /* the triangle it crosses */
	bool self;     /* within one object */
} tangle_crossing;

typedef struct tangle_pass {
	const plait_sim *sim;
	const plait_mesh_contacts *mc;
	const vec3 *x;             /* positions at the substep's start */
	const int (*triangles)[3]; /* the elements searched: cloth triangles and curve segments */
	const uint8_t *sizes;      /* per element searched: 3 (a triangle) or 2 (a segment) */
	const uint8_t *own_edges;  /* per element searched: the edges it owns (bit k: v[k]-v[k+1]) */
	tangle_crossing *crossings;
	int count, capacity;
	bool out_of_memory;
} tangle_pass;

/* The elements searched: cloth triangles and curve segments (colliders' crossings are the
 * collider pass's, and loose particles cannot be cut). */
static bool searched(const plait_sim *sim, const element *el)
{
	plait_object_type type = sim->materials[el->material].type;
	return (el->size == 3 && type == PLAIT_OBJECT_CLOTH) || (el->size == 2 && type == PLAIT_OBJECT_CURVE);
}

static bool add_crossing(tangle_pass *pass, int a, int b, const int *target, bool self)
{
	if (pass->count == pass->capacity) {
		int capacity = pass->capacity > 0 ? 2 * pass->capacity : 64;
		tangle_crossing *bigger =
		    plait_alloc_grow(&pass->sim->allocator, pass->crossings, sizeof *bigger, pass->count, capacity);
		if (bigger == NULL) {
			pass->out_of_memory = true;
			return false;
		}
		pass->crossings = bigger;
		pass->capacity = capacity;
	}
	pass->crossings[pass->count++] = (tangle_crossing){a, b, {target[0], target[1], target[2]}, self};
	return true;
}

/* The edges of the searched triangle `triangle` that cross triangle u, as crossings: those it
 * owns, so that an edge is found once, not once from each of its triangles. */
static void edges_through(tangle_pass *pass, int triangle, const int *u, bool self)
{
	const vec3 *x = pass->x;
	const int *t = pass->triangles[triangle];
	for (int k = 0; k < 3; ++k) {
		if (!(pass->own_edges[triangle] & (1u << k))) {
			continue;
		}
		int a = t[k], b = t[(k + 1) % 3];
		if (plait_segment_crosses_triangle(x[a], x[b], x[u[0]], x[u[1]], x[u[2]])) {
			(void)add_crossing(pass, a, b, u, self);
		}
	}
}

/* A vertex nearer a triangle than half the failsafe's distance began the substep in it: the
 * failsafe ends every substep with primitives at least that far apart, so only a state that
 * began so, or a tangle squeezed flat, has one (a sheet's vertex pressed between the ground and
 * the sheet it was being pushed through lay in that sheet, beyond the reach of the crossing test,
 * its contacts unable to tell the side, and the failsafe stepped in at every substep after).
 * Its edges in t count as crossing u. */
static void vertices_in(tangle_pass *pass, const int *t, const int *u, bool self)
{
	const vec3 *x = pass->x;
	for (int k = 0; k < 3; ++k) {
		int region;
		float weights[3];
		vec3 on = plait_closest_point_on_triangle(x[t[k]], x[u[0]], x[u[1]], x[u[2]], &region, weights);
		if (v3_length(v3_sub(x[t[k]], on)) < 0.5f * FAILSAFE_DISTANCE) {
			(void)add_crossing(pass, t[k], t[(k + 1) % 3], u, self);
			(void)add_crossing(pass, t[k], t[(k + 2) % 3], u, self);
		}
	}
}

/* A curve segment s that crosses triangle u, or one of whose ends lies in it (as vertices_in),
 * as a crossing (when s owns its edge, so that it is found once). */
static void segment_through(tangle_pass *pass, int segment, const int *u, bool self)
{
	const vec3 *x = pass->x;
	const int *s = pass->triangles[segment];
	if (!(pass->own_edges[segment] & 1u)) {
		return;
	}
	bool crossing = plait_segment_crosses_triangle(x[s[0]], x[s[1]], x[u[0]], x[u[1]], x[u[2]]);
	for (int k = 0; k < 2 && !crossing; ++k) {
		int region;
		float weights[3];
		vec3 on = plait_closest_point_on_triangle(x[s[k]], x[u[0]], x[u[1]], x[u[2]], &region, weights);
		crossing = v3_length(v3_sub(x[s[k]], on)) < 0.5f * FAILSAFE_DISTANCE;
	}
	if (crossing) {
		(void)add_crossing(pass, s[0], s[1], u, self);
	}
}

static void visit_triangle_pair(int first, int other, void *context)
{
	tangle_pass *pass = context;
	const int *t = pass->triangles[first], *u = pass->triangles[other];
	int nt = pass->sizes[first], nu = pass->sizes[other];
	if (nt == 2 && nu == 2) {
		return; /* curves against curves: particle pairs' */
	}
	for (int i = 0; i < nt; ++i) {
		for (int j = 0; j < nu; ++j) {
			if (t[i] == u[j]) {
				return; /* neighbours touch by construction */
			}
		}
	}
	const plait_mesh_contacts *mc = pass->mc;
	int ot = mc->object_of[t[0]], ou = mc->object_of[u[0]];
	bool self = ot == ou;
	if (self ? !mc->objects[ot].self
	         : !plait_mesh_contacts_objects_meet(pass->sim, mc, ot < ou ? ot : ou, ot < ou ? ou : ot)) {
		return;
	}
	if (nt == 2 || nu == 2) {
		segment_through(pass, nt == 2 ? first : other, nt == 2 ? u : t, self);
		return;
	}
	edges_through(pass, first, u, self);
	edges_through(pass, other, t, self);
	vertices_in(pass, t, u, self);
	vertices_in(pass, u, t, self);
}

/* ---- Links: the vertices of each crossing edge (or vertex in a triangle) with those of the
 * triangle it crosses, in an open-addressed set of vertex pairs. A pair of primitives is
 * exempt from contacts and the failsafe only when a vertex of each is linked: free to come
 * undone where it crosses, and where its edges slide over the triangle's as it does, but held
 * everywhere else. (Exempt wherever both had some tangled vertex, three sheets begun through
 * each other crumpled as they landed, passed through each other further from every crossing,
 * each new crossing freed more, and the frame had 440,000 crossings by frame 24.) */

static uint64_t edge_key(int a, int b)
{
	uint32_t low = (uint32_t)(a < b ? a : b), high = (uint32_t)(a < b ? b : a);
	return ((uint64_t)low << 32) | high;
}

static uint64_t link_key(int a, int b)
{
	return edge_key(a, b) + 1u; /* 0 marks an empty slot */
}

static uint32_t link_slot(uint64_t key, uint32_t mask)
{
	return (uint32_t)((key * 0x9e3779b97f4a7c15ull) >> 32) & mask;
}

static bool linked(const plait_mesh_contacts *mc, int a, int b)
{
	uint64_t key = link_key(a, b);
	uint32_t mask = (uint32_t)mc->tangle_link_capacity - 1u;
	for (uint32_t s = link_slot(key, mask);; s = (s + 1u) & mask) {
		if (mc->tangle_links[s] == key) {
			return true;
		}
		if (mc->tangle_links[s] == 0) {
			return false;
		}
	}
}

/* The links of `count` crossings (six each), into a set at most a quarter full. */
static bool link_crossings(plait_sim *sim, plait_mesh_contacts *mc, const tangle_crossing *crossings,
                           int count)
{
	int capacity = 64;
	while (capacity < 4 * 6 * count) {
		capacity *= 2;
	}
	if (capacity > mc->tangle_link_capacity) {
		uint64_t *bigger = plait_alloc(&sim->allocator, sizeof(uint64_t) * (size_t)capacity);
		if (bigger == NULL) {
			return false;
		}
		plait_free(&sim->allocator, mc->tangle_links);
		mc->tangle_links = bigger;
		mc->tangle_link_capacity = capacity;
	}
	memset(mc->tangle_links, 0, sizeof(uint64_t) * (size_t)mc->tangle_link_capacity);
	uint32_t mask = (uint32_t)mc->tangle_link_capacity - 1u;
	for (int k = 0; k < count; ++k) {
		const tangle_crossing *c = &crossings[k];
		int ends[2] = {c->a, c->b};
		for (int e = 0; e < 2; ++e) {
			for (int t = 0; t < 3; ++t) {
				uint64_t key = link_key(ends[e], c->target[t]);
				uint32_t s = link_slot(key, mask);
				while (mc->tangle_links[s] != 0 && mc->tangle_links[s] != key) {
					s = (s + 1u) & mask;
				}
				mc->tangle_links[s] = key;
			}
		}
	}
	return true;
}

static int compare_keys(const void *a, const void *b)
{
	uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
	return x < y ? -1 : x > y;
}

static bool is_cut(const uint64_t *cut, int count, int a, int b)
{
	uint64_t key = edge_key(a, b);
	return bsearch(&key, cut, (size_t)count, sizeof *cut, compare_keys) != NULL;
}

/* Where a crossing cuts its cloth in no two pieces (two sheets crossed like an X, the crossing
 * running from one's border to the other's), which end of the crossing edge is on the side
 * fewer of its cloth's vertices near the crossing are on: the vertices within three edge
 * lengths of it, counted by their side of the crossed triangle's plane. Returns +1 when a's
 * side has more (b goes through), -1 when b's has, 0 when neither. (A pass over the cloth's
 * vertices per such crossing: only while crossings remain.) */
static int local_side_vote(const plait_sim *sim, const plait_mesh_contacts *mc, const tangle_crossing *c)
{
	const vec3 *x = sim->particles.x_prev;
	vec3 normal = v3_normalize(
	    v3_cross(v3_sub(x[c->target[1]], x[c->target[0]]), v3_sub(x[c->target[2]], x[c->target[0]])));
	float side_a = v3_dot(v3_sub(x[c->a], x[c->target[0]]), normal);
	vec3 centre = v3_scale(v3_add(x[c->a], x[c->b]), 0.5f);
	float reach = 3.0f * v3_length(v3_sub(x[c->a], x[c->b]));
	const collision_object *o = &mc->objects[mc->object_of[c->a]];
	int with_a = 0, with_b = 0;
	for (int e = o->first; e < o->first + o->count; ++e) {
		const element *el = &mc->elements[e];
		for (int q = 0; q < el->size; ++q) {
			if (!(el->own_vertices & (1u << q)) || v3_length(v3_sub(x[el->v[q]], centre)) > reach) {
				continue;
			}
			float height = v3_dot(v3_sub(x[el->v[q]], x[c->target[0]]), normal);
			if (fabsf(height) > FAILSAFE_DISTANCE) {
				with_a += (height > 0.0f) == (side_a > 0.0f);
				with_b += (height > 0.0f) != (side_a > 0.0f);
			}
		}
	}
	return with_a > with_b ? 1 : with_a < with_b ? -1 : 0;
}

static int compare_pushes(const void *a, const void *b)
{
	const tangle_push *x = a, *y = b;
	if (x->vertex != y->vertex) {
		return x->vertex < y->vertex ? -1 : 1;
	}
	for (int k = 0; k < 3; ++k) {
		if (x->target[k] != y->target[k]) {
			return x->target[k] < y->target[k] ? -1 : 1;
		}
	}
	return 0;
}

/* The pushes of the crossings: per cloth, its vertices joined along the edges that do not cross
 * (union-find), and each crossing edge whose ends fall in different pieces pushes its end in the
 * smaller piece (fewer vertices; the higher root on a tie) through to the other end's side; one
 * whose ends fall in one piece, the end local_side_vote weighs less. */
static bool plan_pushes(plait_sim *sim, plait_mesh_contacts *mc, const tangle_crossing *crossings, int count)
{
	const plait_allocator *a = &sim->allocator;
	const plait_particles *p = &sim->particles;
	int n = p->count;
	int *parent = plait_alloc(a, sizeof(int) * (size_t)n);
	int *size = plait_alloc_zero(a, (size_t)n, sizeof(int));
	uint64_t *cut = plait_alloc(a, sizeof(uint64_t) * (size_t)count);
	if (parent == NULL || size == NULL || cut == NULL) {
		plait_free(a, parent);
		plait_free(a, size);
		plait_free(a, cut);
		return false;
	}
	for (int k = 0; k < count; ++k) {
		cut[k] = edge_key(crossings[k].a, crossings[k].b);
	}
	qsort(cut, (size_t)count, sizeof *cut, compare_keys);
	for (int i = 0; i < n; ++i) {
		parent[i] = i;
	}
	for (int e = 0; e < mc->element_count; ++e) {
		const element *el = &mc->elements[e];
		if (!searched(sim, el)) {
			continue;
		}
		for (int k = 0; k < (el->size == 3 ? 3 : 1); ++k) {
			int u = el->v[k], w = el->v[(k + 1) % el->size];
			if (!is_cut(cut, count, u, w)) {
				int ru = plait_mesh_contacts_root(parent, u), rw = plait_mesh_contacts_root(parent, w);
				if (ru != rw) {
					parent[ru > rw ? ru : rw] = ru < rw ? ru : rw;
				}
			}
		}
	}
	for (int i = 0; i < n; ++i) {
		size[plait_mesh_contacts_root(parent, i)] += 1;
	}
	mc->tangle_push_count = 0;
	bool ok = true;
	for (int k = 0; k < count && ok; ++k) {
		const tangle_crossing *c = &crossings[k];
		int ra = plait_mesh_contacts_root(parent, c->a), rb = plait_mesh_contacts_root(parent, c->b);
		bool a_smaller;
		if (ra != rb) {
			a_smaller = size[ra] < size[rb] || (size[ra] == size[rb] && ra > rb);
		} else {
			int vote = local_side_vote(sim, mc, c);
			if (vote == 0) {
				continue;
			}
			a_smaller = vote < 0;
		}
		int wrong = a_smaller ? c->a : c->b, right = a_smaller ? c->b : c->a;
		if (!(p->point[wrong].w > 0.0f)) {
			continue;
		}
		const vec3 *x = p->x_prev;
		vec3 normal = v3_normalize(
		    v3_cross(v3_sub(x[c->target[1]], x[c->target[0]]), v3_sub(x[c->target[2]], x[c->target[0]])));
		float height = v3_dot(v3_sub(x[right], x[c->target[0]]), normal);
		if (!(fabsf(height) > FAILSAFE_DISTANCE)) {
			continue; /* the other end lies in the plane too: no side to push to */
		}
		float side = height > 0.0f ? 1.0f : -1.0f;
		const plait_material *mv = &sim->materials[p->material[wrong]];
		float distance = p->radius[wrong] +
		                 (p->radius[c->target[0]] + p->radius[c->target[1]] + p->radius[c->target[2]]) / 3.0f;
		if (c->self) {
			distance *= mv->self_width_scale;
		}
		if (mc->tangle_push_count == mc->tangle_push_capacity) {
			int capacity = mc->tangle_push_capacity > 0 ? 2 * mc->tangle_push_capacity : 64;
			tangle_push *bigger =
			    plait_alloc_grow(a, mc->tangle_pushes, sizeof *bigger, mc->tangle_push_count, capacity);
			if (bigger == NULL) {
				ok = false;
				break;
			}
			mc->tangle_pushes = bigger;
			mc->tangle_push_capacity = capacity;
		}
		mc->tangle_pushes[mc->tangle_push_count++] =
		    (tangle_push){wrong, {c->target[0], c->target[1], c->target[2]}, side, distance};
	}
	plait_free(a, parent);
	plait_free(a, size);
	plait_free(a, cut);
	/* Once each: a vertex cut from its piece along several edges through one triangle. */
	qsort(mc->tangle_pushes, (size_t)mc->tangle_push_count, sizeof *mc->tangle_pushes, compare_pushes);
	int kept = 0;
	for (int k = 0; k < mc->tangle_push_count; ++k) {
		if (kept == 0 || compare_pushes(&mc->tangle_pushes[kept - 1], &mc->tangle_pushes[k]) != 0) {
			mc->tangle_pushes[kept++] = mc->tangle_pushes[k];
		}
	}
	mc->tangle_push_count = kept;
	return ok;
}

bool plait_mesh_contacts_find_tangles(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_allocator *a = &sim->allocator;
	const plait_particles *p = &sim->particles;
	mc->tangle_check_due = false;
	if (mc->tangle_count > 0) {
		for (int i = 0; i < p->count; ++i) {
			mc->tangled[i] &= (uint8_t)~TANGLED_NOW;
		}
	}
	mc->tangle_count = 0;
	mc->tangle_push_count = 0;
	/* The elements searched (cloth triangles and curve segments), counted. */
	int triangles = 0;
	for (int e = 0; e < mc->element_count; ++e) {
		triangles += searched(sim, &mc->elements[e]);
	}
	if (triangles < 2) {
		return true;
	}
	int(*tris)[3] = plait_alloc(a, sizeof *tris * (size_t)triangles);
	uint8_t *own_edges = plait_alloc(a, (size_t)triangles), *sizes = plait_alloc(a, (size_t)triangles);
	vec3 *boxes = plait_alloc(a, sizeof(vec3) * 3 * (size_t)triangles); /* centres, lowers, uppers */
	plait_element_tree tree = {0};
	bool ok = tris != NULL && own_edges != NULL && sizes != NULL && boxes != NULL;
	tangle_pass pass = {.sim = sim,
	                    .mc = mc,
	                    .x = p->x_prev,
	                    .triangles = (const int(*)[3])tris,
	                    .sizes = sizes,
	                    .own_edges = own_edges};
	if (ok) {
		vec3 *centre = boxes, *lower = boxes + triangles, *upper = boxes + 2 * triangles;
		int t = 0;
		for (int e = 0; e < mc->element_count; ++e) {
			const element *el = &mc->elements[e];
			if (!searched(sim, el)) {
				continue;
			}
			const vec3 *x = p->x_prev;
			memcpy(tris[t], el->v, sizeof el->v);
			own_edges[t] = el->own_edges;
			sizes[t] = el->size;
			/* (Not grown: a vertex in a flat triangle's plane meets its box exactly. Grown by the
			 * failsafe's distance, the boxes met more vertices a rounding off such planes,
			 * and the two test sheets came apart the other way round, and later.) */
			vec3 last = x[el->v[el->size - 1]];
			lower[t] = v3_min(x[el->v[0]], v3_min(x[el->v[1]], last));
			upper[t] = v3_max(x[el->v[0]], v3_max(x[el->v[1]], last));
			centre[t] = v3_scale(v3_add(lower[t], upper[t]), 0.5f);
			++t;
		}
		ok = plait_element_tree_build(&tree, a, centre, triangles);
		if (ok) {
			plait_element_tree_refit(&tree, lower, upper);
			plait_element_tree_pairs(&tree, lower, upper, visit_triangle_pair, &pass);
		}
	}
	plait_element_tree_destroy(&tree, a);
	plait_free(a, tris);
	plait_free(a, own_edges);
	plait_free(a, sizes);
	plait_free(a, boxes);
	if (!ok) {
		plait_free(a, pass.crossings);
		return false;
	}
	ok = !pass.out_of_memory;
	if (ok && pass.count == 0 && mc->was_tangled) {
		/* Undone. The stage is built again at the next substep: a cloth's own pairs that began
		 * crossing were rest pairs (closer than their contact distance in the start shape),
		 * never pushed; now they are not (plait_mesh_contacts_pair_tangled, ever). */
		mc->rebuild_untangled = true;
		mc->was_tangled = false;
	}
	if (ok && pass.count > 0) {
		mc->tangle_check_due = true; /* again at the next substep, until none is left */
		mc->was_tangled = true;
		sim->tangles += pass.count;
		ok = link_crossings(sim, mc, pass.crossings, pass.count) &&
		     plan_pushes(sim, mc, pass.crossings, pass.count);
		/* Pairs are exempt only with their links in place (out of memory, the frame fails). */
		if (ok) {
			for (int k = 0; k < pass.count; ++k) {
				const tangle_crossing *c = &pass.crossings[k];
				int v[5] = {c->a, c->b, c->target[0], c->target[1], c->target[2]};
				for (int q = 0; q < 5; ++q) {
					mc->tangled[v[q]] = TANGLED_NOW | TANGLED_EVER;
				}
			}
			mc->tangle_count = pass.count;
			mc->ever_tangled = true;
		} else {
			mc->tangle_push_count = 0;
		}
	}
	plait_free(a, pass.crossings);
	return ok;
}

int plait_mesh_contacts_push_through(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_particles *p = &sim->particles;
	int pushed = 0;
	for (int k = 0; k < mc->tangle_push_count; ++k) {
		const tangle_push *push = &mc->tangle_pushes[k];
		vec3 x = p->point[push->vertex].x, t0 = p->point[push->target[0]].x, t1 = p->point[push->target[1]].x,
		     t2 = p->point[push->target[2]].x;
		vec3 face = v3_normalize(v3_cross(v3_sub(t1, t0), v3_sub(t2, t0)));
		if (!(v3_length_sq(face) > 0.0f)) {
			continue;
		}
		vec3 normal = v3_scale(face, push->side);
		float along = v3_dot(v3_sub(x, t0), normal);
		if (along >= push->distance) {
			continue;
		}
		int region;
		float weights[3];
		(void)plait_closest_point_on_triangle(x, t0, t1, t2, &region, weights);
		contact_pair pair = {.v = {push->vertex, push->target[0], push->target[1], push->target[2]},
		                     .type = PAIR_VERTEX_FACE,
		                     .gives_way = {1, 1}};
		float g[4] = {1.0f, -weights[0], -weights[1], -weights[2]};
		/* A contact distance at a time: all at once, a vertex a few centimetres on the wrong
		 * side jumped through alone, and its sheet, stretched by 0.6, folded where it landed. */
		float step = plait_maxf(along - push->distance, -push->distance);
		pushed += plait_mesh_contacts_respond(sim, &pair, g, normal, step, PROJECT_FULL);
	}
	return pushed;
}

bool plait_mesh_contacts_pair_tangled(const plait_mesh_contacts *mc, int type, const int *v, uint8_t when)
{
	int first = type == PAIR_EDGE_EDGE ? 2 : 1, n = pair_size[type];
	bool a = false, b = false;
	for (int k = 0; k < first; ++k) {
		a = a || (mc->tangled[v[k]] & when) != 0;
	}
	for (int k = first; k < n; ++k) {
		b = b || (mc->tangled[v[k]] & when) != 0;
	}
	if (!(a && b) || when != TANGLED_NOW) {
		return a && b;
	}
	/* Now: only where a vertex of one primitive is linked to one of the other's. */
	for (int i = 0; i < first; ++i) {
		for (int j = first; j < n; ++j) {
			if ((mc->tangled[v[i]] & mc->tangled[v[j]] & TANGLED_NOW) && linked(mc, v[i], v[j])) {
				return true;
			}
		}
	}
	return false;
}
