/* The failsafe at the end of a substep (mesh_contact.h): every pair swept from the substep's
 * start, on the workers when there are any, and the pairs that cross joined into impact zones
 * made rigid, or put back where the substep began (carried with a moving collider they lay on). */
#include "dynamics/mesh_contact_internal.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "dynamics/contact.h"

/* ---- Impact zones ---------------------------------------------------------------------------- */

/* Merges the pair's vertices into one impact zone (union-find; the smaller index roots a
 * union, so zones do not depend on the order pairs are met). */
static void join_zone(plait_mesh_contacts *mc, const int *v, int n)
{
	int root = -1;
	for (int k = 0; k < n; ++k) {
		int i = v[k];
		if (mc->zone_parent[i] < 0) {
			mc->zone_parent[i] = i;
			mc->touched[mc->touched_count++] = i;
		}
		while (mc->zone_parent[i] != i) {
			mc->zone_parent[i] = mc->zone_parent[mc->zone_parent[i]];
			i = mc->zone_parent[i];
		}
		if (root < 0) {
			root = i;
		} else if (i != root) {
			int low = i < root ? i : root, high = i < root ? root : i;
			mc->zone_parent[high] = low;
			root = low;
		}
	}
}

static int compare_members(const void *a, const void *b)
{
	const int *x = a, *y = b;
	if (x[0] != y[0]) {
		return x[0] < y[0] ? -1 : 1;
	}
	return x[1] < y[1] ? -1 : x[1] > y[1];
}

/* Rotation by angle |theta| about theta's direction (Rodrigues). */
static vec3 rotate(vec3 theta, vec3 r)
{
	float angle = v3_length(theta);
	if (!(angle > 1e-12f)) {
		return v3_add(r, v3_cross(theta, r));
	}
	vec3 axis = v3_scale(theta, 1.0f / angle);
	float c = cosf(angle), s = sinf(angle);
	return v3_add(v3_add(v3_scale(r, c), v3_scale(v3_cross(axis, r), s)),
	              v3_scale(axis, v3_dot(axis, r) * (1.0f - c)));
}

/* Solves the symmetric 3x3 system I x = b (Cramer, in double); a singular I (a zone on a line)
 * is regularised. */
static vec3 solve_inertia(const double i[6], vec3 b)
{
	double xx = i[0], yy = i[1], zz = i[2], xy = i[3], xz = i[4], yz = i[5];
	double trace = xx + yy + zz;
	double eps = 1e-6 * trace + 1e-30;
	xx += eps;
	yy += eps;
	zz += eps;
	double c00 = yy * zz - yz * yz, c01 = xz * yz - xy * zz, c02 = xy * yz - xz * yy;
	double det = xx * c00 + xy * c01 + xz * c02;
	if (!(fabs(det) > 0.0)) {
		return v3(0.0f, 0.0f, 0.0f);
	}
	double c11 = xx * zz - xz * xz, c12 = xy * xz - xx * yz, c22 = xx * yy - xy * xy;
	double bx = b.x, by = b.y, bz = b.z;
	return v3((float)((c00 * bx + c01 * by + c02 * bz) / det),
	          (float)((c01 * bx + c11 * by + c12 * bz) / det),
	          (float)((c02 * bx + c12 * by + c22 * bz) / det));
}

/* Makes the motion of zone members[first, last) over the substep rigid: the mean displacement
 * and the angular momentum (about the centre of mass) of the substep are kept. A zone with
 * pinned vertices takes their mean displacement, without rotation. */
static void rigidify(plait_particles *p, int (*members)[2], int first, int last)
{
	double mass = 0.0, c0[3] = {0, 0, 0}, c1[3] = {0, 0, 0};
	double pinned = 0.0, pin_motion[3] = {0, 0, 0};
	for (int k = first; k < last; ++k) {
		int i = members[k][1];
		vec3 a = p->x_prev[i], b = p->point[i].x;
		if (p->point[i].w == 0.0f) {
			pinned += 1.0;
			pin_motion[0] += (double)(b.x - a.x);
			pin_motion[1] += (double)(b.y - a.y);
			pin_motion[2] += (double)(b.z - a.z);
			continue;
		}
		double m = 1.0 / (double)p->point[i].w;
		mass += m;
		c0[0] += m * a.x;
		c0[1] += m * a.y;
		c0[2] += m * a.z;
		c1[0] += m * b.x;
		c1[1] += m * b.y;
		c1[2] += m * b.z;
	}
	if (pinned > 0.0) {
		vec3 shift = v3((float)(pin_motion[0] / pinned), (float)(pin_motion[1] / pinned),
		                (float)(pin_motion[2] / pinned));
		for (int k = first; k < last; ++k) {
			int i = members[k][1];
			if (p->point[i].w > 0.0f) {
				p->point[i].x = v3_add(p->x_prev[i], shift);
			}
		}
		return;
	}
	if (!(mass > 0.0)) {
		return;
	}
	vec3 centre0 = v3((float)(c0[0] / mass), (float)(c0[1] / mass), (float)(c0[2] / mass));
	vec3 centre1 = v3((float)(c1[0] / mass), (float)(c1[1] / mass), (float)(c1[2] / mass));
	vec3 shift = v3_sub(centre1, centre0);
	double inertia[6] = {0, 0, 0, 0, 0, 0};
	double momentum[3] = {0, 0, 0};
	for (int k = first; k < last; ++k) {
		int i = members[k][1];
		double m = 1.0 / (double)p->point[i].w;
		vec3 r = v3_sub(p->x_prev[i], centre0);
		vec3 d = v3_sub(v3_sub(p->point[i].x, p->x_prev[i]), shift);
		vec3 l = v3_cross(r, d);
		momentum[0] += m * l.x;
		momentum[1] += m * l.y;
		momentum[2] += m * l.z;
		double rr = (double)v3_dot(r, r);
		inertia[0] += m * (rr - (double)(r.x * r.x));
		inertia[1] += m * (rr - (double)(r.y * r.y));
		inertia[2] += m * (rr - (double)(r.z * r.z));
		inertia[3] -= m * (double)(r.x * r.y);
		inertia[4] -= m * (double)(r.x * r.z);
		inertia[5] -= m * (double)(r.y * r.z);
	}
	vec3 theta = solve_inertia(inertia, v3((float)momentum[0], (float)momentum[1], (float)momentum[2]));
	for (int k = first; k < last; ++k) {
		int i = members[k][1];
		p->point[i].x = v3_add(centre1, rotate(theta, v3_sub(p->x_prev[i], centre0)));
	}
}

