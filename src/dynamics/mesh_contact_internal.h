/* The private parts of mesh contacts (mesh_contact.h), shared by the files of the stage:
 *   mesh_contact.c           the stage's life (prepare, begin a substep, destroy) and its
 *                            contacts: projection and response
 *   mesh_contact_elements.c  the collision elements and objects, rest pairs, particle scratch
 *   mesh_contact_geometry.c  distances and paths of primitive pairs
 *   mesh_contact_pairs.c     which primitive pairs exist: the walk of an element pair
 *   mesh_contact_features.c  which of a rigid collider's corners and edges need mesh contacts
 *   mesh_contact_listing.c   element boxes, the traversal of objects, the gather and its guards
 *   mesh_contact_pieces.c    the traversals cut into pieces, listed on the workers
 *   mesh_contact_failsafe.c  the end-of-substep failsafe: sweeps and impact zones
 *   mesh_contact_cross.c     cross patches: flat patches of a second tree, over the seams
 *   mesh_contact_untangle.c  states that begin tangled: crossings found, and undone
 * A function one of them lends the others is named plait_mesh_contacts_ and what it was called
 * when they were one file; the rest stay static where they are used. */
#ifndef PLAIT_DYNAMICS_MESH_CONTACT_INTERNAL_H
#define PLAIT_DYNAMICS_MESH_CONTACT_INTERNAL_H

#include "collision/element_tree.h"
#include "collision/flat_patches.h"
#include "dynamics/mesh_contact.h"
#include "topology/topology.h"

#include <stdatomic.h>

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
	/* A self-colliding cloth's patches that cannot touch themselves (refitted at each gather;
	 * node_count 0 when it has none), and per node whether the last gather passed over its
	 * pairs with itself (the failsafe checks those patches along the substep's paths), and
	 * the direction each such patch faced. */
	plait_flat_patches patches;
	uint8_t *culled; /* 1: passed over; 2: and found not flat along this substep's paths */
	vec3 *culled_axis;
	/* Its cross patches (mesh_contact_cross.c; cross_of NULL when it has none): a second tree
	 * over the same elements and its flat patches; per element the largest cross patch found
	 * flat at the last gather that holds it (-1: none, or none fitted); per cross node whether
	 * a gather passed over pairs in it (as culled), and the direction it faced. Whether the
	 * last gather fitted them, the element pairs they passed over then, and the gathers since
	 * they were last fitted. */
	plait_element_tree cross_tree;
	plait_flat_patches cross;
	int *cross_of;
	_Atomic uint8_t *cross_culled;
	vec3 *cross_axis;
	bool cross_fitted;
	long cross_skipped;
	int cross_idle;
	plait_triangle_normals *normals; /* scratch: its triangles' normals over the gather's paths */
	/* Per tree node, for traversals between a filtered collider and a cloth or curve (see
	 * plait_mesh_contacts_smooth_skip): the collider's least smooth reach of the corners and
	 * edges its elements own under the node; the cloth's largest D (pair_reach) under it. NULL
	 * when the object has no such part. */
	float *node_floor;
	float *node_ceiling;
} collision_object;

/* A rigid mesh collider's corners and edges (plait_collider.first). Each element's own vertices
 * and edges as built, and for each the longest cloth edge below which it is left out of mesh
 * contacts (smooth_reach): a corner or edge that smooth cannot reach between the vertices of so
 * short a triangle held out of the collider by the collider pass (contact.c). */
typedef struct collider_features {
	uint8_t vertices, edges; /* as built (element.own_vertices, own_edges) */
	float reach[6];          /* vertex k: reach[k]; edge k: reach[3 + k]; scene units */
} collider_features;

/* An element pair that owns rest pairs (plait_mesh_contacts.near_list), under its lower
 * element: the other, and the slots of its rest pairs as walked from the lower one. */
typedef struct near_element {
	int element;
	uint32_t rest_slots;
} near_element;

/* The primitive pairs an element pair (a, b) owns, numbered as the walk meets them:
 * a vertex of a (k) against b: k; a vertex of b (k) against a: 3 + k; vertex k of a against
 * vertex m of b: 6 + 3k + m; edge i of a against edge j of b: 15 + 3i + j. */
#define VERTEX_SLOT(turn, k) (3 * (turn) + (k))
#define VERTEX_VERTEX_SLOT(k, m) (6 + 3 * (k) + (m))
#define EDGE_EDGE_SLOT(i, j) (15 + 3 * (i) + (j))
#define ALL_REST_SLOTS 0xffffffffu

/* An element's box, centroid and normal at the gather, for its cheap rejections. */
typedef struct element_shape {
	vec3 lower, upper;
	vec3 centre;
	vec3 normal; /* triangles: unit normal (zero when degenerate) */
} element_shape;

/* A vertex on the wrong side of a triangle it crossed into (mesh_contact_untangle.c): pushed
 * to `side` of the triangle's plane (+1 along its winding's normal, -1 against), `distance`
 * beyond it. */
typedef struct tangle_push {
	int vertex;
	int target[3];
	float side;
	float distance;
} tangle_push;

