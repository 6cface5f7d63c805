/* Which of a rigid collider's corners and edges need mesh contacts.
 *
 * A collider's faces meet cloth vertices in the collider pass (contact.c), which ends every
 * substep (and every failsafe round) with each vertex at least its contact distance r (its
 * radius plus the collider's thickness) outside the collider. Mesh contacts add the collider's
 * corners against cloth triangles and its edges against cloth edges, for what reaches between
 * vertices held out like that. Where the collider is smooth at the scale of the cloth's
 * triangles nothing can, and a corner or edge there is left out. The argument, for a cloth
 * triangle T whose edges are at most D long and whose vertices v_i are at least m = r / 2 (the
 * half of r this leans on) from the collider's surface, on its outside:
 *
 * Take a point x of a corner or edge f, and the plane Q through x normal to f's reference
 * normal n0 (the mean of the normals of f's faces). Let M = sqrt(3) m. Suppose every face within
 * distance t + M of f makes an angle at most A(t) < 1 rad with n0, for every t up to D, and
 * none of them has an edge not shared by exactly two faces. Then, over the disc of radius D
 * about x in Q, the surface through x is a graph h over Q (h(x) = 0) with slope at most
 * tan A(t) at distance t from x: walking out from x, the surface point above or below where we
 * are is within t + |h| of x, on a face within that distance of f, and each face leads on to
 * exactly one other. So |h| <= F(t) at distance t, F the integral of tan A from 0, and while
 * F(D) < M the walk never leaves the faces counted. No other sheet of the surface comes within
 * the disc: it would be a face within D + M facing away from n0 (closed surfaces), or one with
 * an open edge.
 *
 * If T touched f at x, then x = sum of l_i v_i (barycentric) and, in heights over Q, each v_i
 * is at least m above the graph under it (that point of the surface is at least m from v_i; for
 * a surface oriented the other way, below it, with signs turned), so with d_i = |v_i - x|
 *   0 = height(x) - h(x) = sum l_i (height(v_i) - h(v_i)) + sum l_i h(v_i) >= m - sum l_i F(d_i).
 * F is convex with F(0) = 0, so F(d_i) <= F(D) d_i / D, and sum l_i d_i <= (sum l_i d_i^2)^1/2
 * = (sum over i < j of l_i l_j |v_i - v_j|^2)^1/2 <= D / sqrt(3): m <= F(D) / sqrt(3), false when
 * F(D) < M. Where F(D) < M, then, f touches no cloth triangle (or segment) with edges up to D at
 * the end of a substep and needs no contacts with it. plait_mesh_smooth_reaches
 * (collision/smooth_reach.c) finds, per corner and edge, such a D: its smooth reach (the
 * largest, or on a fine mesh a little less, found with a cluster of features and its normal
 * for n0; any n0 serves the argument while A stays under a radian).
 *
 * A crossing of T and the collider at the end of a substep needs a collider edge through T (a
 * straight cut of T by one face would leave a vertex of T inside), an edge that can touch T:
 * one whose reach is at most T's longest edge. It came through T, from the free start of the
 * substep, past one of T's edges or with a corner through T. So an edge-edge pair is kept when
 * either triangle of its cloth edge is long enough for the collider's edge, and a corner's reach
 * is at most its edges': then every crossing is one the listed pairs and the failsafe see.
 * Concave and flat edges fall out of the same bound (their faces turn little against n0), and
 * sharp ones keep their contacts at any D.
 *
 * Each cloth element's D (pair_reach) is the longest edge of it and of the triangles across its
 * edges: at a listing with slack, and the list covers only while no edge outgrows it; in the
 * failsafe's traversal, as they end the substep (plait_mesh_contacts_measure_cloth_edges). A
 * deforming collider's angles change from frame to frame, and between frames its triangles'
 * normals are not bounded by those at the frames: it keeps all its corners and edges. */
#include "dynamics/mesh_contact_internal.h"

#include "collision/mesh_shape.h"
#include "collision/smooth_reach.h"

#include <stdatomic.h>
#include <string.h>

/* The share of the contact distance the argument leans on: the collider pass pushes vertices
 * out to all of it, friction and other colliders can take back some. */
#define SMOOTH_MARGIN 0.5f
/* Reaches are looked for up to this many times the longest cloth edge at the build (beyond
 * that, a stretched cloth meets every corner and edge again). */
#define SMOOTH_RANGE 2.0f
/* The smooth reaches of one rigid collider's corners and edges (object o, from its surface's
 * shape), into mc->features from `features` on; false only when out of memory. */
