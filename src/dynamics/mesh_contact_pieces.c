/* Listing on the workers. The traversals of plait_mesh_contacts_traverse_objects, cut into pieces
 * (node pairs a few splits down), list side by side, each into a list of its own, and the lists
 * are joined in piece order: the list is the one plait_mesh_contacts_traverse_objects makes, pair
 * for pair, whatever the number of workers. A worker may not call the allocator (its hooks need
 * not be thread-safe): each piece's list is given room first, and a piece that runs out of it is
 * listed again on the calling thread. */
#include "dynamics/mesh_contact_internal.h"

#include <string.h>

/* The scratch of the listing and the failsafe's sweeps on the workers
 * (plait_mesh_contacts_gather_on_workers, sweep_on_workers). */
void plait_mesh_contacts_free_pieces(plait_mesh_contacts *mc, const plait_allocator *a)
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
	if (mc->around_lists != NULL) {
		for (int k = 0; k < MAX_PIECES; ++k) {
			plait_free(a, mc->around_lists[k].pairs);
		}
	}
	plait_free(a, mc->around_lists);
	plait_free(a, mc->around_elements);
	mc->around_lists = NULL;
	mc->around_elements = NULL;
	mc->around_capacity = mc->around_count = 0;
	mc->pieces = NULL;
	mc->piece_nodes = NULL;
	mc->piece_lists = NULL;
	mc->piece_hits = NULL;
	mc->piece_hit_count = mc->piece_swept = NULL;
	mc->piece_full = NULL;
	mc->piece_count = 0;
}

/* That scratch, made once, all of it or none; false when out of memory. */
bool plait_mesh_contacts_reserve_pieces(plait_mesh_contacts *mc, const plait_allocator *a)
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
		plait_mesh_contacts_free_pieces(mc, a);
		return false;
	}
	return true;
}

void plait_mesh_contacts_list_piece(plait_mesh_contacts *mc, pair_pass *pass, const gather_piece *piece)
{
	const collision_object *oa = &mc->objects[piece->a], *ob = &mc->objects[piece->b];
	bool self = piece->a == piece->b;
	object_pass o = {pass, oa->first, ob->first};
	flat_skip flat;
	plait_node_skip skip;
	smooth_skip floors;
	plait_node_skip smooth;
	plait_element_tree_piece_pairs(
	    &oa->tree, mc->lower + oa->first, mc->upper + oa->first, &ob->tree, mc->lower + ob->first,
	    mc->upper + ob->first, self,
	    self ? v3(0.0f, 0.0f, 0.0f) : plait_mesh_contacts_listing_margin(mc, pass, piece->a, piece->b),
	    self ? plait_mesh_contacts_self_skip(mc, &mc->objects[piece->a], pass, &flat, &skip)
	         : plait_mesh_contacts_smooth_skip(mc, piece->a, piece->b, &floors, &smooth),
	    piece->node, plait_mesh_contacts_visit_object_elements, &o);
}

/* Lists [begin, end) copied to their offsets in the joined list. */
typedef struct join_job {
	const piece_list *lists;
	contact_pair *into;
} join_job;

#define JOIN_GRAIN 4

static void join_lists(void *context, int begin, int end)
{
	const join_job *job = context;
	for (int k = begin; k < end; ++k) {
		const piece_list *list = &job->lists[k];
		if (list->count > 0) {
			memcpy(job->into + list->offset, list->pairs, sizeof *list->pairs * (size_t)list->count);
		}
	}
}

/* Room for `room` pairs in a piece's list (its pairs need not be kept); false when out of
 * memory. Grown by half again, so that lists whose length wavers are not made anew each time. */
static bool piece_room(const plait_allocator *a, piece_list *list, int room)
{
	if (list->capacity >= room) {
		return true;
	}
	int capacity = room + room / 2;
	contact_pair *bigger = plait_alloc(a, sizeof *bigger * (size_t)capacity);
	if (bigger == NULL) {
		return false;
	}
	plait_free(a, list->pairs);
	list->pairs = bigger;
	list->capacity = capacity;
	return true;
}

/* Listing in parts on the workers: the gather's pieces and the re-listing's runs. Part k lists
 * into lists[k] through list_part; the parts are joined in order, which is the order one thread
 * lists them in. */
typedef struct parts_job parts_job;
typedef void list_part_fn(const parts_job *job, pair_pass *pass, int k);
struct parts_job {
	plait_sim *sim;
	plait_mesh_contacts *mc;
	piece_list *lists;
	list_part_fn *list_part;
	bool around_only; /* the re-listing's (pair_pass.around_only) */
	int run;          /* the re-listing's flagged elements a run */
	bool again;       /* only the parts that ran out of room */
};

