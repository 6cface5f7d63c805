#include "dynamics/mesh_contact.h"

#include <stdlib.h>
#include <string.h>

#include "collision/ccd.h"
#include "collision/closest.h"
#include "collision/element_tree.h"
#include "collision/mesh_shape.h"
#include "collision/smooth_reach.h"
#include "dynamics/contact.h"
#include "topology/topology.h"

/* Primitive pairs. The first primitive's vertices come first in v[]. */
typedef enum pair_type {
	PAIR_VERTEX_FACE = 0, /* v[0] against triangle v[1..3] */
	PAIR_EDGE_EDGE,       /* v[0]-v[1] against v[2]-v[3] */
	PAIR_VERTEX_EDGE,     /* v[0] against v[1]-v[2] */
	PAIR_VERTEX_VERTEX,   /* v[0] against v[1] */
} pair_type;

static const int pair_size[4] = {4, 4, 3, 2};

/* Listing on the workers: traversals cut this many splits down, into at most so many pieces. */
#define PIECE_DEPTH 6
#define MAX_PIECES 2048

/* A collision element: a triangle of a cloth, a segment of a curve, or a loose particle. Each
 * vertex and each edge is tested by exactly one element, its owner (the first element that has
 * it): a pair of primitives is then met once, through the pair of their owners, whose boxes
 * hold the primitives' boxes. */
typedef struct element {
	int v[3];
	int material;
	uint8_t size;         /* vertices: 1, 2 or 3 */
	uint8_t own_vertices; /* bit k: v[k] */
	uint8_t own_edges;    /* bit k: edge v[k] - v[(k + 1) % size] (a segment has one) */
} element;

/* The elements of one object, with their own tree: objects meet pairwise through their trees,
 * and only an object that collides with itself is traversed against itself. */
typedef struct collision_object {
	int first, count; /* its elements */
	int material;
	bool self;
	plait_element_tree tree;
	int features; /* a collider's: index of its first element's collider_features, or -1 */
} collision_object;

/* A rigid mesh collider's corners and edges (plait_collider.first). Each element's own vertices
 * and edges as built, and for each the longest cloth edge below which it is left out of mesh
 * contacts (smooth_reach): a corner or edge that smooth cannot reach between the vertices of so
 * short a triangle held out of the collider by the collider pass (contact.c). */
typedef struct collider_features {
	uint8_t vertices, edges; /* as built (element.own_vertices, own_edges) */
	float reach[6];          /* vertex k: reach[k]; edge k: reach[3 + k]; scene units */
} collider_features;

/* An element's box, centroid and normal at the gather, for its cheap rejections. */
typedef struct element_shape {
	vec3 lower, upper;
	vec3 centre;
	vec3 normal; /* triangles: unit normal (zero when degenerate) */
} element_shape;

typedef struct contact_pair {
	int v[4];
	uint8_t type;
	uint8_t self;
	float distance; /* contact distance, scene units */
	float friction;
	float side;     /* vertex-face: which side of the triangle's plane the vertex is on (+1, -1) */
	vec3 direction; /* the others: unit vector from the second primitive to the first */
	float scale[2]; /* 0 for a primitive not pushed (lower collision layer), else 1 */
	float lower;    /* rest pairs: a lower bound of their distance now, < 0 when unknown */
} contact_pair;

/* Listing on the workers (gather_on_workers): a piece of a traversal, and its own list. */
typedef struct gather_piece {
	int a, b;    /* collision objects (a == b: self) */
	int node[2]; /* the node pair in their trees */
} gather_piece;

typedef struct piece_list {
	contact_pair *pairs;
	int count, capacity;
	bool full;
	int features_kept, features_left_out;
} piece_list;

/* A crossing found by a failsafe sweep on a worker, joined into its impact zone afterwards on
 * the calling thread, in the order the sweeps would have met it. */
typedef struct sweep_hit {
	int v[4];
	int n;
} sweep_hit;

#define HIT_ROOM 4 /* crossings a piece of a sweep keeps; one that finds more (rare) is swept again */

typedef struct plait_mesh_contacts {
	int element_count;
	element *elements;
	float *element_reach;  /* an element's largest radius (at the last listing) */
	float *element_guard;  /* an element's largest guard (at the last listing) */
	element_shape *shapes; /* at the last listing */
	vec3 *lower, *upper;   /* element boxes */
	int object_count;
	collision_object *objects;
	/* Colliders' corners and edges left out where smooth (see build_collider_features): per
	 * filtered collider element its features; per element of a cloth or curve that meets them
	 * its edge-connected neighbours (-1: none), its longest edge's bound while the list serves,
	 * and the D its element pairs with colliders are decided with. */
	collider_features *features;
	int (*neighbours)[3];
	float *cloth_bound, *cloth_bound_scratch, *pair_reach;
	int features_kept, features_left_out; /* at the last listing, over its element pairs */
	/* Neighbours in the start shape. Within a self-colliding object, primitives closer than
	 * their self-collision distance at the start (seed 000 §4.5) never push each other: that is
	 * left to the object's own constraints. They may still not pass through each other: they
	 * are the rest pairs, swept by the failsafe in every substep. Element pairs all of whose
	 * primitive pairs share a vertex or are rest pairs are excluded whole: per element, a
	 * sorted run of excluded_list from excluded_start[e] to excluded_start[e + 1]. */
	int rest_count, rest_capacity;
	struct contact_pair *rest_pairs;
	int *excluded_start;
	int *excluded_list;
	bool active;
	bool gathered;   /* the candidates of this substep are ready */
	bool list_valid; /* the list of the last gather may serve again (see list_covers) */
	int pair_count, pair_capacity;
	contact_pair *pairs;
	bool out_of_memory;   /* the candidate list could not grow: a contact may be left to the failsafe */
	int traversal_sweeps; /* primitive pairs swept by the failsafe's last traversal (0 before it) */
	/* Listing on the workers (gather_on_workers): the traversals' pieces, a list each, and the
	 * length of the last list (to size the pieces' lists). */
	int piece_count;
	gather_piece *pieces;
	int (*piece_nodes)[2]; /* scratch of cut_pieces */
	piece_list *piece_lists;
	int last_listed;
	/* The failsafe's sweeps on the workers (sweep_on_workers): per piece, its crossings (room for
	 * HIT_ROOM), how many, the pairs it swept, and whether it ran out of room. */
	sweep_hit *piece_hits;
	int *piece_hit_count, *piece_swept;
	bool *piece_full;
	/* The list holds every pair that was within LIST_SCALE times its contact distance plus the
	 * guards of its vertices at the gather, so it holds every pair that can touch or cross as
	 * long as no vertex is farther than its guard from where it was then (list_covers). */
	vec3 *x_gather;
	float *guard;       /* per particle: how far it may move relative to its object */
	int *object_of;     /* per particle: its collision object, or -1 */
	vec3 *shift;        /* per collision object: mean motion since the gather (scratch) */
	int *object_counts; /* per collision object: scratch of object_shifts */
	float *allowance;   /* per pair of objects: how far they may move relative to each other */
	float allowance_max;
	/* Failsafe scratch: union-find over particles, and the particles it touched. */
	int particle_capacity;
	int *zone_parent;
	int *touched;
	int touched_count;
	int (*members)[2]; /* (root, particle), sorted to walk zone by zone */
} plait_mesh_contacts;

/* ---- Building the elements --------------------------------------------------------------- */

static void free_elements(plait_mesh_contacts *mc, const plait_allocator *a)
{
	plait_free(a, mc->elements);
	plait_free(a, mc->element_reach);
	plait_free(a, mc->element_guard);
	mc->element_guard = NULL;
	plait_free(a, mc->shapes);
	mc->shapes = NULL;
	plait_free(a, mc->lower);
	plait_free(a, mc->upper);
	for (int k = 0; k < mc->object_count; ++k) {
		plait_element_tree_destroy(&mc->objects[k].tree, a);
	}
	plait_free(a, mc->objects);
	plait_free(a, mc->features);
	plait_free(a, mc->neighbours);
	plait_free(a, mc->cloth_bound);
	plait_free(a, mc->cloth_bound_scratch);
	plait_free(a, mc->pair_reach);
	mc->features = NULL;
	mc->neighbours = NULL;
	mc->cloth_bound = mc->cloth_bound_scratch = mc->pair_reach = NULL;
	plait_free(a, mc->shift);
	plait_free(a, mc->allowance);
	plait_free(a, mc->object_counts);
	mc->object_counts = NULL;
	mc->shift = NULL;
	mc->allowance = NULL;
	plait_free(a, mc->excluded_start);
	plait_free(a, mc->excluded_list);
	plait_free(a, mc->rest_pairs);
	mc->rest_pairs = NULL;
	mc->rest_count = mc->rest_capacity = 0;
	mc->excluded_start = mc->excluded_list = NULL;
	mc->objects = NULL;
	mc->object_count = 0;
	mc->elements = NULL;
	mc->element_reach = NULL;
	mc->lower = mc->upper = NULL;
	mc->element_count = 0;
}

static bool material_collides(const plait_sim *sim, int material)
{
	return sim->materials[material].collide;
}