typedef struct contact_pair {
	int v[4];
	uint8_t type;
	uint8_t self;
	/* Whether its two surfaces ask for bounce or stickiness (their means above 0), and
	 * whether it pushed in this substep: plait_mesh_contacts_restitute, at the substep's end,
	 * then sets its velocities, from `approach`, the relative normal velocity it had at the
	 * substep's start along its normal at its first push (scene units per second, < 0 when
	 * closing). */
	uint8_t restitutes;
	uint8_t pushed;
	uint8_t pushed_last;  /* pushed or rested at the last collision iteration: contact passes project it */
	uint8_t gives_way[2]; /* 0 for a primitive not pushed (lower collision layer), else 1 */
	uint8_t sums_substep; /* the substep push_sum and rubbed are of (mc->substep_serial's low bits) */
	float distance;       /* contact distance, scene units */
	float friction;
	float approach;
	float side;     /* vertex-face: which side of the triangle's plane the vertex is on (+1, -1) */
	vec3 direction; /* the others: unit vector from the second primitive to the first */
	/* Over the substep, in the pair's separation (scene units): what its pushes closed, and
	 * the relative tangential motion its friction took off in all, a vector. Coulomb's law over
	 * the substep: that stays within friction times all the pushes (mesh_contact.c, rub). */
	float push_sum;
	vec3 rubbed;
	float lower; /* rest pairs: a lower bound of their distance now, < 0 when unknown */
} contact_pair;

/* A rest pair (plait_mesh_contacts.rest_pairs): only swept, every substep, so kept small (a
 * large cloth holds millions). lower: a lower bound of its distance, carried from substep to
 * substep, < 0 when unknown. */
typedef struct rest_pair {
	int v[4];
	float lower;
	uint8_t type;
	uint8_t crossed; /* found crossing by a sweep on the workers, its zone not joined yet */
} rest_pair;

/* The rest pairs of one element pair, rest_pairs[first, first + count). While lower (a lower
 * bound of all their distances, < 0 when unknown), less what the two elements' motions over the
 * substep can take off (their spreads and the difference of their means), keeps them apart,
 * they are passed over whole, and what was taken off is kept in pending, for each pair's own
 * bound when they are swept again. */
typedef struct rest_group {
	int first, count;
	int a, b; /* the elements */
	float lower, pending;
} rest_group;

/* Listing on the workers (plait_mesh_contacts_gather_on_workers): a piece of a traversal, and its
 * own list. */
typedef struct gather_piece {
	int a, b;    /* collision objects (a == b: self) */
	int node[2]; /* the node pair in their trees */
} gather_piece;

typedef struct piece_list {
	contact_pair *pairs;
	int count, capacity;
	int needed; /* pairs it would have listed, had it room */
	int offset; /* where its pairs go in the joined list */
	bool full;
	int features_kept, features_left_out;
	long met; /* element pairs it met */
	long cross_skipped;
} piece_list;

/* A crossing found by a failsafe sweep on a worker, joined into its impact zone afterwards on
 * the calling thread, in the order the sweeps would have met it. */
typedef struct sweep_hit {
	int v[4];
	int n;
} sweep_hit;

#define HIT_ROOM 4 /* crossings a piece of a sweep keeps; one that finds more (rare) is swept again */

/* Slabs a long contact list's space is cut into, and the groups of its projection order: a
 * slab's own pairs each, pairs across each border between two slabs, the rest (see
 * mesh_contact_plan.c). */
#define PLAN_SLABS 16
/* Lists shorter than this keep the gather's order (a length, not a thread count: the order must
 * not depend on the threads). Shorter lists are mostly gathered again at every substep (a plan,
 * a pass or two over the list, then costs about what two threads save; on one thread it is
 * lost: hang-self --stiff, whose lists pass 16,384 pairs, was 4% slower so) or hold too few
 * pairs to share. */
#define PLAN_LEAST_PAIRS 65536
#define PLAN_GROUPS (PLAN_SLABS + PLAN_SLABS - 1 + 1)
/* The groups: one per slab, one per border between two slabs (even borders, then odd), then the
 * pairs reaching wider. The stages the workers take one after another: slabs, even borders, odd
 * borders (groups [plan_stage_start[k], plan_stage_start[k + 1])); the wide group last, on the
 * calling thread. */
#define PLAN_FIRST_EVEN PLAN_SLABS
#define PLAN_FIRST_ODD (PLAN_FIRST_EVEN + PLAN_SLABS / 2)
#define PLAN_WIDE_GROUP (PLAN_FIRST_ODD + (PLAN_SLABS - 1) / 2)
#define PLAN_STAGES 3
static const int plan_stage_start[PLAN_STAGES + 1] = {0, PLAN_FIRST_EVEN, PLAN_FIRST_ODD, PLAN_WIDE_GROUP};
#define SLAB_BINS 1024

/* Where the slabs lie: along an axis (0, 1, 2) from `low`, SLAB_BINS bins of 1 / per_bin each,
 * each bin to its slab (of `count`). */
typedef struct plan_slabs {
	int count; /* slabs, up to PLAN_SLABS */
	int axis;
	float low, per_bin;
	uint8_t bin_slab[SLAB_BINS];
} plan_slabs;