/* Whether collider c does not move this substep. */
static bool collider_still(const plait_collider *c)
{
	return memcmp(&c->rigid_start, &c->rigid_end, sizeof c->rigid_start) == 0;
}

/* Colliders a zone can be carried by: the shapes with a rigid motion and a bounded body. */
static bool carrying_collider(const plait_collider *c)
{
	return c->collide && (c->shape.type == PLAIT_SHAPE_SPHERE || c->shape.type == PLAIT_SHAPE_CAPSULE ||
	                      c->shape.type == PLAIT_SHAPE_BOX);
}

/* Colliders a carried zone must not be pressed into: those, planes, and closed rigid meshes
 * (their signed distance says how deep and the way out). A zone holding one arm mesh's
 * vertices is carried with it into the other's in a bent elbow (`bench_collide arm
 * --mesh-colliders`): slid out of it, the sleeve no longer ends pinched through the upper arm
 * from 2 of 64 nearby starts but from 1 (performance.md, session 26). A mesh still carries
 * no zone beside it (collider_beside): carried that way too, one of the two failed again. */
static bool pressing_collider(const plait_collider *c)
{
	bool closed_rigid_mesh = c->shape.type == PLAIT_SHAPE_MESH && c->mesh_end == NULL &&
	                         c->shape.mesh != NULL && c->shape.mesh->closed;
	return carrying_collider(c) || (c->collide && (c->shape.type == PLAIT_SHAPE_PLANE || closed_rigid_mesh));
}

/* How far vertex i at x lies outside collider c's thickened surface (c's thickness and i's
 * radius) where the collider is at rigid; negative inside. */
static float collider_gap(const plait_sim *sim, const plait_collider *c, const plait_rigid *rigid, int i,
                          vec3 x, vec3 *normal)
{
	float distance = plait_shape_distance(&c->shape, plait_rigid_apply_inverse(rigid, x), normal);
	return distance * rigid->scale - (sim->particles.radius[i] + c->thickness);
}

/* The moving collider that zone members[first, last) lay nearest at the substep's start, if a
 * member was within its contact reach of the thickened surface (twice the reach from the bare
 * one); NULL if none. */
static const plait_collider *collider_beside(const plait_sim *sim, int (*members)[2], int first, int last)
{
	const plait_particles *p = &sim->particles;
	const plait_collider *nearest = NULL;
	float nearest_gap = INFINITY;
	for (int k = 0; k < sim->collider_count; ++k) {
		const plait_collider *c = &sim->colliders[k];
		if (!carrying_collider(c) || collider_still(c)) {
			continue;
		}
		for (int m = first; m < last; ++m) {
			int i = members[m][1];
			vec3 normal;
			float gap = collider_gap(sim, c, &c->rigid_start, i, p->x_prev[i], &normal);
			if (gap <= p->radius[i] + c->thickness && gap < nearest_gap) {
				nearest_gap = gap;
				nearest = c;
			}
		}
	}
	return nearest;
}

/* Where collider c's motion over the substep carries vertex i's start. */
static vec3 carried_start(const plait_particles *p, const plait_collider *c, int i)
{
	return plait_rigid_apply(&c->rigid_end, plait_rigid_apply_inverse(&c->rigid_start, p->x_prev[i]));
}

/* How far collider c presses a point of vertex i's radius at x deeper in than it was at the
 * substep's start, at `start` (0: not), and the way out (world space). */
static float pressed_depth(const plait_sim *sim, const plait_collider *c, int i, vec3 x, vec3 start,
                           vec3 *way_out)
{
	vec3 normal, unused;
	float gap = collider_gap(sim, c, &c->rigid_end, i, x, &normal);
	float allowed = plait_minf(collider_gap(sim, c, &c->rigid_start, i, start, &unused), 0.0f);
	*way_out = plait_rigid_rotate(&c->rigid_end, normal);
	return gap < allowed ? allowed - gap : 0.0f;
}

/* Whether vertex i is a zone member that can move, in the zone rooted at `root`. */
static bool moving_member(const plait_sim *sim, const plait_mesh_contacts *mc, int i, int root)
{
	return sim->particles.point[i].w > 0.0f && mc->zone_parent[i] >= 0 &&
	       plait_mesh_contacts_root(mc->zone_parent, i) == root;
}

#define EDGE_SEARCH_STEPS 24