static bool build_rest_pairs(plait_sim *sim, plait_mesh_contacts *mc);
static bool build_collider_features(plait_sim *sim, plait_mesh_contacts *mc, const plait_triangle_edge *edges,
                                    int edge_count);

static bool excluded(const plait_mesh_contacts *mc, int a, int b)
{
	if (mc->excluded_start == NULL) {
		return false;
	}
	for (int k = mc->excluded_start[a]; k < mc->excluded_start[a + 1]; ++k) {
		if (mc->excluded_list[k] >= b) {
			return mc->excluded_list[k] == b;
		}
	}
	return false;
}

static bool build_elements(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_allocator *a = &sim->allocator;
	plait_particles *p = &sim->particles;
	free_elements(mc, a);
	mc->active = false;
	/* Triangles of cloths, then the particles of no surface (curves' vertices, loose ones). */
	int triangles = 0;
	for (int s = 0; s < sim->surface_count; ++s) {
		if (material_collides(sim, sim->surfaces[s].material)) {
			triangles += sim->surfaces[s].shape->triangle_count;
		}
	}
	int segments = 0;
	for (int c = 0; c < sim->chain_count; ++c) {
		if (material_collides(sim, sim->chains[c].material)) {
			segments += sim->chains[c].count - 1;
		}
	}
	if (triangles + segments == 0) {
		return true; /* points alone meet as particle pairs (contact.c) */
	}
	bool *in_surface = plait_alloc_zero(a, (size_t)(p->count > 0 ? p->count : 1), sizeof(bool));
	if (in_surface == NULL) {
		return false;
	}
	for (int s = 0; s < sim->surface_count; ++s) {
		for (int k = 0; k < sim->surfaces[s].shape->vertex_count; ++k) {
			in_surface[sim->surfaces[s].first + k] = true;
		}
	}
	for (int c = 0; c < sim->chain_count; ++c) {
		for (int k = 0; k < sim->chains[c].count; ++k) {
			in_surface[sim->chains[c].first + k] = true;
		}
	}
	int points = 0;
	for (int i = 0; i < p->count; ++i) {
		points += !in_surface[i] && (p->flags[i] & PLAIT_PARTICLE_COLLIDE) &&
		          material_collides(sim, p->material[i]);
	}
	int count = triangles + segments + points;
	mc->elements = plait_alloc_zero(a, (size_t)count, sizeof *mc->elements);
	mc->element_reach = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->element_guard = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->shapes = plait_alloc_zero(a, (size_t)count, sizeof *mc->shapes);
	mc->lower = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->upper = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	plait_triangle_edge *edges =
	    plait_alloc_zero(a, (size_t)(triangles > 0 ? 3 * triangles : 1), sizeof *edges);
	bool *owned = plait_alloc_zero(a, (size_t)p->count, sizeof(bool));
	/* At most one object per surface, per chain and per particle run. */
	mc->objects =
	    plait_alloc_zero(a, (size_t)(sim->surface_count + sim->chain_count + points), sizeof *mc->objects);
	bool active = false;
	int edge_count = 0;
	bool ok = mc->elements != NULL && mc->element_reach != NULL && mc->element_guard != NULL &&
	          mc->shapes != NULL && mc->lower != NULL && mc->upper != NULL && edges != NULL &&
	          owned != NULL && mc->objects != NULL;
	if (ok) {
		int e = 0;
		for (int s = 0; s < sim->surface_count; ++s) {
			const plait_surface *surface = &sim->surfaces[s];
			if (!material_collides(sim, surface->material)) {
				continue;
			}
			const plait_material *m = &sim->materials[surface->material];
			mc->objects[mc->object_count++] = (collision_object){
			    e, surface->shape->triangle_count, surface->material, m->self_collide, {0}, -1};
			for (int t = 0; t < surface->shape->triangle_count; ++t, ++e) {
				element *el = &mc->elements[e];
				el->size = 3;
				el->material = surface->material;
				for (int k = 0; k < 3; ++k) {
					el->v[k] = surface->first + surface->shape->triangles[t][k];
				}
				for (int k = 0; k < 3; ++k) {
					int i = el->v[k], j = el->v[(k + 1) % 3];
					edges[edge_count++] = (plait_triangle_edge){i < j ? i : j, i < j ? j : i, e, k};
					if (!owned[i]) {
						owned[i] = true;
						el->own_vertices |= (uint8_t)(1u << k);
					}
				}
			}
		}
		/* Segments of curves: each owns its edge and its first vertex; the last segment also
		 * its last vertex. */
		for (int c = 0; c < sim->chain_count; ++c) {
			const plait_chain *chain = &sim->chains[c];
			if (!material_collides(sim, chain->material) || chain->count < 2) {
				continue;
			}
			const plait_material *m = &sim->materials[chain->material];
			mc->objects[mc->object_count++] =
			    (collision_object){e, chain->count - 1, chain->material, m->self_collide, {0}, -1};
			for (int k = 0; k + 1 < chain->count; ++k, ++e) {
				element *el = &mc->elements[e];
				el->size = 2;
				el->material = chain->material;
				el->v[0] = chain->first + k;
				el->v[1] = el->v[2] = chain->first + k + 1;
				el->own_edges = 1;
				el->own_vertices = (uint8_t)(k + 2 == chain->count ? 3 : 1);
			}
		}
		for (int i = 0; i < p->count; ++i) {
			if (!in_surface[i] && (p->flags[i] & PLAIT_PARTICLE_COLLIDE) &&
			    material_collides(sim, p->material[i])) {
				collision_object *last = mc->object_count > 0 ? &mc->objects[mc->object_count - 1] : NULL;
				if (last == NULL || last->material != p->material[i] || last->first + last->count != e) {
					/* Loose points never meet their own kind here (particle pairs do). */
					mc->objects[mc->object_count++] =
					    (collision_object){e, 0, p->material[i], false, {0}, -1};
					last = &mc->objects[mc->object_count - 1];
				}
				last->count += 1;
				element *el = &mc->elements[e++];
				el->size = 1;
				el->material = p->material[i];
				el->v[0] = el->v[1] = el->v[2] = i;
				el->own_vertices = 1;
			}
		}
		plait_sort_triangle_edges(edges, edge_count);
		for (int k = 0; k < edge_count; ++k) {
			if (k == 0 || edges[k].low != edges[k - 1].low || edges[k].high != edges[k - 1].high) {
				mc->elements[edges[k].triangle].own_edges |= (uint8_t)(1u << edges[k].corner);
			}
		}
		mc->element_count = count;
		/* One object that does not collide with itself meets nothing here: its contacts with
		 * colliders are the particle pass's (contact.c). It needs no trees, features or rest
		 * pairs (a hanging cloth's tree cost more than its first frame's solve). */
		active = mc->object_count > 1 || (mc->object_count == 1 && mc->objects[0].self);
	}
	if (ok && active) {
		ok = build_collider_features(sim, mc, edges, edge_count);
		/* Each object's tree, shaped from the current positions. */
		vec3 *centres = mc->lower;
		for (int k = 0; k < count; ++k) {
			const element *el = &mc->elements[k];
			vec3 c = {0.0f, 0.0f, 0.0f};
			for (int m = 0; m < el->size; ++m) {
				c = v3_add(c, p->point[el->v[m]].x);
			}
			centres[k] = v3_scale(c, 1.0f / (float)el->size);
		}
		for (int k = 0; k < mc->object_count && ok; ++k) {
			collision_object *o = &mc->objects[k];
			ok = plait_element_tree_build(&o->tree, a, centres + o->first, o->count);
		}
		ok = ok && build_rest_pairs(sim, mc);
		int objects = mc->object_count;
		mc->shift = plait_alloc_zero(a, (size_t)objects, sizeof(vec3));
		mc->allowance = plait_alloc_zero(a, (size_t)(objects * objects), sizeof(float));
		mc->object_counts = plait_alloc_zero(a, (size_t)objects, sizeof(int));
		ok = ok && mc->shift != NULL && mc->allowance != NULL && mc->object_counts != NULL;
	}
	plait_free(a, edges);
	plait_free(a, owned);
	plait_free(a, in_surface);
	if (!ok) {
		free_elements(mc, a);
		return false;
	}
	mc->active = active;
	if (!mc->active) {
		free_elements(mc, a);
	}
	return true;
}