static bool collider_reaches(plait_sim *sim, plait_mesh_contacts *mc, collision_object *o,
                             const plait_mesh_shape *shape, float budget, float range, int features)
{
	const plait_allocator *a = &sim->allocator;
	int nt = shape->triangle_count;
	float *vertex_reach =
	    plait_alloc(a, sizeof(float) * (size_t)(shape->vertex_count > 0 ? shape->vertex_count : 1));
	float *edge_reach = plait_alloc(a, sizeof(float) * (size_t)(3 * nt > 0 ? 3 * nt : 1));
	bool ok = vertex_reach != NULL && edge_reach != NULL &&
	          plait_mesh_smooth_reaches(shape, a, &sim->parallel, budget, range, vertex_reach, edge_reach);
	if (ok) {
		for (int t = 0; t < nt; ++t) {
			const element *el = &mc->elements[o->first + t];
			collider_features *f = &mc->features[features + t];
			f->vertices = el->own_vertices;
			f->edges = el->own_edges;
			for (int k = 0; k < 3; ++k) {
				f->reach[k] = vertex_reach[shape->triangles[t][k]];
				f->reach[3 + k] = edge_reach[3 * t + k];
			}
		}
	}
	plait_free(a, vertex_reach);
	plait_free(a, edge_reach);
	return ok;
}

/* The square of an element's longest edge now (a segment's length; 0 for a point). */
static float longest_edge_sq(const plait_particles *p, const element *el)
{
	float longest = 0.0f;
	for (int m = 0; m < el->size; ++m) {
		vec3 d = v3_sub(p->point[el->v[(m + 1) % el->size]].x, p->point[el->v[m]].x);
		longest = plait_maxf(longest, v3_length_sq(d));
	}
	return longest;
}

/* Whether an object's cloth triangles or curve segments meet colliders' surfaces here. */
static bool meets_collider_surfaces(const plait_sim *sim, const plait_mesh_contacts *mc,
                                    const collision_object *o)
{
	const plait_material *m = &sim->materials[o->material];
	return m->type != PLAIT_OBJECT_COLLIDER && m->collider_flag != PLAIT_COLLIDE_VERTEX && o->count > 0 &&
	       mc->elements[o->first].size >= 2;
}

/* The smooth reaches of every rigid mesh collider's corners and edges (see above), from the
 * current shapes: the contact distance from the thinnest cloth or curve that meets them, the
 * range from their longest edge. Colliders with nothing to leave out (boxes) keep features -1. */