/* Where along vertex i's edge from a to b (t in [0, 1]) collider c at the substep's end comes
 * deepest: a golden-section search for the least signed distance. That distance is convex along
 * a line for a convex shape (sphere, capsule, box, plane), so the search finds its least to
 * within 1e-5 of the edge; in a mesh, a local least. */
static float deepest_along(const plait_sim *sim, const plait_collider *c, int i, vec3 a, vec3 b)
{
	const float golden = 0.618034f;
	vec3 d = v3_sub(b, a), unused;
	float lo = 0.0f, hi = 1.0f;
	float t1 = hi - golden, t2 = lo + golden;
	float g1 = collider_gap(sim, c, &c->rigid_end, i, v3_mul_add(a, t1, d), &unused);
	float g2 = collider_gap(sim, c, &c->rigid_end, i, v3_mul_add(a, t2, d), &unused);
	for (int step = 0; step < EDGE_SEARCH_STEPS; ++step) {
		if (g1 < g2) {
			hi = t2;
			t2 = t1;
			g2 = g1;
			t1 = hi - golden * (hi - lo);
			g1 = collider_gap(sim, c, &c->rigid_end, i, v3_mul_add(a, t1, d), &unused);
		} else {
			lo = t1;
			t1 = t2;
			g1 = g2;
			t2 = lo + golden * (hi - lo);
			g2 = collider_gap(sim, c, &c->rigid_end, i, v3_mul_add(a, t2, d), &unused);
		}
	}
	return 0.5f * (lo + hi);
}

/* How far collider c presses zone members[first, last) in at most (0: not), and the way out:
 * at each moving member, and at the deepest point of each edge between two of them. A segment
 * between two points outside a convex collider can still cut through it near an edge: the
 * sleeve carried with one arm mesh kept a cloth edge across the other's edge that way, and
 * over the box arm's bars, edges whose middles stayed outside a bar while a point nearer one
 * end was in (performance.md, sessions 26 and 27). */
static float deepest_press(const plait_sim *sim, const plait_collider *c, int (*members)[2], int first,
                           int last, vec3 *push)
{
	const plait_particles *p = &sim->particles;
	const plait_mesh_contacts *mc = sim->mesh_contacts;
	float deepest = 0.0f;
	for (int m = first; m < last; ++m) {
		int i = members[m][1];
		vec3 way_out;
		float depth =
		    p->point[i].w > 0.0f ? pressed_depth(sim, c, i, p->point[i].x, p->x_prev[i], &way_out) : 0.0f;
		if (depth > deepest) {
			deepest = depth;
			*push = way_out;
		}
	}
	int root = members[first][0];
	for (int e = 0; e < mc->element_count; ++e) {
		const element *el = &mc->elements[e];
		int edges = el->size == 3 ? 3 : el->size - 1; /* a triangle's three, a segment's one */
		for (int a = 0; a < edges; ++a) {
			int i = el->v[a], j = el->v[a + 1 < el->size ? a + 1 : 0];
			if (!moving_member(sim, mc, i, root) || !moving_member(sim, mc, j, root)) {
				continue;
			}
			/* The middle, and the deepest point (which in a mesh may be only a local one). */
			vec3 from = p->point[i].x, to = p->point[j].x;
			float along[2] = {0.5f, deepest_along(sim, c, i, from, to)};
			for (int k = 0; k < 2; ++k) {
				vec3 at = v3_mul_add(from, along[k], v3_sub(to, from));
				vec3 start = v3_mul_add(p->x_prev[i], along[k], v3_sub(p->x_prev[j], p->x_prev[i]));
				vec3 way_out;
				float depth = pressed_depth(sim, c, i, at, start, &way_out);
				if (depth > deepest) {
					deepest = depth;
					*push = way_out;
				}
			}
		}
	}
	return deepest;
}

#define SLIDE_PASSES 8

/* Translates zone members[first, last), as placed, out of every collider that presses them in
 * deeper than they began: by the deepest push (deepest_press), collider after collider, pass
 * after pass. */
static void slide_out(plait_sim *sim, int (*members)[2], int first, int last)
{
	plait_particles *p = &sim->particles;
	for (int pass = 0; pass < SLIDE_PASSES; ++pass) {
		bool moved = false;
		for (int k = 0; k < sim->collider_count; ++k) {
			const plait_collider *c = &sim->colliders[k];
			if (!pressing_collider(c)) {
				continue;
			}
			vec3 push = v3(0.0f, 0.0f, 0.0f);
			float deepest = deepest_press(sim, c, members, first, last, &push);
			if (deepest > 0.0f) {
				moved = true;
				for (int m = first; m < last; ++m) {
					int i = members[m][1];
					if (p->point[i].w > 0.0f) {
						p->point[i].x = v3_mul_add(p->point[i].x, deepest, push);
					}
				}
			}
		}
		if (!moved) {
			return;
		}
	}
}

/* The rigid collider particle i is a vertex of (pinned particles: a mesh's or a box's), or NULL
 * (a cloth's pin, a deforming mesh's vertex). */
static const plait_collider *rigid_collider_of(const plait_sim *sim, int i)
{
	for (int k = 0; k < sim->collider_count; ++k) {
		const plait_collider *c = &sim->colliders[k];
		if (i >= c->first && i < c->first + c->count) {
			return c->mesh_end == NULL ? c : NULL;
		}
	}
	return NULL;
}

/* The collider a zone holding collider vertices is carried by: the one moving collider among
 * those whose vertices zone members[first, last) holds; NULL when none moves, when a pinned
 * member is no rigid collider's vertex or when two of its colliders move. */