static bool reserve_particles(plait_sim *sim, plait_mesh_contacts *mc)
{
	int count = sim->particles.count;
	if (mc->particle_capacity >= count) {
		return true;
	}
	const plait_allocator *a = &sim->allocator;
	plait_free(a, mc->zone_parent);
	plait_free(a, mc->touched);
	plait_free(a, mc->members);
	plait_free(a, mc->x_gather);
	plait_free(a, mc->guard);
	plait_free(a, mc->object_of);
	mc->x_gather = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->guard = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->object_of = plait_alloc_zero(a, (size_t)count, sizeof(int));
	mc->list_valid = false;
	mc->zone_parent = plait_alloc_zero(a, (size_t)count, sizeof(int));
	mc->touched = plait_alloc_zero(a, (size_t)count, sizeof(int));
	mc->members = plait_alloc_zero(a, (size_t)count, sizeof *mc->members);
	if (mc->zone_parent == NULL || mc->touched == NULL || mc->members == NULL || mc->x_gather == NULL ||
	    mc->guard == NULL || mc->object_of == NULL) {
		mc->particle_capacity = 0;
		return false;
	}
	for (int i = 0; i < count; ++i) {
		mc->zone_parent[i] = -1;
	}
	mc->particle_capacity = count;
	return true;
}

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
	}
	if (sim->mesh_contacts_dirty) {
		mc->list_valid = false;
		mc->pair_count = 0;
		sim->mesh_contacts_dirty_objects = true;
		if (!build_elements(sim, mc)) {
			return false;
		}
		sim->mesh_contacts_dirty = false;
	}
	if (mc->active && !reserve_particles(sim, mc)) {
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
	*active = mc->active;
	return true;
}

/* The scratch of the listing and the failsafe's sweeps on the workers (gather_on_workers,
 * sweep_on_workers). */
static void free_pieces(plait_mesh_contacts *mc, const plait_allocator *a)
{
	if (mc->piece_lists != NULL) {
		for (int k = 0; k < MAX_PIECES; ++k) {
			plait_free(a, mc->piece_lists[k].pairs);
		}
	}
	plait_free(a, mc->pieces);
	plait_free(a, mc->piece_nodes);
	plait_free(a, mc->piece_lists);
	plait_free(a, mc->piece_hits);
	plait_free(a, mc->piece_hit_count);
	plait_free(a, mc->piece_swept);
	plait_free(a, mc->piece_full);
	mc->pieces = NULL;
	mc->piece_nodes = NULL;
	mc->piece_lists = NULL;
	mc->piece_hits = NULL;
	mc->piece_hit_count = mc->piece_swept = NULL;
	mc->piece_full = NULL;
	mc->piece_count = 0;
}

/* That scratch, made once, all of it or none; false when out of memory. */
static bool reserve_pieces(plait_mesh_contacts *mc, const plait_allocator *a)
{
	if (mc->pieces != NULL) {
		return true;
	}
	mc->pieces = plait_alloc_zero(a, MAX_PIECES, sizeof *mc->pieces);
	mc->piece_nodes = plait_alloc_zero(a, MAX_PIECES, sizeof *mc->piece_nodes);
	mc->piece_lists = plait_alloc_zero(a, MAX_PIECES, sizeof *mc->piece_lists);
	mc->piece_hits = plait_alloc_zero(a, (size_t)MAX_PIECES * HIT_ROOM, sizeof *mc->piece_hits);
	mc->piece_hit_count = plait_alloc_zero(a, MAX_PIECES, sizeof(int));
	mc->piece_swept = plait_alloc_zero(a, MAX_PIECES, sizeof(int));
	mc->piece_full = plait_alloc_zero(a, MAX_PIECES, sizeof(bool));
	if (mc->pieces == NULL || mc->piece_nodes == NULL || mc->piece_lists == NULL || mc->piece_hits == NULL ||
	    mc->piece_hit_count == NULL || mc->piece_swept == NULL || mc->piece_full == NULL) {
		free_pieces(mc, a);
		return false;
	}
	return true;
}

void plait_mesh_contacts_destroy(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc == NULL) {
		return;
	}
	const plait_allocator *a = &sim->allocator;
	free_elements(mc, a);
	plait_free(a, mc->pairs);
	plait_free(a, mc->zone_parent);
	plait_free(a, mc->touched);
	plait_free(a, mc->members);
	plait_free(a, mc->x_gather);
	plait_free(a, mc->guard);
	plait_free(a, mc->object_of);
	free_pieces(mc, a);
	plait_free(a, mc);
	sim->mesh_contacts = NULL;
}

static void forget_rest_bounds(plait_mesh_contacts *mc);

void plait_mesh_contacts_begin_substep(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc != NULL) {
		mc->gathered = false;
		if (sim->substep == 0) {
			forget_rest_bounds(mc); /* positions may have been set between frames */
		}
	}
}

/* ---- Geometry of primitive pairs --------------------------------------------------------- */

static float primitive_distance(int type, const vec3 *x)
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

/* Cheap lower bounds of primitive_distance (closest.h), less a rounding allowance (scene units,
 * well under every margin): most pairs the traversals meet are neighbours in the cloth, about an
 * edge apart, and these settle them without the closest points. */
#define REJECT_SLACK 1e-5f

static float distance_lower_bound(int type, const vec3 *x)
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

static void gather_points(const vec3 *source, const int *v, int n, vec3 *out)
{
	for (int k = 0; k < n; ++k) {
		out[k] = source[v[k]];
	}
}

static void gather_current(const plait_point *point, const int *v, int n, vec3 *out)
{
	for (int k = 0; k < n; ++k) {
		out[k] = point[v[k]].x;
	}
}

/* Whether the pair's primitives, moving on straight lines from start to end, come within
 * distance of each other (the conservative test: never a miss). */
static bool paths_meet(int type, const vec3 *start, const vec3 *end, float distance)
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
static float largest_motion(int type, const vec3 *start, const vec3 *end)
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
static bool paths_apart(int type, const vec3 *start, const vec3 *end, float distance)
{
	float motion = largest_motion(type, start, end);
	float quick = distance_lower_bound(type, start) + distance_lower_bound(type, end) - motion;
	if (0.5f * quick > distance) {
		return true;
	}
	float d0 = primitive_distance(type, start), d1 = primitive_distance(type, end);
	return 0.5f * (d0 + d1 - motion) > distance;
}

/* ---- Which primitive pairs exist --------------------------------------------------------- */

/* The failsafe keeps primitives this far apart, scene units: a thousandth of a millimetre in
 * metres, well above float rounding at the sizes of cloth and well below any thickness. */
#define FAILSAFE_DISTANCE 1e-6f

/* Pairs are listed within this many times their contact distance (plus their guards). */
#define LIST_SCALE 1.1f

typedef enum stage {
	STAGE_REST, /* finding the rest pairs, from the start positions */
	STAGE_GATHER,
	STAGE_FAILSAFE,
} stage;

typedef struct pair_pass {
	plait_sim *sim;
	plait_mesh_contacts *mc;
	stage stage;
	float failsafe_distance;
	int hits;
	float list_distance; /* STAGE_GATHER: of the element pair being visited */
	float pair_slack;    /* STAGE_GATHER: how far its primitives may come closer (guards, allowance) */
	/* STAGE_REST: whether every primitive pair of the element pair met so far is a rest pair
	 * (or shares a vertex); the element pairs that are, for the exclusion lists. */
	bool all_rest;
	int excluded_count, excluded_capacity;
	int (*excluded)[2];
	bool failed;
	int swept; /* STAGE_FAILSAFE: primitive pairs swept */
	/* STAGE_GATHER: where the listed pairs go; with fixed_capacity (on a worker, where the
	 * allocator may not be called) a full list sets `full` instead of growing. */
	contact_pair **out_pairs;
	int *out_count, *out_capacity;
	bool fixed_capacity, full;
	int features_kept, features_left_out; /* STAGE_GATHER: see plait_mesh_contacts */
	/* STAGE_FAILSAFE on a worker: crossings go here (room for HIT_ROOM; `full` past it) instead
	 * of into the impact zones. */
	sweep_hit *hits_out;
	int hits_count;
} pair_pass;

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

static bool add_pair_to(plait_sim *sim, contact_pair **pairs, int *count, int *capacity,
                        const contact_pair *pair)
{
	if (*count == *capacity) {
		int bigger_capacity = *capacity < 256 ? 256 : 2 * *capacity;
		contact_pair *bigger = plait_alloc_zero(&sim->allocator, (size_t)bigger_capacity, sizeof *bigger);
		if (bigger == NULL) {
			return false;
		}
		if (*count > 0) {
			memcpy(bigger, *pairs, sizeof *bigger * (size_t)*count);
		}
		plait_free(&sim->allocator, *pairs);
		*pairs = bigger;
		*capacity = bigger_capacity;
	}
	(*pairs)[(*count)++] = *pair;
	return true;
}