typedef struct plait_mesh_contacts {
	int element_count;
	element *elements;
	float *element_reach;  /* an element's largest radius (at the last listing) */
	float *element_guard;  /* an element's largest guard (at the last listing) */
	vec3 *element_motion;  /* the mean of its vertices' motions (at the last listing) */
	float *element_spread; /* how far its vertices' motions are from that mean */
	/* The same over the substep, start to end, for the rest pairs' sweep (failsafe scratch). */
	vec3 *element_substep_motion;
	float *element_substep_spread;
	element_shape *shapes; /* at the last listing */
	vec3 *lower, *upper;   /* element boxes */
	int object_count;
	collision_object *objects;
	/* Colliders' corners and edges left out where smooth (see
	 * plait_mesh_contacts_build_collider_features): per filtered collider element its features;
	 * per element of a cloth or curve that meets them its edge-connected neighbours (-1: none),
	 * its longest edge's bound while the list serves, and the D its element pairs with colliders
	 * are decided with. */
	collider_features *features;
	int (*neighbours)[3];
	float *cloth_bound, *cloth_bound_scratch, *pair_reach;
	int features_kept, features_left_out; /* at the last listing, over its element pairs */
	/* Neighbours in the start shape. Within a self-colliding object, primitives closer than
	 * their self-collision distance at the start (seed 000 §4.5) never push each other: that is
	 * left to the object's own constraints. They may still not pass through each other: they
	 * are the rest pairs, swept by the failsafe in every substep. Each element pair that owns a
	 * rest pair is noted once, under its lower element: a sorted run of near_list from
	 * near_start[e] to near_start[e + 1], with the slots of its rest pairs (rest_slot), or
	 * ALL_REST_SLOTS when every primitive pair it owns is a rest pair or shares a vertex (it is
	 * then excluded whole). The gather passes over rest slots before any distance. */
	int rest_count, rest_capacity;
	struct rest_pair *rest_pairs;
	int rest_group_count, rest_group_capacity;
	struct rest_group *rest_groups; /* the rest pairs of each element pair, swept as one */
	int *near_start;
	struct near_element *near_list;
	bool active;
	bool restitution; /* some object's surface asks for bounce or stickiness */
	/* States that begin tangled (mesh_contact_untangle.c): whether triangles are searched for
	 * crossings at the next substep's start, how many edge-triangle crossings the last search
	 * found, per particle whether it is a vertex of one (tangled: no contact pushes it, the
	 * failsafe does not sweep its pairs), and the pushes through that undo them. */
	bool tangle_check_due;
	bool was_tangled;       /* crossings were found and are not all undone yet */
	bool ever_tangled;      /* crossings were found since the stage had its particles */
	bool rebuild_untangled; /* all were undone: the stage is built again (rest pairs) */
	int tangle_count;
	uint8_t *tangled;
	struct tangle_push *tangle_pushes;
	int tangle_push_count, tangle_push_capacity;
	uint64_t *tangle_links; /* vertex pairs of crossings (mesh_contact_untangle.c, linked) */
	int tangle_link_capacity;
	/* Per particle (scratch of plait_mesh_contacts_restitute, zero between): the velocity
	 * changes its pairs ask of it, summed by its weight in each, and those weights. */
	vec3 *restitution_sum;
	float *restitution_weight;
	bool gathered;   /* the candidates of this substep are ready */
	bool list_valid; /* the list of the last gather may serve again (see plait_mesh_contacts_list_covers) */
	int pair_count, pair_capacity;
	/* The order a long list is kept in, for its projection on the workers (mesh_contact_plan.c).
	 * list_changes counts the lists made (gathers and mendings); plan_list is the one the plan
	 * was made or counted for (-1: none), plan_kept_list one whose first `planned` pairs a
	 * mending kept in the plan's order, with their groups (pair_group, per pair). group_start:
	 * where each group begins in the list (the pairs from group_start[PLAN_GROUPS] on are a
	 * mending's, projected last). The slabs were cut for gather plan_listing (of listings).
	 * Scratch: the spare list and groups of the plan's counting sort, its counts per chunk, and
	 * per particle its slab and whether it could move at the plan (vertex_moves). */
	long list_changes, plan_list, plan_kept_list, plan_listing;
	long plan_failed_list; /* a list whose plan found no memory (-1: none): projected in order */
	long plan_projections; /* projections on a plan (a count, for tests) */
	int planned;
	int group_start[PLAN_GROUPS + 1];
	plan_slabs slabs;
	int8_t *pair_group, *spare_group;
	contact_pair *spare_pairs;
	int (*plan_counts)[PLAN_GROUPS];
	int8_t *vertex_slab;
	uint8_t *vertex_moves;
	int plan_pair_capacity, plan_particle_capacity;
	contact_pair *pairs;
	bool out_of_memory;   /* the candidate list could not grow: a contact may be left to the failsafe */
	int traversal_sweeps; /* primitive pairs swept by the failsafe's last traversal (0 before it) */
	/* Listing on the workers (plait_mesh_contacts_gather_on_workers): the traversals' pieces, a
	 * list each, and the length of the last list (to size the pieces' lists). */
	int piece_count;
	gather_piece *pieces;
	int (*piece_nodes)[2]; /* scratch of plait_mesh_contacts_cut_pieces */
	piece_list *piece_lists;
	int last_listed;
	/* The failsafe's sweeps on the workers (sweep_on_workers): per piece, its crossings (room for
	 * HIT_ROOM), how many, the pairs it swept, and whether it ran out of room. */
	sweep_hit *piece_hits;
	int *piece_hit_count, *piece_swept;
	bool *piece_full;
	/* The re-listing around strayed vertices on the workers (plait_mesh_contacts_relist_on_workers):
	 * the flagged elements in order, cut into runs with a list each, and how many pairs the last
	 * one listed per flagged element (to size the lists). */
	int *around_elements;
	int around_count, around_capacity;
	piece_list *around_lists;
	float around_pairs_per_element;
	/* What listings cost, in element pairs met: the last gather's, and the last mending's per
	 * element around a strayed vertex (0 before the first). A list is mended only where that is
	 * expected to meet fewer than gathering it again (plait_mesh_contacts_mending_pays). */
	long gather_met;
	float mend_met_per_element;
	long listing_met; /* element pairs met by every gather and mending so far (a count, for tests) */
	/* The list holds every pair that can touch or cross as long as every vertex keeps within its
	 * guard of its path: the straight one it was on at the gather for LIST_SUBSTEPS substeps
	 * after the gather's, then at that path's end (path_end), for up to LIST_LIFE substeps
	 * (plait_mesh_contacts_gather, plait_mesh_contacts_list_covers). */
	vec3 *x_gather;
	vec3 *motion; /* per particle: its motion over the gather's substep, start to gather */
	/* per particle: the substep (counted from the gather's, as `since` in list_holds) where its
	 * path stops: it runs x_gather + s motion up to there and stays at its end after. */
	float *path_end;
	float *guard; /* per particle: how far it may stray from that path */
	/* The paths the flat patches were last fitted to, and for which traversal (STAGE_GATHER:
	 * the list's paths above, over the substeps it serves, without their guards: the failsafe
	 * checks each patch the gather passed over along the substep's own paths, sweep_end and
	 * sweep_motion per particle, which STAGE_FAILSAFE's traversal also culls by). cull_flat:
	 * whether traversals pass over flat patches' pairs with themselves (on unless a test
	 * compares). */
	plait_patch_paths patch_paths;
	int patches_fitted_for; /* a stage, or -1 */
	long culled_patches;    /* patches the gathers passed over (a count) */
	long unflattened;       /* of those, the ones the failsafe swept (a count) */
	bool cull_flat;
	/* Tests' switches (both on otherwise): whether gathers fit cross patches, and whether
	 * traversals pass over the objects' own flat patches (cull_flat off: neither). */
	bool cull_cross, cull_own;
	bool skip_smooth; /* traversals pass over smooth node pairs (plait_mesh_contacts_smooth_skip) */
	vec3 *sweep_end, *sweep_motion;
	/* Per particle (scratch of fit_boxes): the box of its path relative to its object's mean
	 * motion over the list's window, found once rather than once for each of its elements. */
	vec3 *path_lower, *path_upper;
	long substep_serial, gather_serial; /* substeps begun since the stage was made; the gather's */
	long listings;                      /* gathers since the stage was made */
	long carried_zones;                 /* zones the failsafe put back carried by a collider */
	int *object_of;                     /* per particle: its collision object, or -1 */
	vec3 *shift;                        /* per collision object: mean motion since the gather (scratch) */
	int *object_counts;                 /* per collision object: scratch of object_shifts */
	vec3 *allowance; /* per pair of objects: how far their boxes must reach across, along each axis */
	/* Substeps after its own that the list's paths run: LIST_SUBSTEPS (its window; past it the
	 * list serves on while its vertices rest at their paths' ends), or 0 when the last list's
	 * vertices left their paths before it could serve again (short_lists, serving only their
	 * own substep; see plait_mesh_contacts_gather). paths_kept: the last check of a list found
	 * every vertex but a few on its path. list_rests: every path stopped for good where the
	 * gather found its vertices or where they began its substep (the substep after the gather
	 * found them nearer there than their paths: resting cloth that jitters about its place;
	 * mesh_contact_listing.c, maybe_rest), so the list serves on as one past its window. */
	int list_serves;
	bool short_lists, paths_kept, list_rests;
	bool rest_asked; /* whether the list was asked to rest (once, in the substep after its gather) */
	/* Failsafe scratch: union-find over particles, and the particles it touched. */
	int particle_capacity;
	int *zone_parent;
	int *touched;
	int touched_count;
	/* Failsafe scratch: per particle, swept around (0 or 1; all 0 between sweeps); per element,
	 * whether it has such a vertex. */
	uint8_t *around;
	/* Per element: the node of a patch the gather passed over that kept flat along this
	 * substep's paths (its rest pairs cannot cross), or -1 (the failsafe's, round 0), found in
	 * substep element_flat_serial (-1: none, or zones have moved vertices since). around_flat:
	 * queries around flagged elements pass over pairs within one such patch (set while a
	 * resting list's mending queries: plait_mesh_contacts_relist_around). */
	int *element_flat;
	long element_flat_serial;
	bool around_flat;
	uint8_t *element_around;
	int (*members)[2]; /* (root, particle), sorted to walk zone by zone */
	/* Pairs of a list being gathered again or mended, whose substep state the new listing
	 * carries over (mesh_contact_carry.c); carried_next chains those with the same first vertex,
	 * from carry_head (per particle, -1 when none: all -1 between listings). */
	contact_pair *carried;
	int *carried_next;
	int carried_count, carried_capacity;
	int *carry_head;
} plait_mesh_contacts;