static const plait_collider *collider_within(const plait_sim *sim, int (*members)[2], int first, int last)
{
	const plait_particles *p = &sim->particles;
	const plait_collider *moving = NULL;
	for (int m = first; m < last; ++m) {
		int i = members[m][1];
		if (p->point[i].w != 0.0f) {
			continue;
		}
		const plait_collider *found = rigid_collider_of(sim, i);
		if (found == NULL) {
			return NULL;
		}
		if (collider_still(found)) {
			continue;
		}
		if (moving != NULL && moving != found) {
			return NULL;
		}
		moving = found;
	}
	return moving;
}

/* Whether every pinned member of zone members[first, last) is a vertex of a rigid collider
 * that does not move this substep. */
static bool pins_only_of_still_colliders(const plait_sim *sim, int (*members)[2], int first, int last)
{
	const plait_particles *p = &sim->particles;
	for (int m = first; m < last; ++m) {
		int i = members[m][1];
		if (p->point[i].w != 0.0f) {
			continue;
		}
		const plait_collider *found = rigid_collider_of(sim, i);
		if (found == NULL || !collider_still(found)) {
			return false;
		}
	}
	return true;
}

/* Zone members[first, last) still crossing after the zone rounds: back where the substep
 * began, which was free, but as seen from what they lay against. A zone beside a moving
 * collider goes where that collider carried its start: one left behind would end inside a
 * collider that turned over it, and every later substep would push it out through the cloth
 * above it and put it back again (the arm scene, performance.md "Session 24"). The zone moves
 * rigidly, so it crosses nothing within itself. Squeezed between that collider and another, it
 * slides out of both as one. Neither place was swept: the round after sweeps again, and the
 * last round (`carry` false) puts such zones back at their start, which was free. A zone that
 * holds a moving collider's vertices (it crossed a mesh's or a box's edges or corners) is
 * carried with that collider in every round: those vertices have moved with it, and the start
 * was free as seen from it; one holding only still colliders' vertices is carried as a zone
 * beside a moving collider is; one holding other pinned vertices stays where the substep
 * began. Returns whether the zone was carried. */
static bool carry_back(plait_sim *sim, int (*members)[2], int first, int last, bool carry)
{
	plait_particles *p = &sim->particles;
	bool pinned = false;
	for (int k = first; k < last && !pinned; ++k) {
		pinned = p->point[members[k][1]].w == 0.0f;
	}
	const plait_collider *c = NULL;
	if (pinned) {
		c = collider_within(sim, members, first, last);
		/* Holding only a still collider's vertices (cloth across the upper bar's edge), it is
		 * carried with a moving collider beside it as any zone is, and slides off the still
		 * one: put back where it began, the forearm turning over it left it inside. */
		if (c == NULL && carry && pins_only_of_still_colliders(sim, members, first, last)) {
			c = collider_beside(sim, members, first, last);
		}
	} else if (carry) {
		c = collider_beside(sim, members, first, last);
	}
	for (int k = first; k < last; ++k) {
		int i = members[k][1];
		if (p->point[i].w > 0.0f) {
			p->point[i].x = c != NULL ? carried_start(p, c, i) : p->x_prev[i];
		}
	}
	if (c != NULL) {
		slide_out(sim, members, first, last); /* nothing moves unless something presses */
	}
	return c != NULL;
}

/* ---- Sweeps ---------------------------------------------------------------------------------- */

/* The failsafe's test of one pair: swept from the start of the substep to now. */
void plait_mesh_contacts_sweep_pair(pair_pass *pass, int type, const int *v)
{
	const plait_particles *p = &pass->sim->particles;
	int n = pair_size[type];
	if (pass->mc->tangle_count > 0 && plait_mesh_contacts_pair_tangled(pass->mc, type, v, TANGLED_NOW)) {
		return; /* it began crossing, or beside a crossing: free to come undone */
	}
	vec3 start[4] = {{0}}, end[4] = {{0}};
	gather_points(p->x_prev, v, n, start);
	gather_current(p->point, v, n, end);
	pass->swept += 1;
	if (plait_mesh_contacts_paths_apart(type, start, end, pass->failsafe_distance)) {
		return;
	}
	if (plait_mesh_contacts_paths_meet(type, start, end, pass->failsafe_distance)) {
		pass->hits += 1;
		if (pass->hits_out == NULL) {
			join_zone(pass->mc, v, n);
		} else if (pass->hits_count == HIT_ROOM) {
			pass->full = true;
		} else {
			sweep_hit *hit = &pass->hits_out[pass->hits_count++];
			memcpy(hit->v, v, sizeof(int) * (size_t)n);
			hit->n = n;
		}
	}
}

/* The rest pairs, each swept unless a lower bound of its distance at the substep's start, less
 * what its motion (relative to its first vertex) can take off, still keeps it apart. The bound
 * is carried from substep to substep, and known exactly again whenever the pair is swept. The
 * pairs of one element pair are first passed over together (rest_group) while the group's
 * bound holds. On the workers, a chunk of groups each (a large cloth holds millions of pairs);
 * the crossing pairs are marked, and join their zones afterwards in the pairs' order. */
typedef struct rest_sweep_job {
	plait_mesh_contacts *mc;
	const plait_particles *p;
	float distance;
	const int *element_flat; /* or NULL */
	_Atomic int crossed;
} rest_sweep_job;