static bool add_pair(pair_pass *pass, const contact_pair *pair)
{
	if (pass->fixed_capacity && *pass->out_count == *pass->out_capacity) {
		pass->full = true;
		return false;
	}
	if (!add_pair_to(pass->sim, pass->out_pairs, pass->out_count, pass->out_capacity, pair)) {
		pass->mc->out_of_memory = true;
		return false;
	}
	return true;
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

/* The failsafe's test of one pair: swept from the start of the substep to now. */
static void sweep_pair(pair_pass *pass, int type, const int *v)
{
	const plait_particles *p = &pass->sim->particles;
	int n = pair_size[type];
	vec3 start[4] = {{0}}, end[4] = {{0}};
	gather_points(p->x_prev, v, n, start);
	gather_current(p->point, v, n, end);
	pass->swept += 1;
	if (paths_apart(type, start, end, pass->failsafe_distance)) {
		return;
	}
	if (paths_meet(type, start, end, pass->failsafe_distance)) {
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

/* A primitive pair met by the traversal: in the failsafe it is swept; in the gather stage it is
 * listed when its paths may come within its list distance: as a contact, or (pairs that only
 * the failsafe watches) as a pair to sweep at the end of the substep. */
static void visit_primitives(pair_pass *pass, int type, const int *v, const plait_material *first,
                             const plait_material *second, bool self)
{
	int n = pair_size[type];
	if (shares_vertex(v, n)) {
		return;
	}
	if (pass->stage == STAGE_FAILSAFE) {
		sweep_pair(pass, type, v);
		return;
	}
	plait_sim *sim = pass->sim;
	plait_mesh_contacts *mc = pass->mc;
	plait_particles *p = &sim->particles;
	int first_count = type == PAIR_EDGE_EDGE ? 2 : 1;
	if (pass->stage == STAGE_REST) {
		float distance = mean_radius(p, v, first_count) + mean_radius(p, v + first_count, n - first_count);
		if (self) {
			distance *= first->self_width_scale;
		}
		vec3 initial[4] = {{0}};
		gather_points(p->x_start, v, n, initial);
		float rest = primitive_distance(type, initial);
		if (rest >= distance) {
			pass->all_rest = false;
			return;
		}
		if (type == PAIR_VERTEX_VERTEX) {
			return; /* no crossing to watch */
		}
		contact_pair pair = {{v[0], v[1], n > 2 ? v[2] : v[1], n > 3 ? v[3] : v[1]},
		                     (uint8_t)type,
		                     1,
		                     0.0f,
		                     0.0f,
		                     1.0f,
		                     {0.0f, 1.0f, 0.0f},
		                     {1.0f, 1.0f},
		                     -1.0f};
		if (!add_pair_to(sim, &mc->rest_pairs, &mc->rest_count, &mc->rest_capacity, &pair)) {
			pass->failed = true;
		}
		return;
	}
	float list_distance = pass->list_distance;
	float now = 0.0f;
	vec3 start[4] = {{0}}, end[4] = {{0}};
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
	    lower_a.z - upper_b.z > list_distance || lower_b.z - upper_a.z > list_distance ||
	    (now = primitive_distance(type, end)) > list_distance) {
		return;
	}
	float distance = mean_radius(p, v, first_count) + mean_radius(p, v + first_count, n - first_count);
	if (self) {
		distance *= first->self_width_scale;
	}
	if (self && distance > 0.0f) {
		/* A rest pair: the failsafe watches it (mc->rest_pairs); no contact. */
		vec3 initial[4] = {{0}};
		gather_points(p->x_start, v, n, initial);
		if (primitive_distance(type, initial) < distance) {
			return;
		}
	}
	gather_points(p->x_prev, v, n, start);
	contact_pair pair = {{v[0], v[1], n > 2 ? v[2] : v[1], n > 3 ? v[3] : v[1]},
	                     (uint8_t)type,
	                     (uint8_t)self,
	                     distance,
	                     plait_combined_friction(first->friction, second->friction),
	                     1.0f,
	                     {0.0f, 1.0f, 0.0f},
	                     {1.0f, 1.0f},
	                     -1.0f};
	/* The thickness between two primitives never exceeds their separation at the start frame
	 * (seed 000 §4.5): a pair of two objects that started closer keeps that closeness. (Within
	 * one object such pairs are rest pairs.) */
	if (distance > 0.0f && !self) {
		vec3 initial[4];
		gather_points(p->x_start, v, n, initial);
		pair.distance = plait_minf(distance, primitive_distance(type, initial));
	}
	/* Edges whose closest points are an end of either are in reach of a vertex-face pair of
	 * the triangles round that end: only the failsafe watches them. */
	if (type == PAIR_EDGE_EDGE && pair.distance > 0.0f) {
		float ps, pt;
		plait_closest_segments(end[0], end[1], end[2], end[3], &ps, &pt);
		if (ps <= 0.0f || ps >= 1.0f || pt <= 0.0f || pt >= 1.0f) {
			pair.distance = 0.0f;
		}
	}
	if (first->collision_layer != second->collision_layer) {
		pair.scale[first->collision_layer < second->collision_layer ? 0 : 1] = 0.0f;
	}
	start_side(&pair, start, end);
	/* While the list covers, the pair's vertices stay within their guards (and its objects
	 * within their allowance) of here, so its paths stay this far apart (the failsafe's
	 * bound). */
	pair.lower = now - pass->pair_slack;
	(void)add_pair(pass, &pair);
}

static bool self_allows(const plait_material *m, int type)
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

/* Whether a vertex of material mv meets a triangle of material mo here. A collider's faces
 * meet other objects' vertices in the collider pass (contact.c: continuous, with the trapped
 * check); here they meet only their edges, and their corners the others' triangles. */
static bool vertex_meets_face(const plait_material *mv, const plait_material *mo)
{
	return mo->type != PLAIT_OBJECT_COLLIDER || mv->type == PLAIT_OBJECT_COLLIDER;
}

static void live_features(const plait_mesh_contacts *mc, int c, int e, uint8_t *vertices, uint8_t *edges);

static int bits3(unsigned bits)
{
	return (int)(bits & 1u) + (int)((bits >> 1) & 1u) + (int)((bits >> 2) & 1u);
}

/* The primitive pairs an element pair owns, each handed to visit_primitives. In the gather,
 * most are rejected first from the elements' points (loaded once) and shapes, before
 * visit_primitives loads them again for its exact test; the other stages see them all. The
 * failsafe leaves vertex-vertex pairs out (nothing to cross). */
static void walk_element_pair(pair_pass *pass, int a, int b, const plait_material *ma,
                              const plait_material *mb, bool self)
{
	const element *ea = &pass->mc->elements[a], *eb = &pass->mc->elements[b];
	bool cull = pass->stage == STAGE_GATHER, failsafe = pass->stage == STAGE_FAILSAFE;
	const element_shape *shape[2] = {&pass->mc->shapes[a], &pass->mc->shapes[b]};
	vec3 x[2][3] = {{{0}}};
	if (cull) {
		const plait_particles *p = &pass->sim->particles;
		for (int k = 0; k < 3; ++k) {
			x[0][k] = p->point[ea->v[k]].x;
			x[1][k] = p->point[eb->v[k]].x;
		}
	}
	float gap = pass->list_distance;
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
			live_features(mc, collider == 0 ? a : b, collider == 0 ? b : a, &vertices, &edges);
			own_vertices[collider] &= vertices;
			own_edges[collider] &= edges;
		}
		if (pass->stage == STAGE_GATHER) {
			int kept = bits3(own_vertices[collider]) + bits3(own_edges[collider]);
			pass->features_kept += kept;
			pass->features_left_out += all - kept;
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
			if (shared && !(turn == 0 && self_allows(ma, PAIR_VERTEX_VERTEX))) {
				continue;
			}
			bool far = cull && !shared && point_far(vx[k], other, os, ox, gap);
			if (other->size == 3 && (!self || self_allows(ma, PAIR_VERTEX_FACE)) &&
			    vertex_meets_face(mv, mo) && !far && !shared) {
				v[1] = other->v[0];
				v[2] = other->v[1];
				v[3] = other->v[2];
				visit_primitives(pass, PAIR_VERTEX_FACE, v, mv, mo, self);
			}
			if (other->size == 2 && vertex_side->size == 1 && !far && !shared) {
				v[1] = other->v[0];
				v[2] = other->v[1];
				visit_primitives(pass, PAIR_VERTEX_EDGE, v, mv, mo, self);
			}
			if (turn == 0 && self && !failsafe && self_allows(ma, PAIR_VERTEX_VERTEX) && !far) {
				for (int m = 0; m < other->size; ++m) {
					if ((other->own_vertices & (1u << m)) &&
					    !(cull && boxes_apart(vx[k], vx[k], ox[m], ox[m], gap))) {
						v[1] = other->v[m];
						visit_primitives(pass, PAIR_VERTEX_VERTEX, v, mv, mo, self);
					}
				}
			}
		}
	}
	if (ea->size >= 2 && eb->size >= 2 && (!self || self_allows(ma, PAIR_EDGE_EDGE))) {
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
				if (cull && segments_far(x[0][i], x[0][i1], x[1][j], x[1][j1], gap)) {
					continue;
				}
				v[0] = ea->v[i];
				v[1] = ea->v[i1];
				v[2] = eb->v[j];
				v[3] = eb->v[j1];
				visit_primitives(pass, PAIR_EDGE_EDGE, v, ma, mb, self);
			}
		}
	}
}