static void list_part_range(void *context, int begin, int end)
{
	const parts_job *job = context;
	for (int k = begin; k < end; ++k) {
		piece_list *list = &job->lists[k];
		if (job->again && !list->full) {
			continue;
		}
		list->count = 0;
		pair_pass pass = {.sim = job->sim,
		                  .mc = job->mc,
		                  .stage = STAGE_GATHER,
		                  .around_only = job->around_only,
		                  .out_pairs = &list->pairs,
		                  .out_count = &list->count,
		                  .out_capacity = &list->capacity,
		                  .fixed_capacity = true};
		job->list_part(job, &pass, k);
		list->full = pass.full;
		list->needed = list->count + pass.overflow;
		list->features_kept = pass.features_kept;
		list->features_left_out = pass.features_left_out;
		list->met = pass.met;
		list->cross_skipped = pass.cross_skipped;
	}
}

/* Room for `count` more pairs after the first `keep` of *pairs (which are kept). */
static bool grow_pairs(const plait_allocator *a, contact_pair **pairs, int *capacity, int keep, int count)
{
	if (keep + count <= *capacity) {
		return true;
	}
	int room = keep + count + (keep + count) / 2;
	contact_pair *bigger = plait_alloc(a, sizeof *bigger * (size_t)room);
	if (bigger == NULL) {
		return false;
	}
	if (keep > 0) {
		memcpy(bigger, *pairs, sizeof *bigger * (size_t)keep);
	}
	plait_free(a, *pairs);
	*pairs = bigger;
	*capacity = room;
	return true;
}

/* Lists parts [0, count), whose lists have their room, side by side. A part that runs out of
 * room counts what it could not list, gets that room and is listed again side by side (the
 * same pairs: a part's list depends on nothing but the part), or, failing that, on the calling
 * thread where its list may grow. The lists are then joined after out's pairs, and their
 * corner and edge counts added to out's. False (nothing listed) when out of memory for a list;
 * out of memory for the joined list sets mc->out_of_memory. */
static bool list_parts(parts_job *job, int count, pair_pass *out)
{
	plait_sim *sim = job->sim;
	const plait_allocator *a = &sim->allocator;
	job->again = false;
	plait_parallel_for(&sim->parallel, list_part_range, job, 0, count, 1);
	bool any_full = false;
	for (int k = 0; k < count; ++k) {
		piece_list *list = &job->lists[k];
		if (list->full) {
			any_full = true;
			if (!piece_room(a, list, list->needed)) {
				return false;
			}
		}
	}
	if (any_full) {
		job->again = true;
		plait_parallel_for(&sim->parallel, list_part_range, job, 0, count, 1);
	}
	int keep = *out->out_count, total = 0;
	for (int k = 0; k < count; ++k) {
		piece_list *list = &job->lists[k];
		if (list->full) {
			list->count = 0;
			list->full = false;
			pair_pass again = {.sim = sim,
			                   .mc = job->mc,
			                   .stage = STAGE_GATHER,
			                   .around_only = job->around_only,
			                   .out_pairs = &list->pairs,
			                   .out_count = &list->count,
			                   .out_capacity = &list->capacity};
			job->list_part(job, &again, k);
			list->features_kept = again.features_kept;
			list->features_left_out = again.features_left_out;
			list->met = again.met;
			list->cross_skipped = again.cross_skipped;
		}
		out->features_kept += list->features_kept;
		out->features_left_out += list->features_left_out;
		out->met += list->met;
		out->cross_skipped += list->cross_skipped;
		list->offset = total;
		total += list->count;
	}
	if (!grow_pairs(a, out->out_pairs, out->out_capacity, keep, total)) {
		job->mc->out_of_memory = true;
		return true;
	}
	join_job join = {job->lists, *out->out_pairs + keep};
	plait_parallel_for(&sim->parallel, join_lists, &join, 0, count, JOIN_GRAIN);
	*out->out_count = keep + total;
	return true;
}

static void list_gather_piece(const parts_job *job, pair_pass *pass, int k)
{
	plait_mesh_contacts_list_piece(job->mc, pass, &job->mc->pieces[k]);
}

/* Cuts the traversals of stage `of` into mc->pieces (piece_count 0 when they do not fit); returns
 * whether the cut is the one before, which had last_count pieces. */