/* Each element's mean motion over the substep and how far its vertices' motions are from it:
 * two elements' points come closer by at most their spreads and the difference of their
 * means (a primitive's points move by means of its vertices' motions). */
static void element_substep_motions(void *context, int begin, int end)
{
	const rest_sweep_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	const plait_particles *p = job->p;
	for (int e = begin; e < end; ++e) {
		const element *el = &mc->elements[e];
		vec3 d[3];
		vec3 mean = v3(0.0f, 0.0f, 0.0f);
		for (int k = 0; k < el->size; ++k) {
			d[k] = v3_sub(p->point[el->v[k]].x, p->x_prev[el->v[k]]);
			mean = v3_add(mean, d[k]);
		}
		mean = v3_scale(mean, 1.0f / (float)el->size);
		float spread = 0.0f;
		for (int k = 0; k < el->size; ++k) {
			spread = plait_maxf(spread, v3_length_sq(v3_sub(d[k], mean)));
		}
		mc->element_substep_motion[e] = mean;
		mc->element_substep_spread[e] = sqrtf(spread);
	}
}

static void sweep_rest_range(void *context, int begin, int end)
{
	rest_sweep_job *job = context;
	const plait_particles *p = job->p;
	int crossed = 0;
	for (int g = begin; g < end; ++g) {
		rest_group *group = &job->mc->rest_groups[g];
		const plait_mesh_contacts *mc = job->mc;
		float group_loss =
		    mc->element_substep_spread[group->a] + mc->element_substep_spread[group->b] +
		    v3_length(v3_sub(mc->element_substep_motion[group->a], mc->element_substep_motion[group->b]));
		/* Two elements of one patch that kept flat along the substep cannot have crossed. */
		bool flat = job->element_flat != NULL && job->element_flat[group->a] >= 0 &&
		            job->element_flat[group->a] == job->element_flat[group->b];
		if (flat || group->lower - group_loss > job->distance) {
			group->lower -= group_loss;
			group->pending += group_loss;
			continue;
		}
		float lowest = INFINITY;
		for (int k = group->first; k < group->first + group->count; ++k) {
			rest_pair *pair = &job->mc->rest_pairs[k];
			pair->lower -= group->pending; /* the motion the group took off for it */
			int n = pair_size[pair->type];
			if (mc->tangle_count > 0 &&
			    plait_mesh_contacts_pair_tangled(mc, pair->type, pair->v, TANGLED_NOW)) {
				pair->lower = -1.0f; /* unknown: measured when it is swept again */
				lowest = -1.0f;
				continue;
			}
			vec3 start[4] = {{0}}, end_points[4] = {{0}};
			gather_points(p->x_prev, pair->v, n, start);
			gather_current(p->point, pair->v, n, end_points);
			float motion = plait_mesh_contacts_largest_motion(pair->type, start, end_points);
			if (pair->lower - motion > job->distance) {
				pair->lower -= motion;
				lowest = plait_minf(lowest, pair->lower);
				continue;
			}
			pair->lower = plait_mesh_contacts_primitive_distance(pair->type, end_points);
			lowest = plait_minf(lowest, pair->lower);
			float d0 = plait_mesh_contacts_primitive_distance(pair->type, start);
			if (0.5f * (d0 + pair->lower - motion) > job->distance) {
				continue;
			}
			if (plait_mesh_contacts_paths_meet(pair->type, start, end_points, job->distance)) {
				pair->crossed = 1;
				crossed += 1;
			}
		}
		group->pending = 0.0f;
		group->lower = lowest;
	}
	if (crossed > 0) {
		atomic_fetch_add_explicit(&job->crossed, crossed, memory_order_relaxed);
	}
}

#define REST_GRAIN 2048

static void sweep_rest_pairs(pair_pass *pass, bool flat_checked)
{
	plait_mesh_contacts *mc = pass->mc;
	rest_sweep_job job = {mc, &pass->sim->particles, pass->failsafe_distance,
	                      flat_checked ? mc->element_flat : NULL, 0};
	if (mc->rest_group_count == 0) {
		return;
	}
	plait_parallel_for(&pass->sim->parallel, element_substep_motions, &job, 0, mc->element_count, REST_GRAIN);
	plait_parallel_for(&pass->sim->parallel, sweep_rest_range, &job, 0, mc->rest_group_count, REST_GRAIN);
	if (atomic_load_explicit(&job.crossed, memory_order_relaxed) == 0) {
		return;
	}
	for (int k = 0; k < mc->rest_count; ++k) {
		rest_pair *pair = &mc->rest_pairs[k];
		if (pair->crossed) {
			pair->crossed = 0;
			pass->hits += 1;
			join_zone(mc, pair->v, pair_size[pair->type]);
		}
	}
}

void plait_mesh_contacts_forget_rest_bounds(plait_mesh_contacts *mc)
{
	for (int k = 0; k < mc->rest_count; ++k) {
		mc->rest_pairs[k].lower = -1.0f;
	}
	for (int g = 0; g < mc->rest_group_count; ++g) {
		mc->rest_groups[g].lower = -1.0f;
		mc->rest_groups[g].pending = 0.0f;
	}
}

/* The listed pairs [begin, end) that may have come within the distance, swept. */
static void sweep_listed(plait_mesh_contacts *mc, pair_pass *pass, int begin, int end)
{
	for (int k = begin; k < end; ++k) {
		if (mc->pairs[k].lower <= pass->failsafe_distance) {
			plait_mesh_contacts_sweep_pair(pass, mc->pairs[k].type, mc->pairs[k].v);
		}
	}
}