/* The failsafe keeps primitives this far apart, scene units: a thousandth of a millimetre in
 * metres, well above float rounding at the sizes of cloth and well below any thickness. */
#define FAILSAFE_DISTANCE 1e-6f

/* Pairs are listed within this many times their contact distance (plus their guards). */
#define LIST_SCALE 1.1f

/* A list serves the substep of its gather and this many after it. */
#define LIST_SUBSTEPS 1
/* Substeps after its gather that a list may serve at most, past its window too (resting lists,
 * list_holds): a bound on how stale what the list was made under may get, and on the rounding
 * of mended paths written back to the gather's substep. */
#define LIST_LIFE 64

/* A list whose vertices strayed from their paths, at most one in this many, is mended around
 * them (the failsafe sweeps around them); otherwise it is gathered again (or traversed). */
#define STRAY_SHARE 8

/* The root of i in a union-find forest (parent[i] == i at a root), halving the path on the way:
 * impact zones (mesh_contact_failsafe.c) and a cloth's pieces (mesh_contact_untangle.c). */
static inline int plait_mesh_contacts_root(int *parent, int i)
{
	while (parent[i] != i) {
		parent[i] = parent[parent[i]];
		i = parent[i];
	}
	return i;
}

/* Whether `strays` of `count` particles are few enough to mend (or sweep) around. */
static inline bool plait_mesh_contacts_few_strays(int strays, int count)
{
	return strays > 0 && strays <= count / STRAY_SHARE;
}