static void visit_elements(int a, int b, void *context)
{
	pair_pass *pass = context;
	const plait_mesh_contacts *mc = pass->mc;
	const element *ea = &mc->elements[a], *eb = &mc->elements[b];
	const plait_material *ma = &pass->sim->materials[ea->material];
	const plait_material *mb = &pass->sim->materials[eb->material];
	bool self = ma->object == mb->object;
	if (self && excluded(mc, a, b)) {
		return;
	}
	pass->all_rest = true;
	if (pass->stage == STAGE_GATHER) {
		/* One list distance for every primitive pair of the two elements, from their largest
		 * radii and guards: a little generous, and no lookups per primitive pair. */
		float scale = self ? ma->self_width_scale : 1.0f;
		pass->list_distance = LIST_SCALE * scale * (mc->element_reach[a] + mc->element_reach[b]) +
		                      mc->element_guard[a] + mc->element_guard[b] + 2.0f * FAILSAFE_DISTANCE;
		pass->pair_slack = mc->element_guard[a] + mc->element_guard[b];
		if (!self) {
			float allowance =
			    mc->allowance[mc->object_of[ea->v[0]] * mc->object_count + mc->object_of[eb->v[0]]];
			pass->list_distance += allowance;
			pass->pair_slack += allowance;
		}
	}
	walk_element_pair(pass, a, b, ma, mb, self);
	if (pass->stage == STAGE_REST && pass->all_rest && !pass->failed) {
		if (pass->excluded_count + 2 > pass->excluded_capacity) {
			int capacity = pass->excluded_capacity < 1024 ? 1024 : 2 * pass->excluded_capacity;
			int(*bigger)[2] = plait_alloc_zero(&pass->sim->allocator, (size_t)capacity, sizeof *bigger);
			if (bigger == NULL) {
				pass->failed = true;
				return;
			}
			if (pass->excluded_count > 0) {
				memcpy(bigger, pass->excluded, sizeof *bigger * (size_t)pass->excluded_count);
			}
			plait_free(&pass->sim->allocator, pass->excluded);
			pass->excluded = bigger;
			pass->excluded_capacity = capacity;
		}
		pass->excluded[pass->excluded_count][0] = a;
		pass->excluded[pass->excluded_count++][1] = b;
		pass->excluded[pass->excluded_count][0] = b;
		pass->excluded[pass->excluded_count++][1] = a;
	}
}

/* ---- Which of a collider's corners and edges need mesh contacts ---------------------------
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
 * (collision/smooth_reach.c) finds, per corner and edge, the largest such D: its smooth reach.
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
 * failsafe's traversal, as they end the substep (measure_cloth_edges). A deforming collider's
 * angles change from frame to frame, and between frames its triangles' normals are not bounded
 * by those at the frames: it keeps all its corners and edges. */

/* The share of the contact distance the argument leans on: the collider pass pushes vertices
 * out to all of it, friction and other colliders can take back some. */
#define SMOOTH_MARGIN 0.5f
/* A listing's bound on a cloth edge near a filtered collider: this many times its length now. */
#define CLOTH_EDGE_SLACK 1.1f
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
	          plait_mesh_smooth_reaches(shape, a, budget, range, vertex_reach, edge_reach);
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
static bool build_collider_features(plait_sim *sim, plait_mesh_contacts *mc, const plait_triangle_edge *edges,
                                    int edge_count)
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

/* The longest edge of each cloth triangle and curve segment that meets filtered colliders,
 * into mc->cloth_bound (grown by `slack`), and each one's D for its element pairs with them,
 * into mc->pair_reach: the largest bound over it and the triangles across its edges (an edge-edge
 * pair is owned by one of the two triangles of its cloth edge, and must hold for both). At a
 * listing the bound has slack, and the list covers only while no edge outgrows it
 * (list_covers); the failsafe's traversal measures the substep's end, with none. */
static void measure_cloth_edges(const plait_sim *sim, plait_mesh_contacts *mc, float slack)
{
	const plait_particles *p = &sim->particles;
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		if (!meets_collider_surfaces(sim, mc, o)) {
			continue;
		}
		for (int e = o->first; e < o->first + o->count; ++e) {
			const element *el = &mc->elements[e];
			mc->pair_reach[e] = slack * sqrtf(longest_edge_sq(p, el));
		}
		if (slack > 1.0f) {
			for (int e = o->first; e < o->first + o->count; ++e) {
				mc->cloth_bound[e] = mc->pair_reach[e];
			}
		}
		/* The neighbours' bounds, read from cloth_bound (at a listing) or from a second pass. */
		const float *bound = slack > 1.0f ? mc->cloth_bound : mc->pair_reach;
		for (int e = o->first; e < o->first + o->count; ++e) {
			float reach = bound[e];
			for (int q = 0; q < 3; ++q) {
				int n = mc->neighbours[e][q];
				reach = n >= 0 ? plait_maxf(reach, bound[n]) : reach;
			}
			mc->cloth_bound_scratch[e] = reach;
		}
		for (int e = o->first; e < o->first + o->count; ++e) {
			mc->pair_reach[e] = mc->cloth_bound_scratch[e];
		}
	}
}

/* Whether every cloth edge that meets filtered colliders is still within its bound. */
static bool cloth_edges_within_bounds(const plait_sim *sim, const plait_mesh_contacts *mc)
{
	const plait_particles *p = &sim->particles;
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		if (!meets_collider_surfaces(sim, mc, o)) {
			continue;
		}
		for (int e = o->first; e < o->first + o->count; ++e) {
			const element *el = &mc->elements[e];
			if (longest_edge_sq(p, el) > mc->cloth_bound[e] * mc->cloth_bound[e]) {
				return false;
			}
		}
	}
	return true;
}

/* Which corners and edges of a filtered collider's element c meet cloth element e here: bits of
 * its own vertices and edges whose smooth reach the cloth's D (pair_reach) does not stay under. */
static void live_features(const plait_mesh_contacts *mc, int c, int e, uint8_t *vertices, uint8_t *edges)
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

/* Element boxes. For the gather: around the current positions, grown by LIST_SCALE times the
 * element's reach plus its largest guard (a pair within its list distance has overlapping
 * boxes). For the failsafe: around the paths of the substep, grown by `margin`. */
static void fit_boxes(plait_sim *sim, plait_mesh_contacts *mc, bool paths, float margin)
{
	const plait_particles *p = &sim->particles;
	for (int e = 0; e < mc->element_count; ++e) {
		const element *el = &mc->elements[e];
		vec3 lower = p->point[el->v[0]].x, upper = lower;
		float radius = 0.0f, guard = 0.0f;
		for (int k = 0; k < el->size; ++k) {
			int i = el->v[k];
			lower = v3_min(lower, p->point[i].x);
			upper = v3_max(upper, p->point[i].x);
			if (paths) {
				lower = v3_min(lower, p->x_prev[i]);
				upper = v3_max(upper, p->x_prev[i]);
			}
			radius = plait_maxf(radius, p->radius[i]);
			guard = plait_maxf(guard, mc->guard[i]);
		}
		float g = margin;
		if (!paths) {
			element_shape *shape = &mc->shapes[e];
			shape->lower = lower;
			shape->upper = upper;
			vec3 c = p->point[el->v[0]].x;
			for (int k = 1; k < el->size; ++k) {
				c = v3_add(c, p->point[el->v[k]].x);
			}
			shape->centre = v3_scale(c, 1.0f / (float)el->size);
			if (el->size == 3) {
				vec3 t[3] = {p->point[el->v[0]].x, p->point[el->v[1]].x, p->point[el->v[2]].x};
				shape->normal = plait_triangle_normal(t);
			}
			const plait_material *m = &sim->materials[el->material];
			float reach = radius * (m->self_collide ? plait_maxf(1.0f, m->self_width_scale) : 1.0f);
			g += LIST_SCALE * reach + guard + FAILSAFE_DISTANCE;
			mc->element_reach[e] = radius;
			mc->element_guard[e] = guard;
		}
		mc->lower[e] = v3_sub(lower, v3(g, g, g));
		mc->upper[e] = v3_add(upper, v3(g, g, g));
	}
	if (mc->features != NULL) {
		measure_cloth_edges(sim, mc, paths ? 1.0f : CLOTH_EDGE_SLACK);
	}
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		plait_element_tree_refit(&o->tree, mc->lower + o->first, mc->upper + o->first);
	}
}

/* Element pairs of two objects (or of one with itself), in global element numbers. */
typedef struct object_pass {
	pair_pass *pass;
	int first_a, first_b;
} object_pass;

static void visit_object_elements(int a, int b, void *context)
{
	const object_pass *o = context;
	visit_elements(o->first_a + a, o->first_b + b, o->pass);
}

/* Whether objects a < b meet in mesh contacts. */
static bool objects_meet(const plait_sim *sim, const plait_mesh_contacts *mc, int a, int b)
{
	const collision_object *oa = &mc->objects[a], *ob = &mc->objects[b];
	if (!sim->settings.cloth_contacts) {
		return false;
	}
	bool points_a = mc->elements[oa->first].size == 1, points_b = mc->elements[ob->first].size == 1;
	if (points_a && points_b) {
		return false; /* particle pairs (contact.c) */
	}
	const plait_material *ma = &sim->materials[oa->material], *mb = &sim->materials[ob->material];
	bool collider_a = ma->type == PLAIT_OBJECT_COLLIDER, collider_b = mb->type == PLAIT_OBJECT_COLLIDER;
	/* Colliders' surfaces (plait_collider.first) never push each other, nor cloth that meets
	 * colliders with its vertices only (contact.c does that). */
	return !((collider_a && collider_b) || (collider_a && mb->collider_flag == PLAIT_COLLIDE_VERTEX) ||
	         (collider_b && ma->collider_flag == PLAIT_COLLIDE_VERTEX));
}