/* What a sweep on the workers sweeps: the listed pairs, the traversal, or the pairs around
 * flagged vertices. */
typedef enum sweep_kind { SWEEP_LIST, SWEEP_TRAVERSAL, SWEEP_AROUND } sweep_kind;

typedef struct sweep_job {
	plait_sim *sim;
	plait_mesh_contacts *mc;
	float distance;
	sweep_kind kind;
	int chunk; /* SWEEP_LIST: listed pairs a piece; SWEEP_AROUND: flagged elements a piece */
} sweep_job;

/* Piece k of a sweep: listed pairs [k chunk, (k + 1) chunk), piece k of the traversal, or the
 * pairs of flagged elements [k chunk, (k + 1) chunk) (mc->around_elements). */
static void sweep_piece(const sweep_job *job, pair_pass *pass, int k)
{
	plait_mesh_contacts *mc = job->mc;
	if (job->kind == SWEEP_LIST) {
		int begin = k * job->chunk,
		    end = begin + job->chunk < mc->pair_count ? begin + job->chunk : mc->pair_count;
		sweep_listed(mc, pass, begin, end);
	} else if (job->kind == SWEEP_TRAVERSAL) {
		plait_mesh_contacts_list_piece(mc, pass, &mc->pieces[k]);
	} else {
		int begin = k * job->chunk,
		    end = begin + job->chunk < mc->around_count ? begin + job->chunk : mc->around_count;
		object_pass objects = {pass, 0, 0};
		for (int j = begin; j < end; ++j) {
			plait_mesh_contacts_query_around_element(job->sim, mc, mc->around_elements[j], false,
			                                         plait_mesh_contacts_visit_object_elements, &objects);
		}
	}
}

static void sweep_pieces(void *context, int begin, int end)
{
	const sweep_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	for (int k = begin; k < end; ++k) {
		pair_pass pass = {.sim = job->sim,
		                  .mc = mc,
		                  .stage = STAGE_FAILSAFE,
		                  .failsafe_distance = job->distance,
		                  .hits_out = mc->piece_hits + (size_t)k * HIT_ROOM};
		sweep_piece(job, &pass, k);
		mc->piece_hit_count[k] = pass.hits_count;
		mc->piece_swept[k] = pass.swept;
		mc->piece_full[k] = pass.full;
	}
}

/* The failsafe's sweep of the listed pairs, its traversal or the pairs around flagged
 * vertices (mc->element_around marked), on the workers: each piece keeps its crossings, which
 * then join their impact zones here in piece order, the order one thread meets them in (a piece
 * that found too many is swept again here). Adds to pass's hits and swept counts; false
 * (nothing swept) when it cannot run there. */
static bool sweep_on_workers(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass, sweep_kind kind)
{
	if (!plait_mesh_contacts_reserve_pieces(mc, &sim->allocator)) {
		return false;
	}
	sweep_job job = {sim, mc, pass->failsafe_distance, kind, 0};
	int pieces;
	if (kind == SWEEP_AROUND) {
		int count = plait_mesh_contacts_collect_around(sim, mc);
		if (count < 2 * AROUND_RUN) {
			return false; /* too few to share (or out of memory) */
		}
		job.chunk = count > AROUND_RUN * MAX_PIECES ? (count + MAX_PIECES - 1) / MAX_PIECES : AROUND_RUN;
		pieces = (count + job.chunk - 1) / job.chunk;
	} else if (kind == SWEEP_LIST) {
		job.chunk = 4096;
		if (mc->pair_count > job.chunk * MAX_PIECES) {
			job.chunk = (mc->pair_count + MAX_PIECES - 1) / MAX_PIECES;
		}
		pieces = (mc->pair_count + job.chunk - 1) / job.chunk;
	} else {
		/* The traversal's boxes are fitted to the paths: a cut of its own. */
		(void)plait_mesh_contacts_cut_pieces(sim, mc, STAGE_FAILSAFE, 0);
		pieces = mc->piece_count;
		if (pieces == 0) {
			return false;
		}
	}
	plait_parallel_for(&sim->parallel, sweep_pieces, &job, 0, pieces, 1);
	for (int k = 0; k < pieces; ++k) {
		if (mc->piece_full[k]) {
			pair_pass again = {
			    .sim = sim, .mc = mc, .stage = STAGE_FAILSAFE, .failsafe_distance = job.distance};
			sweep_piece(&job, &again, k);
			pass->hits += again.hits;
			pass->swept += again.swept;
			continue;
		}
		const sweep_hit *hits = mc->piece_hits + (size_t)k * HIT_ROOM;
		for (int h = 0; h < mc->piece_hit_count[k]; ++h) {
			join_zone(mc, hits[h].v, hits[h].n);
		}
		pass->hits += mc->piece_hit_count[k];
		pass->swept += mc->piece_swept[k];
	}
	return true;
}

/* ---- Sweeps around some vertices ------------------------------------------------------------ */

/* Sweeps every primitive pair with a vertex flagged in mc->around, from the substep's start to
 * now: each element with such a vertex, its box around its paths queried against the trees of
 * the objects it meets, in element order (on the workers when there are enough of them). */