bool plait_mesh_contacts_build_collider_features(plait_sim *sim, plait_mesh_contacts *mc,
                                                 const plait_triangle_edge *edges, int edge_count)
{
	const plait_particles *p = &sim->particles;
	float thinnest = INFINITY, longest = 0.0f;
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		if (!meets_collider_surfaces(sim, mc, o)) {
			continue;
		}
		for (int e = o->first; e < o->first + o->count; ++e) {
			const element *el = &mc->elements[e];
			longest = plait_maxf(longest, sqrtf(longest_edge_sq(p, el)));
			for (int m = 0; m < el->size; ++m) {
				thinnest = plait_minf(thinnest, p->radius[el->v[m]]);
			}
		}
	}
	if (!(longest > 0.0f) || !isfinite(thinnest)) {
		return true;
	}
	int total = 0;
	for (int k = 0; k < mc->object_count; ++k) {
		if (sim->materials[mc->objects[k].material].type == PLAIT_OBJECT_COLLIDER) {
			total += mc->objects[k].count;
		}
	}
	if (total == 0) {
		return true;
	}
	mc->features = plait_alloc_zero(&sim->allocator, (size_t)total, sizeof *mc->features);
	if (mc->features == NULL) {
		return false;
	}
	int next = 0;
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		const plait_material *m = &sim->materials[o->material];
		if (m->type != PLAIT_OBJECT_COLLIDER) {
			continue;
		}
		const plait_collider *c = NULL;
		for (int i = 0; i < sim->collider_count; ++i) {
			c = sim->colliders[i].object == m->object ? &sim->colliders[i] : c;
		}
		const plait_mesh_shape *shape = NULL;
		for (int s = 0; s < sim->surface_count; ++s) {
			shape = sim->surfaces[s].material == o->material ? sim->surfaces[s].shape : shape;
		}
		/* M above: sqrt(3) times the margin the argument leans on. */
		float budget = 1.7320508f * SMOOTH_MARGIN * (thinnest + (c != NULL ? c->thickness : 0.0f));
		if (c == NULL || c->mesh_start != NULL || shape == NULL || shape->triangle_count != o->count ||
		    !(budget > 0.0f)) {
			continue; /* deforming (or unknown): every corner and edge keeps its contacts */
		}
		if (!collider_reaches(sim, mc, o, shape, budget, SMOOTH_RANGE * longest + budget, next)) {
			return false;
		}
		bool any = false;
		for (int t = 0; t < o->count && !any; ++t) {
			for (int q = 0; q < 6; ++q) {
				any = any || mc->features[next + t].reach[q] > 0.0f;
			}
		}
		if (any) {
			o->features = next;
			next += o->count;
		}
	}
	if (next == 0) {
		plait_free(&sim->allocator, mc->features);
		mc->features = NULL;
		return true;
	}
	int count = mc->element_count;
	mc->neighbours = plait_alloc(&sim->allocator, sizeof *mc->neighbours * (size_t)count);
	mc->cloth_bound = plait_alloc_zero(&sim->allocator, (size_t)count, sizeof(float));
	mc->cloth_bound_scratch = plait_alloc_zero(&sim->allocator, (size_t)count, sizeof(float));
	mc->pair_reach = plait_alloc_zero(&sim->allocator, (size_t)count, sizeof(float));
	if (mc->neighbours == NULL || mc->cloth_bound == NULL || mc->cloth_bound_scratch == NULL ||
	    mc->pair_reach == NULL) {
		return false;
	}
	for (int e = 0; e < count; ++e) {
		mc->neighbours[e][0] = mc->neighbours[e][1] = mc->neighbours[e][2] = -1;
	}
	for (int k = 0; k + 1 < edge_count; ++k) {
		const plait_triangle_edge *x = &edges[k], *y = &edges[k + 1];
		if (x->low == y->low && x->high == y->high) {
			mc->neighbours[x->triangle][x->corner] = y->triangle;
			mc->neighbours[y->triangle][y->corner] = x->triangle;
		}
	}
	return true;
}

/* The largest of bound[] over element e and the elements across its edges. */
static float reach_over_neighbours(const plait_mesh_contacts *mc, const float *bound, int e)
{
	float reach = bound[e];
	for (int q = 0; q < 3; ++q) {
		int n = mc->neighbours[e][q];
		reach = n >= 0 ? plait_maxf(reach, bound[n]) : reach;
	}
	return reach;
}

/* Whether element e's longest edge is past its bound. */
static bool outgrown(const plait_particles *p, const plait_mesh_contacts *mc, int e)
{
	return longest_edge_sq(p, &mc->elements[e]) > mc->cloth_bound[e] * mc->cloth_bound[e];
}

/* The longest edge of each cloth triangle and curve segment that meets filtered colliders, into
 * mc->cloth_bound (grown by `slack`), and each one's D for its element pairs with them, into
 * mc->pair_reach: the largest bound over it and the triangles across its edges (an edge-edge
 * pair is owned by one of the two triangles of its cloth edge, and must hold for both). At a
 * listing the bound has slack, and the list covers only while no edge outgrows it
 * (plait_mesh_contacts_list_covers); the failsafe's traversal measures the substep's end,
 * with none. */
/* ---- Node floors and ceilings ------------------------------------------------------------- */

/* Whether collision object o is a filtered collider (its corners and edges have reaches). */
static bool filtered(const plait_mesh_contacts *mc, const collision_object *o)
{
	return mc->features != NULL && o->features >= 0;
}

/* A cloth's tree: each node's largest pair_reach under it, bottom-up (parents come before
 * children in the node array). */
static void fit_ceilings(plait_mesh_contacts *mc, collision_object *o)
{
	const plait_element_tree *tree = &o->tree;
	for (int n = tree->node_count - 1; n >= 0; --n) {
		const plait_tree_node *node = &tree->nodes[n];
		float ceiling = 0.0f;
		if (node->count > 0) {
			for (int k = node->first; k < node->first + node->count; ++k) {
				ceiling = plait_maxf(ceiling, mc->pair_reach[o->first + tree->order[k]]);
			}
		} else {
			ceiling = plait_maxf(o->node_ceiling[node->first], o->node_ceiling[node->first + 1]);
		}
		o->node_ceiling[n] = ceiling;
	}
}