/* How far two objects' boxes reach across at a listing: their allowance. */
static float listing_margin(const plait_mesh_contacts *mc, const pair_pass *pass, int a, int b)
{
	return pass->stage == STAGE_GATHER ? mc->allowance[a * mc->object_count + b] : 0.0f;
}

/* Every pair of elements that may touch: each self-colliding object with itself, then each
 * pair of objects that collide with each other. */
static void traverse_objects(plait_mesh_contacts *mc, pair_pass *pass)
{
	const plait_sim *sim = pass->sim;
	for (int a = 0; a < mc->object_count; ++a) {
		const collision_object *oa = &mc->objects[a];
		vec3 *la = mc->lower + oa->first, *ua = mc->upper + oa->first;
		object_pass self = {pass, oa->first, oa->first};
		if (oa->self) {
			plait_element_tree_pairs(&oa->tree, la, ua, visit_object_elements, &self);
		}
		for (int b = a + 1; b < mc->object_count; ++b) {
			if (!objects_meet(sim, mc, a, b)) {
				continue;
			}
			const collision_object *ob = &mc->objects[b];
			object_pass between = {pass, oa->first, ob->first};
			plait_element_tree_pairs_between(&oa->tree, la, ua, &ob->tree, mc->lower + ob->first,
			                                 mc->upper + ob->first, listing_margin(mc, pass, a, b),
			                                 visit_object_elements, &between);
		}
	}
}

/* ---- Listing on the workers -------------------------------------------------------------
 * The traversals of traverse_objects, cut into pieces (node pairs a few splits down), list
 * side by side, each into a list of its own, and the lists are joined in piece order: the
 * list is the one traverse_objects makes, pair for pair, whatever the number of workers. A
 * worker may not call the allocator (its hooks need not be thread-safe): each piece's list is
 * given room first, and a piece that runs out of it is listed again on the calling thread. */

typedef struct piece_job {
	plait_sim *sim;
	plait_mesh_contacts *mc;
} piece_job;

static void list_piece(plait_mesh_contacts *mc, pair_pass *pass, const gather_piece *piece)
{
	const collision_object *oa = &mc->objects[piece->a], *ob = &mc->objects[piece->b];
	bool self = piece->a == piece->b;
	object_pass o = {pass, oa->first, ob->first};
	plait_element_tree_piece_pairs(&oa->tree, mc->lower + oa->first, mc->upper + oa->first, &ob->tree,
	                               mc->lower + ob->first, mc->upper + ob->first, self,
	                               self ? 0.0f : listing_margin(mc, pass, piece->a, piece->b), piece->node,
	                               visit_object_elements, &o);
}

static void list_pieces(void *context, int begin, int end)
{
	piece_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	for (int k = begin; k < end; ++k) {
		piece_list *list = &mc->piece_lists[k];
		list->count = 0;
		pair_pass pass = {.sim = job->sim,
		                  .mc = mc,
		                  .stage = STAGE_GATHER,
		                  .out_pairs = &list->pairs,
		                  .out_count = &list->count,
		                  .out_capacity = &list->capacity,
		                  .fixed_capacity = true};
		list_piece(mc, &pass, &mc->pieces[k]);
		list->full = pass.full;
		list->features_kept = pass.features_kept;
		list->features_left_out = pass.features_left_out;
	}
}

/* Cuts the traversals of stage `of` into mc->pieces (piece_count 0 when they do not fit); returns
 * whether the cut is the one before, which had last_count pieces. */
static bool cut_pieces(const plait_sim *sim, plait_mesh_contacts *mc, stage of, int last_count)
{
	int(*nodes)[2] = mc->piece_nodes;
	int count = 0;
	bool fits = true, same = true;
	for (int a = 0; a < mc->object_count && fits; ++a) {
		for (int b = a; b < mc->object_count && fits; ++b) {
			const collision_object *oa = &mc->objects[a], *ob = &mc->objects[b];
			if ((a == b && !oa->self) || (a != b && !objects_meet(sim, mc, a, b))) {
				continue;
			}
			pair_pass margin_pass = {.stage = of};
			int n = plait_element_tree_split(&oa->tree, &ob->tree, a == b,
			                                 a == b ? 0.0f : listing_margin(mc, &margin_pass, a, b),
			                                 PIECE_DEPTH, nodes, MAX_PIECES - count);
			fits = n >= 0;
			for (int k = 0; k < n; ++k) {
				gather_piece piece = {a, b, {nodes[k][0], nodes[k][1]}};
				const gather_piece *was = &mc->pieces[count];
				same = same && count < last_count && was->a == a && was->b == b &&
				       was->node[0] == piece.node[0] && was->node[1] == piece.node[1];
				mc->pieces[count++] = piece;
			}
		}
	}
	mc->piece_count = fits ? count : 0;
	return fits && same && count == last_count;
}

/* The gather's traversal on the workers, into mc's list; false (nothing listed) when it cannot
 * run there (out of memory, too many pieces): the caller then traverses on its own. */
static bool gather_on_workers(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass)
{
	const plait_allocator *a = &sim->allocator;
	if (!reserve_pieces(mc, a)) {
		return false;
	}
	/* The first listing, with nothing to size the pieces' lists by, runs on the calling thread
	 * (most pieces would fill their room and be listed twice); so does a listing much longer
	 * than the traversal that makes it (pile: about 50 pairs an element, against 8 in
	 * hang-self), where joining the pieces' lists costs more than a worker saves. */
	if (mc->last_listed == 0 || mc->last_listed > 16 * mc->element_count) {
		return false;
	}
	int last_count = mc->piece_count;
	bool same_cut = cut_pieces(sim, mc, STAGE_GATHER, last_count);
	if (mc->piece_count == 0) {
		return false;
	}
	/* Room for each piece: half as much again as it listed last time when the cut is the same
	 * (a tree's node pairs change little from one listing to the next), else twice its share
	 * of the last listing. */
	for (int k = 0; k < mc->piece_count; ++k) {
		piece_list *list = &mc->piece_lists[k];
		int room = same_cut ? 64 + list->count + list->count / 2 : 64 + 2 * mc->last_listed / mc->piece_count;
		if (list->capacity < room) {
			contact_pair *bigger = plait_alloc_zero(a, (size_t)room, sizeof *bigger);
			if (bigger == NULL) {
				return false;
			}
			plait_free(a, list->pairs);
			list->pairs = bigger;
			list->capacity = room;
		}
	}
	piece_job job = {sim, mc};
	plait_parallel_for(&sim->parallel, list_pieces, &job, 0, mc->piece_count, 1);
	int total = 0;
	for (int k = 0; k < mc->piece_count; ++k) {
		piece_list *list = &mc->piece_lists[k];
		if (list->full) {
			/* Again here, where its list may grow. */
			list->count = 0;
			pair_pass again = {.sim = sim,
			                   .mc = mc,
			                   .stage = STAGE_GATHER,
			                   .out_pairs = &list->pairs,
			                   .out_count = &list->count,
			                   .out_capacity = &list->capacity};
			list_piece(mc, &again, &mc->pieces[k]);
			list->features_kept = again.features_kept;
			list->features_left_out = again.features_left_out;
		}
		pass->features_kept += list->features_kept;
		pass->features_left_out += list->features_left_out;
		total += list->count;
	}
	if (total > mc->pair_capacity) {
		contact_pair *bigger = plait_alloc_zero(a, (size_t)total, sizeof *bigger);
		if (bigger == NULL) {
			mc->out_of_memory = true;
			return true;
		}
		plait_free(a, mc->pairs);
		mc->pairs = bigger;
		mc->pair_capacity = total;
	}
	mc->pair_count = 0;
	for (int k = 0; k < mc->piece_count; ++k) {
		const piece_list *list = &mc->piece_lists[k];
		if (list->count > 0) {
			memcpy(mc->pairs + mc->pair_count, list->pairs, sizeof *list->pairs * (size_t)list->count);
			mc->pair_count += list->count;
		}
	}
	return true;
}

/* The mean motion of each collision object from the gather positions to `x` (a particle
 * array: positions now, or at the substep's start), into mc->shift. */
static void object_shifts(const plait_sim *sim, plait_mesh_contacts *mc, const vec3 *x_prev, bool at_start)
{
	const plait_particles *p = &sim->particles;
	for (int k = 0; k < mc->object_count; ++k) {
		mc->shift[k] = v3(0.0f, 0.0f, 0.0f);
	}
	int *counts = mc->object_counts;
	for (int k = 0; k < mc->object_count; ++k) {
		counts[k] = 0;
	}
	for (int i = 0; i < p->count; ++i) {
		int o = mc->object_of[i];
		if (o >= 0) {
			vec3 x = at_start ? x_prev[i] : p->point[i].x;
			mc->shift[o] = v3_add(mc->shift[o], v3_sub(x, mc->x_gather[i]));
			counts[o] += 1;
		}
	}
	for (int k = 0; k < mc->object_count; ++k) {
		mc->shift[k] = v3_scale(mc->shift[k], 1.0f / (float)(counts[k] > 0 ? counts[k] : 1));
	}
}