/* The rounding allowance of the cheap distance bounds (mesh_contact_geometry.c) and of the
 * element pair walk's rejections (mesh_contact_pairs.c), scene units. */
#define REJECT_SLACK 1e-5f

/* A listing's bound on a cloth edge near a filtered collider: this many times its length now. */
#define CLOTH_EDGE_SLACK 1.1f

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
	/* STAGE_GATHER when re-listing around strayed vertices (plait_mesh_contacts_relist_around):
	 * only primitive pairs with a vertex flagged in mc->around, with twice the guards. */
	bool around_only;
	float pair_slack; /* STAGE_GATHER: how far its primitives may come closer (guards, allowance) */
	/* STAGE_GATHER: the list distance of the element pair's primitive pairs that only the
	 * failsafe watches (those the self-collision flag does not push): they matter only where
	 * they may cross while the list serves. */
	float failsafe_reach;
	/* STAGE_REST: whether every primitive pair of the element pair met so far is a rest pair
	 * (or shares a vertex), and the slots of its rest pairs (slot: the one being visited);
	 * the element pairs that own rest pairs, for the near lists. STAGE_GATHER: the slots of
	 * the element pair's rest pairs, passed over. */
	bool all_rest;
	int slot;
	uint32_t rest_slots;
	int near_count, near_capacity;
	struct near_pair *near;
	bool failed;
	int swept; /* STAGE_FAILSAFE: primitive pairs swept */
	/* STAGE_GATHER: where the listed pairs go; with fixed_capacity (on a worker, where the
	 * allocator may not be called) a full list sets `full` instead of growing, and counts the
	 * pairs that found no room into `overflow`. */
	contact_pair **out_pairs;
	int *out_count, *out_capacity;
	bool fixed_capacity, full;
	int overflow;
	int features_kept, features_left_out; /* STAGE_GATHER: see plait_mesh_contacts */
	long met;                             /* element pairs met (visit_elements) */
	long cross_skipped;                   /* of those, passed over within a cross patch */
	/* STAGE_FAILSAFE on a worker: crossings go here (room for HIT_ROOM; `full` past it) instead
	 * of into the impact zones. */
	sweep_hit *hits_out;
	int hits_count;
} pair_pass;

/* An element pair that owns rest pairs, as found (the lower element first). */
typedef struct near_pair {
	int a, b;
	uint32_t rest_slots;
} near_pair;

/* Element pairs of two objects (or of one with itself), in global element numbers. */
typedef struct object_pass {
	pair_pass *pass;
	int first_a, first_b;
} object_pass;

/* A pair's points, from a particle array (x_prev, x_start) or from the current positions. */
static inline void gather_points(const vec3 *source, const int *v, int n, vec3 *out)
{
	for (int k = 0; k < n; ++k) {
		out[k] = source[v[k]];
	}
}

static inline void gather_current(const plait_point *point, const int *v, int n, vec3 *out)
{
	for (int k = 0; k < n; ++k) {
		out[k] = point[v[k]].x;
	}
}

/* mesh_contact_elements.c */

/* Frees the elements, their objects and trees, and all that is sized by them. */
void plait_mesh_contacts_free_elements(plait_mesh_contacts *mc, const plait_allocator *a);

/* The elements and objects of what collides, their trees, colliders' features and rest pairs;
 * mc->active when anything can meet here. False only when out of memory. */
bool plait_mesh_contacts_build_elements(plait_sim *sim, plait_mesh_contacts *mc);

/* The scratch sized by the particles (guards, gather positions, impact zones); false when out
 * of memory. */
bool plait_mesh_contacts_reserve_particles(plait_sim *sim, plait_mesh_contacts *mc);

/* mesh_contact_geometry.c: pair types and points as in contact_pair. */

/* The distance between the pair's primitives at points x. */
float plait_mesh_contacts_primitive_distance(int type, const vec3 *x);
/* A cheap lower bound of it (projection gaps, less a rounding allowance). */
float plait_mesh_contacts_distance_lower_bound(int type, const vec3 *x);
/* Whether the primitives, moving on straight lines from start to end, come within distance of
 * each other (conservative: never a miss). */