static void sweep_around(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass)
{
	plait_mesh_contacts_fit_boxes(sim, mc, true, pass->failsafe_distance);
	plait_mesh_contacts_mark_elements(mc);
	if (sim->parallel.worker_count > 1 && sweep_on_workers(sim, mc, pass, SWEEP_AROUND)) {
		return;
	}
	object_pass objects = {pass, 0, 0};
	plait_mesh_contacts_query_around(sim, mc, false, plait_mesh_contacts_visit_object_elements, &objects);
}

/* The substep's own paths (start to now), for the flat patches. */
static plait_patch_paths substep_paths(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_particles *p = &sim->particles;
	for (int i = 0; i < p->count; ++i) {
		mc->sweep_end[i] = p->point[i].x;
		mc->sweep_motion[i] = v3_sub(p->point[i].x, p->x_prev[i]);
	}
	return (plait_patch_paths){mc->sweep_end, mc->sweep_motion, NULL, 1.0f, 0.0f, NULL};
}

typedef struct check_job {
	plait_mesh_contacts *mc;
	collision_object *object;
	const plait_patch_paths *paths;
} check_job;

/* check_passed_over for the nodes [begin, end) of one object (passed-over patches never share a
 * triangle, so ranges side by side write apart). */
static void check_nodes(void *context, int begin, int end)
{
	check_job *job = context;
	collision_object *o = job->object;
	const plait_flat_patches *fp = &o->patches;
	for (int n = begin; n < end; ++n) {
		if (!o->culled[n]) {
			continue;
		}
		if (!plait_flat_patches_keeps_flat(fp, n, o->culled_axis[n], job->paths)) {
			o->culled[n] = 2;
			continue;
		}
		for (int m = fp->node_begin[n]; m < fp->node_end[n]; ++m) {
			job->mc->element_flat[o->first + fp->order[m]] = n;
		}
	}
}

#define CHECK_GRAIN 256

/* The patches the gather passed over hold pairs no list has: the gather took them flat along
 * the paths it expected (without the guards). Each is checked along the substep's own paths
 * (facing the way it faced then): the elements of one that kept flat are marked in
 * mc->element_flat (their rest pairs cannot have crossed either); one that did not (it folded,
 * or its vertices strayed) is marked 2 in culled, for sweep_unflattened. Returns whether any
 * was passed over. */
static bool check_passed_over(plait_sim *sim, plait_mesh_contacts *mc)
{
	bool any = false;
	for (int k = 0; k < mc->object_count && !any; ++k) {
		const collision_object *o = &mc->objects[k];
		for (int n = 0; o->culled != NULL && n < o->tree.node_count && !any; ++n) {
			any = o->culled[n] != 0;
		}
	}
	bool cross = plait_mesh_contacts_any_cross(mc);
	if (!any && !cross) {
		return false;
	}
	for (int e = 0; e < mc->element_count; ++e) {
		mc->element_flat[e] = -1;
	}
	plait_patch_paths paths = substep_paths(sim, mc);
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		if (o->culled != NULL) {
			check_job job = {mc, o, &paths};
			plait_parallel_for(&sim->parallel, check_nodes, &job, 0, o->tree.node_count, CHECK_GRAIN);
		}
	}
	if (cross) {
		plait_mesh_contacts_check_cross(sim, mc, &paths);
	}
	mc->element_flat_serial = mc->substep_serial;
	return true;
}

/* Each patch check_passed_over found not flat along the substep's paths: its pairs with itself
 * swept, so the gather's guess costs a sweep at worst, never a crossing. */
static void sweep_unflattened(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass)
{
	bool boxes = false;
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		for (int n = 0; o->culled != NULL && n < o->tree.node_count; ++n) {
			if (o->culled[n] != 2) {
				continue;
			}
			o->culled[n] = 1;
			if (!boxes) {
				plait_mesh_contacts_fit_boxes(sim, mc, true, pass->failsafe_distance);
				boxes = true;
			}
			mc->unflattened += 1;
			const vec3 *lower = mc->lower + o->first, *upper = mc->upper + o->first;
			object_pass self = {pass, o->first, o->first};
			int node[2] = {n, n};
			plait_element_tree_piece_pairs(&o->tree, lower, upper, &o->tree, lower, upper, true,
			                               v3(0.0f, 0.0f, 0.0f), NULL, node,
			                               plait_mesh_contacts_visit_object_elements, &self);
		}
	}
	bool cross = false;
	for (int k = 0; k < mc->object_count && !cross; ++k) {
		const collision_object *o = &mc->objects[k];
		for (int n = 0; o->cross_of != NULL && n < o->cross_tree.node_count && !cross; ++n) {
			cross = atomic_load_explicit(&o->cross_culled[n], memory_order_relaxed) == 2;
		}
	}
	if (cross) {
		if (!boxes) {
			plait_mesh_contacts_fit_boxes(sim, mc, true, pass->failsafe_distance);
		}
		mc->unflattened += plait_mesh_contacts_sweep_cross(mc, pass);
	}
}

/* Sweeps from the start of the substep to now: every pair (from_list: the listed pairs, which
 * are every pair that can cross while the list covers), or with `around` only the listed pairs
 * and those with a vertex flagged in mc->around; returns the crossing pairs found and leaves
 * them merged into zones. */