static int compare_int_pairs(const void *a, const void *b)
{
	const int *x = a, *y = b;
	if (x[0] != y[0]) {
		return x[0] < y[0] ? -1 : 1;
	}
	return x[1] < y[1] ? -1 : x[1] > y[1];
}

/* The rest pairs and the excluded element pairs of every self-colliding object, from the start
 * positions: element boxes grown so that primitives within their contact distance at the
 * start overlap. */
static bool build_rest_pairs(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_allocator *a = &sim->allocator;
	const plait_particles *p = &sim->particles;
	pair_pass pass = {.sim = sim, .mc = mc, .stage = STAGE_REST};
	for (int k = 0; k < mc->object_count && !pass.failed; ++k) {
		collision_object *o = &mc->objects[k];
		if (!o->self) {
			continue;
		}
		const plait_material *m = &sim->materials[o->material];
		for (int e = o->first; e < o->first + o->count; ++e) {
			const element *el = &mc->elements[e];
			vec3 lower = p->x_start[el->v[0]], upper = lower;
			float radius = 0.0f;
			for (int q = 0; q < el->size; ++q) {
				lower = v3_min(lower, p->x_start[el->v[q]]);
				upper = v3_max(upper, p->x_start[el->v[q]]);
				radius = plait_maxf(radius, p->radius[el->v[q]]);
			}
			float g = radius * m->self_width_scale;
			mc->lower[e] = v3_sub(lower, v3(g, g, g));
			mc->upper[e] = v3_add(upper, v3(g, g, g));
		}
		plait_element_tree_refit(&o->tree, mc->lower + o->first, mc->upper + o->first);
		object_pass self = {&pass, o->first, o->first};
		plait_element_tree_pairs(&o->tree, mc->lower + o->first, mc->upper + o->first, visit_object_elements,
		                         &self);
	}
	mc->excluded_start = plait_alloc_zero(a, (size_t)mc->element_count + 1, sizeof(int));
	mc->excluded_list =
	    plait_alloc_zero(a, (size_t)(pass.excluded_count > 0 ? pass.excluded_count : 1), sizeof(int));
	bool ok = !pass.failed && mc->excluded_start != NULL && mc->excluded_list != NULL;
	if (ok && pass.excluded_count > 0) {
		qsort(pass.excluded, (size_t)pass.excluded_count, sizeof *pass.excluded, compare_int_pairs);
		for (int k = 0; k < pass.excluded_count; ++k) {
			mc->excluded_start[pass.excluded[k][0] + 1] += 1;
			mc->excluded_list[k] = pass.excluded[k][1];
		}
		for (int e = 0; e < mc->element_count; ++e) {
			mc->excluded_start[e + 1] += mc->excluded_start[e];
		}
	}
	plait_free(a, pass.excluded);
	return ok;
}

/* Each vertex's guard: how far it may move, relative to its object as a whole, before the list
 * must be gathered again: its relative motion of this substep so far (so the substep's start
 * is covered), a tenth of its radius (contact pushes) and a tenth of a millimetre in metres.
 * Each pair of objects likewise may move relative to each other by their relative motion of
 * the substep so far plus a tenth of a millimetre. Relative motion is what brings primitives
 * together: a cloth falling fast keeps its list. */
static void gather(plait_sim *sim, plait_mesh_contacts *mc)
{
	mc->pair_count = 0;
	mc->out_of_memory = false;
	const plait_particles *p = &sim->particles;
	for (int i = 0; i < p->count; ++i) {
		mc->x_gather[i] = p->point[i].x;
	}
	object_shifts(sim, mc, p->x_prev, true); /* minus the motion of the substep so far */
	for (int i = 0; i < p->count; ++i) {
		int o = mc->object_of[i];
		vec3 motion = v3_sub(p->x_prev[i], p->point[i].x);
		float relative = o >= 0 ? v3_length(v3_sub(motion, mc->shift[o])) : v3_length(motion);
		mc->guard[i] = relative + 0.1f * p->radius[i] + 1e-4f;
	}
	mc->allowance_max = 0.0f;
	for (int a = 0; a < mc->object_count; ++a) {
		for (int b = 0; b < mc->object_count; ++b) {
			float allow = v3_length(v3_sub(mc->shift[a], mc->shift[b])) + 1e-4f;
			mc->allowance[a * mc->object_count + b] = allow;
			mc->allowance_max = plait_maxf(mc->allowance_max, allow);
		}
	}
	fit_boxes(sim, mc, false, 0.0f);
	pair_pass pass = {.sim = sim,
	                  .mc = mc,
	                  .stage = STAGE_GATHER,
	                  .out_pairs = &mc->pairs,
	                  .out_count = &mc->pair_count,
	                  .out_capacity = &mc->pair_capacity};
	if (!(sim->parallel.worker_count > 1 && gather_on_workers(sim, mc, &pass))) {
		traverse_objects(mc, &pass);
	}
	mc->last_listed = mc->pair_count;
	mc->features_kept = pass.features_kept;
	mc->features_left_out = pass.features_left_out;
	mc->list_valid = !mc->out_of_memory;
}

/* Whether the list still holds every pair that can touch or cross. True while, at the
 * substep's start (with `with_start`) and now, every vertex is within its guard of where it
 * was at the gather once its object's mean motion is taken out, and every pair of objects is
 * within its allowance of where it was relative to the other. A pair not listed was then
 * farther apart than LIST_SCALE times its contact distance plus its guards (and allowance),
 * and distances do not change when things move together, so over any path between such
 * positions it stays farther than LIST_SCALE times its contact distance. */
static bool list_covers(const plait_sim *sim, plait_mesh_contacts *mc, bool with_start)
{
	if (!mc->list_valid) {
		return false;
	}
	if (mc->features != NULL && !cloth_edges_within_bounds(sim, mc)) {
		return false; /* D of the colliders' corners and edges left out no longer holds */
	}
	const plait_particles *p = &sim->particles;
	for (int when = with_start ? 0 : 1; when < 2; ++when) {
		object_shifts(sim, mc, p->x_prev, when == 0);
		for (int a = 0; a < mc->object_count; ++a) {
			for (int b = a + 1; b < mc->object_count; ++b) {
				if (v3_length(v3_sub(mc->shift[a], mc->shift[b])) > mc->allowance[a * mc->object_count + b]) {
					return false;
				}
			}
		}
		for (int i = 0; i < p->count; ++i) {
			int o = mc->object_of[i];
			if (o < 0) {
				continue;
			}
			vec3 x = when == 0 ? p->x_prev[i] : p->point[i].x;
			vec3 relative = v3_sub(v3_sub(x, mc->x_gather[i]), mc->shift[o]);
			if (v3_length_sq(relative) > mc->guard[i] * mc->guard[i]) {
				return false;
			}
		}
	}
	return true;
}

/* ---- Contacts ---------------------------------------------------------------------------- */

/* Moves the pair's vertices so that C = (separation along n) - distance becomes 0: the vertices
 * move along n by their inverse mass times their weight g (the constraint's gradient), and
 * friction removes relative tangential motion of the substep within friction times the push. */
static bool respond(plait_sim *sim, const contact_pair *pair, const float *g, vec3 n, float c)
{
	plait_particles *p = &sim->particles;
	int count = pair_size[pair->type];
	int first_count = pair->type == PAIR_EDGE_EDGE ? 2 : 1;
	float w[4];
	bool any_free = false;
	for (int k = 0; k < count; ++k) {
		int i = pair->v[k];
		float scale = pair->scale[k < first_count ? 0 : 1];
		w[k] = p->point[i].w * scale;
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
		return false;
	}
	vec3 relative = {0.0f, 0.0f, 0.0f};
	for (int k = 0; k < count; ++k) {
		int i = pair->v[k];
		relative = v3_mul_add(relative, g[k], v3_sub(p->point[i].x, p->x_prev[i]));
	}
	float depth = -c;
	vec3 move = v3_scale(n, depth);
	vec3 tangential = v3_mul_add(relative, -v3_dot(relative, n), n);
	float tangential_length = v3_length(tangential);
	if (tangential_length > 0.0f && pair->friction > 0.0f) {
		float limit = pair->friction * depth;
		float removed = tangential_length < limit ? 1.0f : limit / tangential_length;
		move = v3_mul_add(move, -removed, tangential);
	}
	vec3 step = v3_scale(move, 1.0f / denominator);
	for (int k = 0; k < count; ++k) {
		int i = pair->v[k];
		p->point[i].x = v3_mul_add(p->point[i].x, w[k] * g[k], step);
	}
	return true;
}