bool plait_mesh_contacts_paths_meet(int type, const vec3 *start, const vec3 *end, float distance);
/* How much the distance between the primitives can change from start to end. */
float plait_mesh_contacts_largest_motion(int type, const vec3 *start, const vec3 *end);
/* Whether a lower bound of their distance over the substep exceeds distance. */
bool plait_mesh_contacts_paths_apart(int type, const vec3 *start, const vec3 *end, float distance);

/* mesh_contact_pairs.c */

/* The element trees' callback for an object_pass: element pair (a, b) of its objects, visited
 * as its pair_pass's stage asks. */
void plait_mesh_contacts_visit_object_elements(int a, int b, void *context);

/* A self traversal's skip over flat patches (plait_mesh_contacts_culls_flat). */
typedef struct flat_skip {
	const plait_flat_patches *patches;
	const plait_patch_paths *paths;
	uint8_t *culled;   /* per node: set where skipped (the gather's), or NULL */
	vec3 *culled_axis; /* per node: the direction a skipped patch faced (with culled) */
} flat_skip;
bool plait_mesh_contacts_culls_flat(const plait_mesh_contacts *mc, const pair_pass *pass);
/* Fits a tree's flat patches to `paths`, subtree by subtree on the workers (the same cones as
 * all at once). */
void plait_mesh_contacts_fit_tree_patches(plait_sim *sim, plait_flat_patches *patches,
                                          const plait_element_tree *tree, const plait_patch_paths *paths);
/* Fits every object's flat patches to `paths` for the traversals of stage `of`. */
void plait_mesh_contacts_fit_patches(plait_sim *sim, plait_mesh_contacts *mc, const plait_patch_paths *paths,
                                     stage of);
bool plait_mesh_contacts_skip_flat(int node, void *context);
/* The skip of object o's pairs with itself in a traversal of `pass`'s stage (NULL: none), with
 * *flat its context. */
const plait_node_skip *plait_mesh_contacts_self_skip(const plait_mesh_contacts *mc, const collision_object *o,
                                                     const pair_pass *pass, flat_skip *flat,
                                                     plait_node_skip *skip);

/* mesh_contact_cross.c */

/* Builds object o's cross tree and patches from its triangles (particle indices, o's element
 * numbering) in the rest shape; false when out of memory (o then has none). */
bool plait_mesh_contacts_build_cross(plait_sim *sim, collision_object *o, const int (*triangles)[3]);
void plait_mesh_contacts_free_cross(collision_object *o, const plait_allocator *allocator);
/* Whether this gather should fit object o's cross patches (they passed over enough pairs at
 * the last gather that did), and the count of the pairs they passed over at this one, into
 * each object that fitted them (self pairs of one object at a time: the gather's whole count
 * goes to the one object that has them, several share it by their triangles). */
bool plait_mesh_contacts_cross_pays(collision_object *o);
void plait_mesh_contacts_count_cross(plait_mesh_contacts *mc, long skipped);
/* Fits object o's cross patches to the gather's paths, finds the largest flat ones (cross_of)
 * and clears their marks; with `fit` false, leaves it none for this gather. */
void plait_mesh_contacts_fit_cross(plait_sim *sim, collision_object *o, const plait_patch_paths *paths,
                                   bool fit);
/* Whether element pair (a, b) of o (o's numbering) lies in one flat cross patch of this gather:
 * then the patch is marked as passed over. */
bool plait_mesh_contacts_in_cross(collision_object *o, int a, int b);
/* Whether any cross patch is marked; the marked ones checked along `paths` (the substep's),
 * those that did not keep flat marked 2; their pairs with themselves swept (the elements'
 * boxes fitted around the substep's paths), returning how many were. */
bool plait_mesh_contacts_any_cross(const plait_mesh_contacts *mc);
void plait_mesh_contacts_check_cross(plait_sim *sim, plait_mesh_contacts *mc, const plait_patch_paths *paths);
int plait_mesh_contacts_sweep_cross(plait_mesh_contacts *mc, pair_pass *pass);

/* mesh_contact_features.c */

/* The smooth reaches of every rigid mesh collider's corners and edges, and the neighbours of the
 * cloth elements that meet them (edges: the triangles' sorted edges); false when out of memory. */
bool plait_mesh_contacts_build_collider_features(plait_sim *sim, plait_mesh_contacts *mc,
                                                 const plait_triangle_edge *edges, int edge_count);
/* Each cloth element's D against filtered colliders (mc->pair_reach); at a listing (slack > 1)
 * also their bounds (mc->cloth_bound). */
void plait_mesh_contacts_measure_cloth_edges(plait_sim *sim, plait_mesh_contacts *mc, float slack);
/* Whether every cloth edge that meets filtered colliders is still within its bound. */
bool plait_mesh_contacts_cloth_edges_within_bounds(plait_sim *sim, plait_mesh_contacts *mc);
/* Flags (marked[], per particle) the vertices of each cloth element whose edge outgrew its
 * bound and of the elements across its edges (whose D reads its bound); returns how many were
 * not flagged yet. */
int plait_mesh_contacts_mark_outgrown(const plait_sim *sim, const plait_mesh_contacts *mc, uint8_t *marked);
/* For a list mended around those vertices: the outgrown bounds set again from the edges now
 * (with slack), the others kept, and every D (pair_reach) taken from the bounds, as at the
 * listing (a failsafe's traversal since may have measured them without slack). */