static int find_crossings(plait_sim *sim, plait_mesh_contacts *mc, float distance, bool from_list,
                          bool around)
{
	pair_pass pass = {.sim = sim, .mc = mc, .stage = STAGE_FAILSAFE, .failsafe_distance = distance};
	/* Round 0 over the list: the patches the gather passed over are checked first. */
	bool flat_checked = from_list && check_passed_over(sim, mc);
	sweep_rest_pairs(&pass, flat_checked);
	if (from_list) {
		if (!(sim->parallel.worker_count > 1 && sweep_on_workers(sim, mc, &pass, SWEEP_LIST))) {
			sweep_listed(mc, &pass, 0, mc->pair_count);
		}
		if (flat_checked) {
			sweep_unflattened(sim, mc, &pass);
		}
	}
	if (around) {
		sweep_around(sim, mc, &pass);
	}
	if (from_list || around) {
		return pass.hits;
	}
	plait_mesh_contacts_fit_boxes(sim, mc, true, distance);
	if (mc->cull_flat) {
		/* A patch flat all along the substep's own paths crosses nothing. */
		plait_patch_paths paths = substep_paths(sim, mc);
		plait_mesh_contacts_fit_patches(sim, mc, &paths, STAGE_FAILSAFE);
	}
	int before = pass.swept;
	if (!(sim->parallel.worker_count > 1 && sweep_on_workers(sim, mc, &pass, SWEEP_TRAVERSAL))) {
		plait_mesh_contacts_traverse_objects(mc, &pass);
	}
	mc->traversal_sweeps = pass.swept - before;
	return pass.hits;
}

#define ZONE_ROUNDS 12
#define FREEZE_ROUNDS 12

void plait_mesh_contacts_failsafe(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc == NULL || !mc->active) {
		return;
	}
	plait_particles *p = &sim->particles;
	float distance = FAILSAFE_DISTANCE;
	/* A list that no longer covers is gathered again here, rather than replaced by a traversal
	 * over the paths, when the last list was no longer than that traversal's sweeps: then it
	 * costs about the same, covers the substep from its start (the guards hold the motion so
	 * far), and often serves the next substep too. Layers lying on each other list far more
	 * pairs than their paths meet, and keep the traversal. So do short lists (the cloth did
	 * not keep to its paths, mc->short_lists): the next substep gathers again anyway, so a list
	 * gathered here would serve only this sweep, at a gather's price with its guards (arm: 181
	 * of its 901 gathers; 45.4 -> 38.9 ms a frame, failsafe activations 248 -> 118). */
	/* A list that holds but for a few vertices that strayed from their paths (pushed by
	 * contacts) is swept with the pairs around those vertices. */
	int strays = 0;
	bool holds = plait_mesh_contacts_list_covers_except(sim, mc, mc->around, &strays);
	bool covers = holds && strays == 0;
	bool around_strays = holds && plait_mesh_contacts_few_strays(strays, p->count);
	if (holds && !around_strays) {
		memset(mc->around, 0, (size_t)p->count);
	}
	if (!covers && !around_strays && !mc->short_lists && mc->pair_count <= mc->traversal_sweeps) {
		plait_mesh_contacts_gather(sim, mc);
		covers = mc->list_valid;
	}
	for (int round = 0; round < ZONE_ROUNDS + FREEZE_ROUNDS; ++round) {
		int hits;
		if (round == 0) {
			hits = find_crossings(sim, mc, distance, covers || around_strays, around_strays);
			if (around_strays) {
				memset(mc->around, 0, (size_t)p->count);
			}
		} else {
			/* Only the zones' vertices moved since the last round, which found every other
			 * pair clear: the pairs around them are swept again. */
			for (int k = 0; k < mc->touched_count; ++k) {
				mc->around[mc->touched[k]] = 1;
			}
			hits = find_crossings(sim, mc, distance, false, true);
			for (int k = 0; k < mc->touched_count; ++k) {
				mc->around[mc->touched[k]] = 0;
			}
		}
		if (hits == 0) {
			break;
		}
		/* The zones move vertices after their pairs were measured, and after their patches were
		 * found flat. */
		plait_mesh_contacts_forget_rest_bounds(mc);
		mc->element_flat_serial = -1;
		sim->ccd_hits += hits;
		/* Zone by zone: members sorted by root. */
		for (int k = 0; k < mc->touched_count; ++k) {
			int i = mc->touched[k];
			mc->members[k][0] = plait_mesh_contacts_root(mc->zone_parent, i);
			mc->members[k][1] = i;
		}
		qsort(mc->members, (size_t)mc->touched_count, sizeof *mc->members, compare_members);
		for (int start = 0; start < mc->touched_count;) {
			int end = start + 1;
			while (end < mc->touched_count && mc->members[end][0] == mc->members[start][0]) {
				++end;
			}
			if (round < ZONE_ROUNDS) {
				rigidify(p, mc->members, start, end);
			} else {
				bool last_round = round == ZONE_ROUNDS + FREEZE_ROUNDS - 1;
				mc->carried_zones += carry_back(sim, mc->members, start, end, !last_round);
			}
			/* A lone vertex that a round collider's triangle push added (see below) is no
			 * impact zone until frozen. */
			sim->failsafe += end - start > 1 || round >= ZONE_ROUNDS;
			start = end;
		}
		/* Colliders have the last word over the moved vertices too; the next round checks that
		 * this crossed nothing. A triangle pushed out of a round collider may move vertices of
		 * no zone: they join as zones of their own, to be swept again with the others. */
		if (round < ZONE_ROUNDS) {
			sim->contacts +=
			    plait_collide_listed_with_colliders(sim, mc->touched, &mc->touched_count, mc->zone_parent);
		}
	}
	for (int k = 0; k < mc->touched_count; ++k) {
		mc->zone_parent[mc->touched[k]] = -1;
	}
	mc->touched_count = 0;
}