static int project_pair(plait_sim *sim, contact_pair *pair)
{
	plait_particles *p = &sim->particles;
	int type = pair->type, n = pair_size[type];
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
		if (region != 0 && reach >= pair->distance && along >= 0.0f) {
			return 0; /* beside the triangle, out of reach, on its side */
		}
		bool crossed = false;
		if (along < 0.0f) {
			/* On the other side of the plane: through the triangle, or round it? */
			vec3 start[4];
			gather_points(p->x_prev, pair->v, n, start);
			crossed = paths_meet(type, start, x, 0.0f);
			if (crossed) {
				sim->ccd_hits += 1;
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
		if (separation >= pair->distance) {
			return 0;
		}
		g[0] = 1.0f;
		g[1] = -weights[0];
		g[2] = -weights[1];
		g[3] = -weights[2];
	} else {
		vec3 first, second;
		float s = 0.0f, t = 0.0f;
		if (type == PAIR_EDGE_EDGE) {
			plait_closest_segments(x[0], x[1], x[2], x[3], &s, &t);
			first = v3_lerp(x[0], x[1], s);
			second = v3_lerp(x[2], x[3], t);
		} else if (type == PAIR_VERTEX_EDGE) {
			t = plait_closest_on_segment(x[0], x[1], x[2]);
			first = x[0];
			second = v3_lerp(x[1], x[2], t);
		} else {
			first = x[0];
			second = x[1];
		}
		vec3 r = v3_sub(first, second);
		float length = v3_length(r);
		if (length >= pair->distance && v3_dot(r, pair->direction) >= 0.0f) {
			return 0;
		}
		bool crossed = false;
		if (v3_dot(r, pair->direction) < 0.0f) {
			vec3 start[4];
			gather_points(p->x_prev, pair->v, n, start);
			crossed = paths_meet(type, start, x, 0.0f);
			sim->ccd_hits += crossed;
		}
		if (crossed) {
			normal = pair->direction;
			separation = v3_dot(r, normal);
		} else {
			normal = length > 1e-9f ? v3_scale(r, 1.0f / length) : pair->direction;
			separation = length;
			pair->direction = normal;
		}
		if (separation >= pair->distance) {
			return 0;
		}
		if (type == PAIR_EDGE_EDGE) {
			g[0] = 1.0f - s;
			g[1] = s;
			g[2] = -(1.0f - t);
			g[3] = -t;
		} else if (type == PAIR_VERTEX_EDGE) {
			g[0] = 1.0f;
			g[1] = -(1.0f - t);
			g[2] = -t;
		} else {
			g[0] = 1.0f;
			g[1] = -1.0f;
		}
	}
	return respond(sim, pair, g, normal, separation - pair->distance);
}

int plait_mesh_contacts_project(plait_sim *sim)
{
	plait_mesh_contacts *mc = sim->mesh_contacts;
	if (mc == NULL || !mc->active) {
		return 0;
	}
	if (!mc->gathered) {
		if (!list_covers(sim, mc, true)) {
			gather(sim, mc);
		}
		mc->gathered = true;
	}
	int contacts = 0;
	for (int k = 0; k < mc->pair_count; ++k) {
		if (mc->pairs[k].distance > 0.0f) {
			contacts += project_pair(sim, &mc->pairs[k]);
		}
	}
	return contacts;
}

/* ---- Failsafe: impact zones -------------------------------------------------------------- */

static int zone_root(int *parent, int i)
{
	while (parent[i] != i) {
		parent[i] = parent[parent[i]];
		i = parent[i];
	}
	return i;
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

/* Sweeps every pair from the start of the substep to now; returns the crossing pairs found
 * and leaves them merged into zones. */
/* The rest pairs, each swept unless a lower bound of its distance at the substep's start, less
 * what its motion (relative to its first vertex) can take off, still keeps it apart. The bound
 * is carried from substep to substep, and known exactly again whenever the pair is swept. */
static void sweep_rest_pairs(pair_pass *pass)
{
	plait_mesh_contacts *mc = pass->mc;
	const plait_particles *p = &pass->sim->particles;
	for (int k = 0; k < mc->rest_count; ++k) {
		contact_pair *pair = &mc->rest_pairs[k];
		int n = pair_size[pair->type];
		vec3 start[4] = {{0}}, end[4] = {{0}};
		gather_points(p->x_prev, pair->v, n, start);
		gather_current(p->point, pair->v, n, end);
		float motion = largest_motion(pair->type, start, end);
		if (pair->lower - motion > pass->failsafe_distance) {
			pair->lower -= motion;
			continue;
		}
		pair->lower = primitive_distance(pair->type, end);
		float d0 = primitive_distance(pair->type, start);
		if (0.5f * (d0 + pair->lower - motion) > pass->failsafe_distance) {
			continue;
		}
		if (paths_meet(pair->type, start, end, pass->failsafe_distance)) {
			pass->hits += 1;
			join_zone(mc, pair->v, n);
		}
	}
}

static void forget_rest_bounds(plait_mesh_contacts *mc)
{
	for (int k = 0; k < mc->rest_count; ++k) {
		mc->rest_pairs[k].lower = -1.0f;
	}
}

/* The listed pairs [begin, end) that may have come within the distance, swept. */
static void sweep_listed(plait_mesh_contacts *mc, pair_pass *pass, int begin, int end)
{
	for (int k = begin; k < end; ++k) {
		if (mc->pairs[k].lower <= pass->failsafe_distance) {
			sweep_pair(pass, mc->pairs[k].type, mc->pairs[k].v);
		}
	}
}

typedef struct sweep_job {
	plait_sim *sim;
	plait_mesh_contacts *mc;
	float distance;
	bool from_list;
	int chunk; /* from_list: listed pairs a piece */
} sweep_job;

/* Piece k of a sweep: listed pairs [k chunk, (k + 1) chunk), or piece k of the traversal. */
static void sweep_piece(const sweep_job *job, pair_pass *pass, int k)
{
	plait_mesh_contacts *mc = job->mc;
	if (job->from_list) {
		int begin = k * job->chunk,
		    end = begin + job->chunk < mc->pair_count ? begin + job->chunk : mc->pair_count;
		sweep_listed(mc, pass, begin, end);
	} else {
		list_piece(mc, pass, &mc->pieces[k]);
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

/* The failsafe's sweep of the listed pairs (from_list) or its traversal, on the workers: each
 * piece keeps its crossings, which then join their impact zones here in piece order, the order
 * one thread meets them in (a piece that found too many is swept again here). Adds to pass's
 * hits and swept counts; false (nothing swept) when it cannot run there. */
static bool sweep_on_workers(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass, bool from_list)
{
	if (!reserve_pieces(mc, &sim->allocator)) {
		return false;
	}
	sweep_job job = {sim, mc, pass->failsafe_distance, from_list, 0};
	int pieces;
	if (from_list) {
		job.chunk = 4096;
		if (mc->pair_count > job.chunk * MAX_PIECES) {
			job.chunk = (mc->pair_count + MAX_PIECES - 1) / MAX_PIECES;
		}
		pieces = (mc->pair_count + job.chunk - 1) / job.chunk;
	} else {
		/* The traversal's boxes are fitted to the paths: a cut of its own. */
		(void)cut_pieces(sim, mc, STAGE_FAILSAFE, 0);
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

static int find_crossings(plait_sim *sim, plait_mesh_contacts *mc, float distance, bool from_list)
{
	pair_pass pass = {.sim = sim, .mc = mc, .stage = STAGE_FAILSAFE, .failsafe_distance = distance};
	sweep_rest_pairs(&pass);
	if (from_list) {
		if (!(sim->parallel.worker_count > 1 && sweep_on_workers(sim, mc, &pass, true))) {
			sweep_listed(mc, &pass, 0, mc->pair_count);
		}
		return pass.hits;
	}
	fit_boxes(sim, mc, true, distance);
	int before = pass.swept;
	if (!(sim->parallel.worker_count > 1 && sweep_on_workers(sim, mc, &pass, false))) {
		traverse_objects(mc, &pass);
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
	 * pairs than their paths meet, and keep the traversal. */
	bool covers = list_covers(sim, mc, true);
	if (!covers && mc->pair_count <= mc->traversal_sweeps) {
		gather(sim, mc);
		covers = mc->list_valid;
	}
	for (int round = 0; round < ZONE_ROUNDS + FREEZE_ROUNDS; ++round) {
		int hits = find_crossings(sim, mc, distance, round == 0 && covers);
		if (hits == 0) {
			break;
		}
		forget_rest_bounds(mc); /* the zones move vertices after their pairs were measured */
		sim->ccd_hits += hits;
		/* Zone by zone: members sorted by root. */
		for (int k = 0; k < mc->touched_count; ++k) {
			int i = mc->touched[k];
			mc->members[k][0] = zone_root(mc->zone_parent, i);
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
				/* Still crossing: back to where the substep began, which was free. */
				for (int k = start; k < end; ++k) {
					int i = mc->members[k][1];
					if (p->point[i].w > 0.0f) {
						p->point[i].x = p->x_prev[i];
					}
				}
			}
			sim->failsafe += 1;
			start = end;
		}
		/* Colliders have the last word over the moved vertices too; the next round checks that
		 * this crossed nothing. */
		if (round < ZONE_ROUNDS) {
			sim->contacts += plait_collide_listed_with_colliders(sim, mc->touched, mc->touched_count);
		}
	}
	for (int k = 0; k < mc->touched_count; ++k) {
		mc->zone_parent[mc->touched[k]] = -1;
	}
	mc->touched_count = 0;
}