void plait_mesh_contacts_rebound_cloth_edges(const plait_sim *sim, plait_mesh_contacts *mc);
/* The collider trees' node floors and the cloth trees' node ceilings' room (after the trees are
 * built), and the floors, which do not change; false when out of memory. */
bool plait_mesh_contacts_build_node_floors(plait_sim *sim, plait_mesh_contacts *mc);
/* Passing over node pairs of objects a and b where no corner or edge of the collider can meet
 * the cloth (every element pair there would keep none): the skip for their traversal, in
 * *skip with its context in *floors, or NULL when they are not such a pair. */
typedef struct smooth_skip {
	const float *floor, *ceiling;
	bool collider_first; /* the collider's tree is the traversal's tree a */
} smooth_skip;
const plait_node_skip *plait_mesh_contacts_smooth_skip(const plait_mesh_contacts *mc, int a, int b,
                                                       smooth_skip *floors, plait_node_skip *skip);
/* The corners and edges of filtered collider element c that meet cloth element e (bits). */
void plait_mesh_contacts_live_features(const plait_mesh_contacts *mc, int c, int e, uint8_t *vertices,
                                       uint8_t *edges);

/* mesh_contact_listing.c */

/* Element boxes, and the trees refitted to them: for the gather (paths false) or around the
 * substep's paths grown by margin (the failsafe's traversal). */
void plait_mesh_contacts_fit_boxes(plait_sim *sim, plait_mesh_contacts *mc, bool paths, float margin);
/* Whether objects a < b meet in mesh contacts. */
bool plait_mesh_contacts_objects_meet(const plait_sim *sim, const plait_mesh_contacts *mc, int a, int b);
/* How far objects a and b's boxes reach across in pass's stage (their allowance at a listing). */
vec3 plait_mesh_contacts_listing_margin(const plait_mesh_contacts *mc, const pair_pass *pass, int a, int b);
/* Every pair of elements that may touch, handed to pass, on the calling thread. */
void plait_mesh_contacts_traverse_objects(plait_mesh_contacts *mc, pair_pass *pass);
/* Lists the pairs that may touch into mc->pairs, with new guards and allowances. */
void plait_mesh_contacts_gather(plait_sim *sim, plait_mesh_contacts *mc);
/* Mends a list that holds but for the vertices flagged in mc->around (see
 * plait_mesh_contacts_list_covers_except): they take new paths, and their pairs are listed
 * again. */
void plait_mesh_contacts_relist_around(plait_sim *sim, plait_mesh_contacts *mc);
/* Its queries on the workers, the pairs appended to pass's list in the order
 * plait_mesh_contacts_query_around would list them; false (nothing listed) when they cannot run
 * there (out of memory, too few flagged elements). */
bool plait_mesh_contacts_relist_on_workers(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass);
/* Flagged elements per piece of the work around strayed vertices on the workers: enough to pay
 * a hand-over. */
#define AROUND_RUN 32
/* The flagged elements (mc->element_around) into mc->around_elements in order; their count, or
 * -1 when out of memory. */
int plait_mesh_contacts_collect_around(plait_sim *sim, plait_mesh_contacts *mc);
/* mc->element_around from mc->around: the elements with a flagged vertex. */
int plait_mesh_contacts_mark_elements(plait_mesh_contacts *mc);
/* Whether re-listing around the vertices flagged in mc->around (marking their elements) is
 * expected to meet fewer element pairs than a gather. */
bool plait_mesh_contacts_mending_pays(plait_mesh_contacts *mc);
/* Each element pair with a flagged element (mc->element_around) whose boxes overlap (between
 * objects within their allowance, with_allowance), once, handed to visit in global element
 * numbers: each flagged element's box queried against the trees of the objects it meets. */
void plait_mesh_contacts_query_around(const plait_sim *sim, const plait_mesh_contacts *mc,
                                      bool with_allowance, plait_element_pair_visitor *visit, void *context);
/* The same for flagged element e alone. */
void plait_mesh_contacts_query_around_element(const plait_sim *sim, const plait_mesh_contacts *mc, int e,
                                              bool with_allowance, plait_element_pair_visitor *visit,
                                              void *context);
/* Whether the list still holds every pair that can touch or cross (at the substep's start and
 * now). */
bool plait_mesh_contacts_list_covers(plait_sim *sim, plait_mesh_contacts *mc);
/* Whether the list holds every pair of two vertices that kept within their guards over the
 * substep, with the others flagged in strayed[] (per particle; set to 1, never cleared here)
 * and counted into *stray_count. False (nothing flagged) when it holds no pair at all: out of
 * its substeps, or a filtered collider's bound outgrown. */
bool plait_mesh_contacts_list_covers_except(plait_sim *sim, plait_mesh_contacts *mc, uint8_t *strayed,
                                            int *stray_count);

/* mesh_contact_pieces.c */

/* The scratch of the work on the workers: freed, or made once (false when out of memory). */
void plait_mesh_contacts_free_pieces(plait_mesh_contacts *mc, const plait_allocator *a);

/* What a projection of a pair does (plait_mesh_contacts_project_pair). */
typedef enum pair_projection {
	PROJECT_FULL,            /* a collision iteration's: pushes, and friction */
	PROJECT_AGAIN,           /* a contact pass's: pushes, and friction where it pushes (not
	                          * where it only rests) */
	PROJECT_AFTER_COLLIDERS, /* after the colliders' pass: as a full one, but no vertex that
	                          * touched a collider in the substep moves (the colliders keep the
	                          * last word on it) */
} pair_projection;