bool plait_mesh_contacts_build_node_floors(plait_sim *sim, plait_mesh_contacts *mc)
{
	if (mc->features == NULL) {
		return true;
	}
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		bool collider = filtered(mc, o), cloth = meets_collider_surfaces(sim, mc, o);
		if ((!collider && !cloth) || o->tree.node_count == 0) {
			continue;
		}
		float *values = plait_alloc_zero(&sim->allocator, (size_t)o->tree.node_count, sizeof(float));
		if (values == NULL) {
			return false;
		}
		if (cloth) {
			o->node_ceiling = values;
			continue;
		}
		o->node_floor = values;
		const plait_element_tree *tree = &o->tree;
		for (int n = tree->node_count - 1; n >= 0; --n) {
			const plait_tree_node *node = &tree->nodes[n];
			float floor = INFINITY;
			if (node->count > 0) {
				for (int q = node->first; q < node->first + node->count; ++q) {
					const collider_features *f = &mc->features[o->features + tree->order[q]];
					for (int m = 0; m < 3; ++m) {
						floor = (f->vertices & (1u << m)) ? plait_minf(floor, f->reach[m]) : floor;
						floor = (f->edges & (1u << m)) ? plait_minf(floor, f->reach[3 + m]) : floor;
					}
				}
			} else {
				floor = plait_minf(values[node->first], values[node->first + 1]);
			}
			values[n] = floor;
		}
	}
	return true;
}

/* A node pair of a filtered collider and a cloth whose every element pair would keep no corner
 * or edge (plait_mesh_contacts_live_features keeps those whose reach the cloth element's D
 * reaches): the cloth's largest D there short of the collider's least reach. */
static bool smooth_node_pair(int node_a, int node_b, void *context)
{
	const smooth_skip *floors = context;
	int collider = floors->collider_first ? node_a : node_b, cloth = floors->collider_first ? node_b : node_a;
	return floors->ceiling[cloth] < floors->floor[collider];
}

const plait_node_skip *plait_mesh_contacts_smooth_skip(const plait_mesh_contacts *mc, int a, int b,
                                                       smooth_skip *floors, plait_node_skip *skip)
{
	const collision_object *oa = &mc->objects[a], *ob = &mc->objects[b];
	if (!mc->skip_smooth) {
		return NULL;
	}
	if (oa->node_floor != NULL && ob->node_ceiling != NULL) {
		*floors = (smooth_skip){oa->node_floor, ob->node_ceiling, true};
	} else if (ob->node_floor != NULL && oa->node_ceiling != NULL) {
		*floors = (smooth_skip){ob->node_floor, oa->node_ceiling, false};
	} else {
		return NULL;
	}
	*skip = (plait_node_skip){NULL, smooth_node_pair, floors};
	return skip;
}

/* The passes over one object's elements below, each element alone: on the workers. */
typedef struct edges_job {
	const plait_sim *sim;
	plait_mesh_contacts *mc;
	float slack;
	_Atomic int outgrown;
} edges_job;

#define EDGES_GRAIN 4096

static void longest_edges(void *context, int begin, int end)
{
	edges_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	for (int e = begin; e < end; ++e) {
		mc->pair_reach[e] = job->slack * sqrtf(longest_edge_sq(&job->sim->particles, &mc->elements[e]));
		if (job->slack > 1.0f) {
			mc->cloth_bound[e] = mc->pair_reach[e];
		}
	}
}

/* The neighbours' bounds, read from cloth_bound (at a listing) or from pair_reach. */
static void neighbours_reach(void *context, int begin, int end)
{
	edges_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	const float *bound = job->slack > 1.0f ? mc->cloth_bound : mc->pair_reach;
	for (int e = begin; e < end; ++e) {
		mc->cloth_bound_scratch[e] = reach_over_neighbours(mc, bound, e);
	}
}

static void take_scratch(void *context, int begin, int end)
{
	edges_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	memcpy(mc->pair_reach + begin, mc->cloth_bound_scratch + begin, sizeof(float) * (size_t)(end - begin));
}

static void find_outgrown(void *context, int begin, int end)
{
	edges_job *job = context;
	for (int e = begin; e < end; ++e) {
		if (outgrown(&job->sim->particles, job->mc, e)) {
			atomic_store_explicit(&job->outgrown, 1, memory_order_relaxed);
			return;
		}
	}
}