bool plait_mesh_contacts_cut_pieces(const plait_sim *sim, plait_mesh_contacts *mc, stage of, int last_count)
{
	int(*nodes)[2] = mc->piece_nodes;
	int count = 0;
	bool fits = true, same = true;
	for (int a = 0; a < mc->object_count && fits; ++a) {
		for (int b = a; b < mc->object_count && fits; ++b) {
			const collision_object *oa = &mc->objects[a], *ob = &mc->objects[b];
			if ((a == b && !oa->self) || (a != b && !plait_mesh_contacts_objects_meet(sim, mc, a, b))) {
				continue;
			}
			pair_pass margin_pass = {.stage = of};
			flat_skip flat;
			plait_node_skip skip;
			smooth_skip floors;
			plait_node_skip smooth;
			int n = plait_element_tree_split(
			    &oa->tree, &ob->tree, a == b,
			    a == b ? v3(0.0f, 0.0f, 0.0f) : plait_mesh_contacts_listing_margin(mc, &margin_pass, a, b),
			    a == b ? plait_mesh_contacts_self_skip(mc, &mc->objects[a], &margin_pass, &flat, &skip)
			           : plait_mesh_contacts_smooth_skip(mc, a, b, &floors, &smooth),
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
bool plait_mesh_contacts_gather_on_workers(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass)
{
	const plait_allocator *a = &sim->allocator;
	if (!plait_mesh_contacts_reserve_pieces(mc, a)) {
		return false;
	}
	/* The first listing, with nothing to size the pieces' lists by, runs on the calling thread
	 * (most pieces would fill their room and be listed twice). (Long listings used to stay
	 * there too, when the pile listed about 50 pairs an element and joining the lists cost more
	 * than a worker saved; with failsafe-only pairs that cannot cross left out it is the other
	 * way round: pile at two threads 611-651 -> 446-530 ms a frame.) */
	if (mc->last_listed == 0) {
		return false;
	}
	int last_count = mc->piece_count;
	bool same_cut = plait_mesh_contacts_cut_pieces(sim, mc, STAGE_GATHER, last_count);
	if (mc->piece_count == 0) {
		return false;
	}
	/* Room for each piece: half as much again as it listed last time when the cut is the same
	 * (a tree's node pairs change little from one listing to the next), else twice its share
	 * of the last listing. */
	for (int k = 0; k < mc->piece_count; ++k) {
		piece_list *list = &mc->piece_lists[k];
		int room = same_cut ? 64 + list->count + list->count / 2 : 64 + 2 * mc->last_listed / mc->piece_count;
		if (!piece_room(a, list, room)) {
			return false;
		}
	}
	parts_job job = {.sim = sim, .mc = mc, .lists = mc->piece_lists, .list_part = list_gather_piece};
	return list_parts(&job, mc->piece_count, pass);
}

/* ---- Re-listing around strayed vertices on the workers ----------------------------------------- */

/* Run k of the flagged elements (mc->around_elements): each one's pairs, in order. */
static void list_around_run(const parts_job *job, pair_pass *pass, int k)
{
	const plait_mesh_contacts *mc = job->mc;
	object_pass objects = {pass, 0, 0};
	int last = (k + 1) * job->run < mc->around_count ? (k + 1) * job->run : mc->around_count;
	for (int j = k * job->run; j < last; ++j) {
		plait_mesh_contacts_query_around_element(job->sim, mc, mc->around_elements[j], true,
		                                         plait_mesh_contacts_visit_object_elements, &objects);
	}
}

int plait_mesh_contacts_collect_around(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_allocator *a = &sim->allocator;
	if (mc->around_capacity < mc->element_count) {
		int *bigger = plait_alloc(a, sizeof(int) * (size_t)mc->element_count);
		if (bigger == NULL) {
			return -1;
		}
		plait_free(a, mc->around_elements);
		mc->around_elements = bigger;
		mc->around_capacity = mc->element_count;
	}
	int count = 0;
	for (int e = 0; e < mc->element_count; ++e) {
		if (mc->element_around[e]) {
			mc->around_elements[count++] = e;
		}
	}
	mc->around_count = count;
	return count;
}

bool plait_mesh_contacts_relist_on_workers(plait_sim *sim, plait_mesh_contacts *mc, pair_pass *pass)
{
	const plait_allocator *a = &sim->allocator;
	if (mc->around_lists == NULL) {
		mc->around_lists = plait_alloc_zero(a, MAX_PIECES, sizeof *mc->around_lists);
		if (mc->around_lists == NULL) {
			return false;
		}
	}
	int count = plait_mesh_contacts_collect_around(sim, mc);
	if (count < 2 * AROUND_RUN) {
		return false; /* too few to share (or out of memory) */
	}
	int run = AROUND_RUN;
	if ((count + run - 1) / run > MAX_PIECES) {
		run = (count + MAX_PIECES - 1) / MAX_PIECES;
	}
	int runs = (count + run - 1) / run;
	/* Room for each run: twice what the last re-listing listed per flagged element. */
	float per_element = mc->around_pairs_per_element > 8.0f ? mc->around_pairs_per_element : 8.0f;
	int room = 64 + (int)(2.0f * per_element * (float)run);
	for (int k = 0; k < runs; ++k) {
		if (!piece_room(a, &mc->around_lists[k], room)) {
			return false;
		}
	}
	int kept = *pass->out_count;
	parts_job job = {.sim = sim,
	                 .mc = mc,
	                 .lists = mc->around_lists,
	                 .list_part = list_around_run,
	                 .around_only = true,
	                 .run = run};
	if (!list_parts(&job, runs, pass)) {
		return false;
	}
	mc->around_pairs_per_element = (float)(*pass->out_count - kept) / (float)count;
	return true;
}