/* A list gathered again or mended within a substep (at a collision iteration after the
 * substep's contact passes projected the list before; in the failsafe after the collision
 * iteration) keeps the substep's state of the pairs it lists again (mesh_contact_carry.c):
 * before the listing, plait_mesh_contacts_carry keeps each pair of the old list that has some
 * (plait_mesh_contacts_has_state) and is not kept in place; list_pair gives a new pair the state
 * of the same pair carried (plait_mesh_contacts_take_carried); after it,
 * plait_mesh_contacts_drop_carried forgets them. Out of memory, a pair's state is lost, as it
 * was before carrying. */
bool plait_mesh_contacts_has_state(const plait_mesh_contacts *mc, const contact_pair *pair);
void plait_mesh_contacts_carry(plait_sim *sim, plait_mesh_contacts *mc, const contact_pair *pair);
void plait_mesh_contacts_take_carried(const plait_mesh_contacts *mc, contact_pair *pair);
void plait_mesh_contacts_drop_carried(plait_mesh_contacts *mc);
void plait_mesh_contacts_free_carried(plait_mesh_contacts *mc, const plait_allocator *a);

/* One projection of `pair` to its contact distance (mesh_contact.c), counting a CCD hit in
 * *ccd_hits. Returns 1 when it moved the pair's vertices. */
int plait_mesh_contacts_project_pair(plait_sim *sim, contact_pair *pair, pair_projection how, int *ccd_hits);
/* The list's pairs projected once as `how` says, a list of PLAN_LEAST_PAIRS or more in its
 * plan's order and on the workers (mesh_contact_plan.c); returns the contacts. A collision
 * iteration's projection (PROJECT_FULL) notes in each pair whether it pushed or rested
 * (pushed_last); a contact pass projects only those that did; after the colliders, only those
 * with a vertex that touched a collider in the substep (and a push or rest notes it too). */
int plait_mesh_contacts_project_list(plait_sim *sim, plait_mesh_contacts *mc, pair_projection how);
/* Puts the list in the plan's order, unless it is already; false when out of memory (the list
 * then keeps its order and is projected one pair after another: another result than the plan's,
 * but still the same for any number of threads). */
bool plait_mesh_contacts_plan(plait_sim *sim, plait_mesh_contacts *mc);
void plait_mesh_contacts_free_plan(plait_mesh_contacts *mc, const plait_allocator *a);
/* At a frame's start: a plan made before a vertex was pinned or unpinned is made again. */
void plait_mesh_contacts_check_plan(const plait_sim *sim, plait_mesh_contacts *mc);
bool plait_mesh_contacts_reserve_pieces(plait_mesh_contacts *mc, const plait_allocator *a);
/* One piece of a traversal, its element pairs handed to pass. */
void plait_mesh_contacts_list_piece(plait_mesh_contacts *mc, pair_pass *pass, const gather_piece *piece);
/* Cuts the traversals of stage `of` into mc->pieces; whether the cut is the last one's. */
bool plait_mesh_contacts_cut_pieces(const plait_sim *sim, plait_mesh_contacts *mc, stage of, int last_count);
/* The gather's traversal on the workers; false (nothing listed) when it cannot run there. */
bool plait_mesh_contacts_gather_on_workers(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass);

/* mesh_contact_failsafe.c */

/* The failsafe's test of one primitive pair, from the substep's start to now. */
void plait_mesh_contacts_sweep_pair(pair_pass *pass, int type, const int *v);
/* Forgets the rest pairs' carried distance bounds (when positions were moved). */
void plait_mesh_contacts_forget_rest_bounds(plait_mesh_contacts *mc);

/* ---- mesh_contact.c ---- */

/* Moves a pair's vertices so that its separation along n less its contact distance, c, becomes
 * 0, as `how` says (see respond there); false when none of them gives way. */
bool plait_mesh_contacts_respond(plait_sim *sim, contact_pair *pair, const float *g, vec3 n, float c,
                                 pair_projection how);

/* ---- mesh_contact_untangle.c ---- */

/* Searches the triangles at the substep's start (x_prev) for crossings; marks the tangled
 * vertices and plans the pushes through. False only when out of memory. */
bool plait_mesh_contacts_find_tangles(plait_sim *sim, plait_mesh_contacts *mc);

/* The planned pushes through, at a collision iteration; returns how many moved vertices. */
int plait_mesh_contacts_push_through(plait_sim *sim, plait_mesh_contacts *mc);

/* mc->tangled: a vertex of a crossing found at this substep's start (TANGLED_NOW), or at any
 * since the stage had its particles (TANGLED_EVER). */
#define TANGLED_NOW 1u
#define TANGLED_EVER 2u

/* Whether both primitives of a pair of this type have a vertex tangled `when`: now (while
 * mc->tangle_count > 0), neither pushed nor swept; ever, its start shape says nothing of it
 * (not a rest pair, its contact distance not clipped to its start separation). Now, moreover, a
 * vertex of each must be linked: of a crossing edge (or a vertex in a triangle) and of the
 * triangle it crosses. */
bool plait_mesh_contacts_pair_tangled(const plait_mesh_contacts *mc, int type, const int *v, uint8_t when);

#endif