/* The longest edge of each cloth triangle and curve segment that meets filtered colliders, into
 * mc->cloth_bound (grown by `slack`), and each one's D for its element pairs with them, into
 * mc->pair_reach: the largest bound over it and the triangles across its edges (an edge-edge
 * pair is owned by one of the two triangles of its cloth edge, and must hold for both). At a
 * listing the bound has slack, and the list covers only while no edge outgrows it
 * (plait_mesh_contacts_list_covers); the failsafe's traversal measures the substep's end,
 * with none. */
void plait_mesh_contacts_measure_cloth_edges(plait_sim *sim, plait_mesh_contacts *mc, float slack)
{
	edges_job job = {.sim = sim, .mc = mc, .slack = slack};
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		if (!meets_collider_surfaces(sim, mc, o)) {
			continue;
		}
		int first = o->first, last = o->first + o->count;
		plait_parallel_for(&sim->parallel, longest_edges, &job, first, last, EDGES_GRAIN);
		plait_parallel_for(&sim->parallel, neighbours_reach, &job, first, last, EDGES_GRAIN);
		plait_parallel_for(&sim->parallel, take_scratch, &job, first, last, EDGES_GRAIN);
		if (o->node_ceiling != NULL) {
			fit_ceilings(mc, &mc->objects[k]);
		}
	}
}

/* Whether every cloth edge that meets filtered colliders is still within its bound. */
bool plait_mesh_contacts_cloth_edges_within_bounds(plait_sim *sim, plait_mesh_contacts *mc)
{
	edges_job job = {.sim = sim, .mc = mc, .slack = 1.0f};
	atomic_init(&job.outgrown, 0);
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		if (meets_collider_surfaces(sim, mc, o)) {
			plait_parallel_for(&sim->parallel, find_outgrown, &job, o->first, o->first + o->count,
			                   EDGES_GRAIN);
		}
	}
	return !atomic_load_explicit(&job.outgrown, memory_order_relaxed);
}

int plait_mesh_contacts_mark_outgrown(const plait_sim *sim, const plait_mesh_contacts *mc, uint8_t *marked)
{
	const plait_particles *p = &sim->particles;
	int newly = 0;
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		if (!meets_collider_surfaces(sim, mc, o)) {
			continue;
		}
		for (int e = o->first; e < o->first + o->count; ++e) {
			if (!outgrown(p, mc, e)) {
				continue;
			}
			for (int q = -1; q < 3; ++q) {
				int n = q < 0 ? e : mc->neighbours[e][q];
				if (n < 0) {
					continue;
				}
				const element *el = &mc->elements[n];
				for (int m = 0; m < el->size; ++m) {
					newly += !marked[el->v[m]];
					marked[el->v[m]] = 1;
				}
			}
		}
	}
	return newly;
}

void plait_mesh_contacts_rebound_cloth_edges(const plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_particles *p = &sim->particles;
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		if (!meets_collider_surfaces(sim, mc, o)) {
			continue;
		}
		for (int e = o->first; e < o->first + o->count; ++e) {
			if (outgrown(p, mc, e)) {
				mc->cloth_bound[e] = CLOTH_EDGE_SLACK * sqrtf(longest_edge_sq(p, &mc->elements[e]));
			}
		}
		for (int e = o->first; e < o->first + o->count; ++e) {
			mc->pair_reach[e] = reach_over_neighbours(mc, mc->cloth_bound, e);
		}
		if (o->node_ceiling != NULL) {
			fit_ceilings(mc, &mc->objects[k]);
		}
	}
}

/* Which corners and edges of a filtered collider's element c meet cloth element e here: bits of
 * its own vertices and edges whose smooth reach the cloth's D (pair_reach) does not stay under. */
void plait_mesh_contacts_live_features(const plait_mesh_contacts *mc, int c, int e, uint8_t *vertices,
                                       uint8_t *edges)
{
	const collision_object *o = &mc->objects[mc->object_of[mc->elements[c].v[0]]];
	const collider_features *f = &mc->features[o->features + c - o->first];
	float d = mc->pair_reach[e];
	uint8_t v = 0, g = 0;
	for (int q = 0; q < 3; ++q) {
		v |= (uint8_t)((d >= f->reach[q]) << q);
		g |= (uint8_t)((d >= f->reach[3 + q]) << q);
	}
	*vertices = v;
	*edges = g;
}

void plait_mesh_contacts_collider_features(const plait_sim *sim, int *kept, int *left_out)
{
	const plait_mesh_contacts *mc = sim->mesh_contacts;
	*kept = mc != NULL ? mc->features_kept : 0;
	*left_out = mc != NULL ? mc->features_left_out : 0;
}
