/* Listing the primitive pairs that may touch: element boxes, the traversal of objects through
 * their trees, the gather, and how long its list covers (the guards). */
#include "dynamics/mesh_contact_internal.h"

#include "collision/closest.h"
#include "core/lanes.h"

#include <stdatomic.h>
#include <string.h>

/* ---- Element boxes and the traversal of objects ---------------------------------------------- */

/* Element boxes. For the gather: around the current positions, grown by LIST_SCALE times the
 * element's reach, its largest guard and how far its motion may take it from its object's
 * (a pair within its list distance has overlapping boxes, see plait_mesh_contacts_gather).
 * For the failsafe: around the paths of the substep, grown by `margin`. */
static void fit_boxes(plait_sim *sim, plait_mesh_contacts *mc, bool paths, float margin, bool measure_edges);

void plait_mesh_contacts_fit_boxes(plait_sim *sim, plait_mesh_contacts *mc, bool paths, float margin)
{
	fit_boxes(sim, mc, paths, margin, true);
}

/* Elements' boxes over [begin, end): each element's alone, so on the workers. */
typedef struct box_job {
	const plait_sim *sim;
	plait_mesh_contacts *mc;
	bool paths;
	float margin;
} box_job;

#define FIT_BOX_GRAIN 2048

/* Substeps since the list's gather: 0 at the gather's own. */
static long substeps_since_gather(const plait_mesh_contacts *mc)
{
	return mc->substep_serial - mc->gather_serial;
}

/* Whether this substep lies past the list's window: every path of the gather has stopped
 * (path_end), and the list serves on only while its vertices rest (resting lists, list_holds). */
static bool past_window(const plait_mesh_contacts *mc)
{
	return substeps_since_gather(mc) > mc->list_serves || mc->list_rests;
}

/* Particle i's motion a substep along its path over the substep `since` (counted from the
 * gather's): mc->motion while its path runs, none once it stopped (mc->path_end). */
static vec3 path_motion(const plait_mesh_contacts *mc, int i, float since)
{
	return mc->path_end[i] >= since ? mc->motion[i] : v3(0.0f, 0.0f, 0.0f);
}

/* Where particle i's path is at substep s (counted from the gather's). */
static vec3 path_at(const plait_mesh_contacts *mc, int i, float s)
{
	return v3_mul_add(mc->x_gather[i], plait_minf(s, mc->path_end[i]), mc->motion[i]);
}

#if defined(PLAIT_HAVE_LANES)
/* The unit normals of four triangle elements, lane k for elements[k]: plait_triangle_normal's
 * operations lane by lane (core/lanes.h), so the same bits; each point loaded whole and the
 * four transposed. */
static void triangle_normals4(const plait_point *point, const element *const elements[4], vec3 out[4])
{
	lanes3 corner[3];
	for (int m = 0; m < 3; ++m) {
		__m128 r0 = _mm_loadu_ps(&point[elements[0]->v[m]].x.x),
		       r1 = _mm_loadu_ps(&point[elements[1]->v[m]].x.x),
		       r2 = _mm_loadu_ps(&point[elements[2]->v[m]].x.x),
		       r3 = _mm_loadu_ps(&point[elements[3]->v[m]].x.x);
		_MM_TRANSPOSE4_PS(r0, r1, r2, r3);
		corner[m] = (lanes3){r0, r1, r2};
	}
	lanes3 n = lanes3_cross(lanes3_sub(corner[1], corner[0]), lanes3_sub(corner[2], corner[0]));
	__m128 length = _mm_sqrt_ps(lanes3_dot(n, n));
	lanes3 unit = lanes3_scale(n, _mm_div_ps(_mm_set1_ps(1.0f), length));
	__m128 kept = _mm_cmpgt_ps(length, _mm_setzero_ps()); /* else zero, as the scalar code */
	lanes3_store((lanes3){_mm_and_ps(kept, unit.x), _mm_and_ps(kept, unit.y), _mm_and_ps(kept, unit.z)}, out);
}

/* The gather's triangle normals over [begin, end), four at a time (the rest one by one): a
 * square root and a division each, a tenth of a falling cloth's collision stage when one by
 * one. */
static void fit_normals_range(const plait_sim *sim, plait_mesh_contacts *mc, int begin, int end)
{
	const plait_point *point = sim->particles.point;
	const element *batch[4];
	int batched[4], count = 0;
	for (int e = begin; e < end; ++e) {
		const element *el = &mc->elements[e];
		if (el->size != 3) {
			continue;
		}
		batch[count] = el;
		batched[count++] = e;
		if (count == 4) {
			vec3 normals[4];
			triangle_normals4(point, batch, normals);
			for (int k = 0; k < 4; ++k) {
				mc->shapes[batched[k]].normal = normals[k];
			}
			count = 0;
		}
	}
	for (int k = 0; k < count; ++k) {
		const int *v = batch[k]->v;
		vec3 t[3] = {point[v[0]].x, point[v[1]].x, point[v[2]].x};
		mc->shapes[batched[k]].normal = plait_triangle_normal(t);
	}
}
#endif

static void fit_box_range(void *context, int begin, int end)
{
	const box_job *job = context;
	const plait_sim *sim = job->sim;
	plait_mesh_contacts *mc = job->mc;
	bool paths = job->paths;
	const plait_particles *p = &sim->particles;
	float since = (float)substeps_since_gather(mc);
#if defined(PLAIT_HAVE_LANES)
	if (!paths) {
		fit_normals_range(sim, mc, begin, end);
	}
#endif
	for (int e = begin; e < end; ++e) {
		const element *el = &mc->elements[e];
		vec3 lower = p->point[el->v[0]].x, upper = lower;
		float radius = 0.0f, guard = 0.0f;
		if (!paths) {
			/* The element's motion and spread: the mean of its vertices' and the largest
			 * distance from it. A vertex whose path stopped before this substep moves no
			 * more (path_motion). */
			vec3 motion[3] = {{0}};
			for (int k = 0; k < el->size; ++k) {
				motion[k] = path_motion(mc, el->v[k], since);
			}
			vec3 mean = motion[0];
			for (int k = 1; k < el->size; ++k) {
				mean = v3_add(mean, motion[k]);
			}
			mean = v3_scale(mean, 1.0f / (float)el->size);
			/* One square root: it is monotonic, so the root of the largest square is the
			 * largest root. */
			float spread_sq = 0.0f;
			for (int k = 0; k < el->size; ++k) {
				vec3 d = v3_sub(motion[k], mean);
				spread_sq = plait_maxf(spread_sq, v3_dot(d, d));
			}
			mc->element_motion[e] = mean;
			mc->element_spread[e] = spread_sq; /* its root below, four at a time */
		}
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
		float g = job->margin;
		if (!paths) {
			element_shape *shape = &mc->shapes[e];
			shape->lower = lower;
			shape->upper = upper;
			vec3 c = p->point[el->v[0]].x;
			for (int k = 1; k < el->size; ++k) {
				c = v3_add(c, p->point[el->v[k]].x);
			}
			shape->centre = v3_scale(c, 1.0f / (float)el->size);
#if !defined(PLAIT_HAVE_LANES)
			if (el->size == 3) {
				vec3 t[3] = {p->point[el->v[0]].x, p->point[el->v[1]].x, p->point[el->v[2]].x};
				shape->normal = plait_triangle_normal(t);
			}
#endif
			const plait_material *m = &sim->materials[el->material];
			float reach = radius * (m->self_collide ? plait_maxf(1.0f, m->self_width_scale) : 1.0f);
			/* Swept along its vertices' paths relative to their object (path_box_range). */
			for (int k = 0; k < el->size; ++k) {
				lower = v3_min(lower, mc->path_lower[el->v[k]]);
				upper = v3_max(upper, mc->path_upper[el->v[k]]);
			}
			g += LIST_SCALE * reach + guard + FAILSAFE_DISTANCE;
			mc->element_reach[e] = radius;
			mc->element_guard[e] = guard;
		}
		mc->lower[e] = v3_sub(lower, v3(g, g, g));
		mc->upper[e] = v3_add(upper, v3(g, g, g));
	}
	if (!paths) {
		/* The spreads' square roots apart from the loop above, whose every element waited on
		 * its own (a fifth of the loop's time): the same roots, correctly rounded either way. */
		float *spread = mc->element_spread;
		int e = begin;
#if defined(PLAIT_HAVE_LANES)
		for (; e + 4 <= end; e += 4) {
			_mm_storeu_ps(spread + e, _mm_sqrt_ps(_mm_loadu_ps(spread + e)));
		}
#endif
		for (; e < end; ++e) {
			spread[e] = sqrtf(spread[e]);
		}
	}
}

/* The box of each particle's path in [begin, end), relative to its object's mean motion, from
 * the gather's substep's start to the end of the list's window (its path as the gather took it,
 * at a gather where it is now): each element's box holds its vertices'. Past the window, the
 * box of the path's last stretch, in place. */
static void path_box_range(void *context, int begin, int end)
{
	const box_job *job = context;
	plait_mesh_contacts *mc = job->mc;
	float serves = (float)mc->list_serves;
	if (past_window(mc)) {
		long since = substeps_since_gather(mc);
		/* Past the list's window (a resting list, list_holds) every path stops by this substep:
		 * the box of its last stretch, in place (not relative to its object, which need not
		 * move on as it did at the gather), so queries between objects need no allowance
		 * (plait_mesh_contacts_query_around_element). */
		for (int i = begin; i < end; ++i) {
			vec3 a = path_at(mc, i, (float)(since - 1)), b = path_at(mc, i, (float)since);
			mc->path_lower[i] = v3_min(a, b);
			mc->path_upper[i] = v3_max(a, b);
		}
		return;
	}
	for (int i = begin; i < end; ++i) {
		int o = mc->object_of[i];
		vec3 mean = o >= 0 ? mc->shift[o] : v3(0.0f, 0.0f, 0.0f); /* minus the object's */
		vec3 x = mc->x_gather[i], w = v3_add(mc->motion[i], mean);
		vec3 back = v3_sub(x, w), on = v3_mul_add(x, serves, w);
		mc->path_lower[i] = v3_min(x, v3_min(back, on));
		mc->path_upper[i] = v3_max(x, v3_max(back, on));
	}
}

#define PATH_BOX_GRAIN 4096

/* Trees are refitted on the workers subtree by subtree, CUT_LEVELS below their roots, then
 * above those on the calling thread. */
#define CUT_LEVELS 5

typedef struct refit_job {
	plait_element_tree *tree;
	const vec3 *lower, *upper;
	const int *roots;
} refit_job;

static void refit_subtrees(void *context, int begin, int end)
{
	const refit_job *job = context;
	for (int k = begin; k < end; ++k) {
		plait_element_tree_refit_subtree(job->tree, job->roots[k], job->lower, job->upper);
	}
}

/* As plait_mesh_contacts_fit_boxes; without measure_edges the cloth edges' bounds of the last
 * listing are kept (a re-listing around strayed vertices must decide as the listing did). */
static void fit_boxes(plait_sim *sim, plait_mesh_contacts *mc, bool paths, float margin, bool measure_edges)
{
	box_job job = {sim, mc, paths, margin};
	if (!paths) {
		plait_parallel_for(&sim->parallel, path_box_range, &job, 0, sim->particles.count, PATH_BOX_GRAIN);
	}
	plait_parallel_for(&sim->parallel, fit_box_range, &job, 0, mc->element_count, FIT_BOX_GRAIN);
	if (mc->features != NULL && measure_edges) {
		plait_mesh_contacts_measure_cloth_edges(sim, mc, paths ? 1.0f : CLOTH_EDGE_SLACK);
	}
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		int roots[1 << CUT_LEVELS];
		refit_job refit = {&o->tree, mc->lower + o->first, mc->upper + o->first, roots};
		int count = plait_element_tree_cut(&o->tree, CUT_LEVELS, roots);
		plait_parallel_for(&sim->parallel, refit_subtrees, &refit, 0, count, 1);
		plait_element_tree_refit_above(&o->tree, CUT_LEVELS, refit.lower, refit.upper);
	}
}

/* Whether the traversal of `pass` passes over flat patches' pairs with themselves: the gather's,
 * once the patches are fitted to its paths. Pairs within a patch that stays flat over the paths
 * cannot touch or cross (collision/flat_patches.h), and none of its vertices can leave its path
 * without being re-listed around (list_holds), which does not skip. */
bool plait_mesh_contacts_culls_flat(const plait_mesh_contacts *mc, const pair_pass *pass)
{
	return mc->cull_flat && mc->patches_fitted_for == (int)pass->stage && !pass->around_only;
}

/* Normal cones are fitted the same way as boxes (CUT_LEVELS). */
typedef struct fit_job {
	plait_flat_patches *patches;
	const plait_element_tree *tree;
	const plait_patch_paths *paths;
	const int *roots;
} fit_job;

static void fit_subtrees(void *context, int begin, int end)
{
	const fit_job *job = context;
	for (int k = begin; k < end; ++k) {
		plait_flat_patches_fit_subtree(job->patches, job->tree, job->paths, job->roots[k]);
	}
}

void plait_mesh_contacts_fit_tree_patches(plait_sim *sim, plait_flat_patches *patches,
                                          const plait_element_tree *tree, const plait_patch_paths *paths)
{
	int roots[1 << CUT_LEVELS];
	int count = plait_element_tree_cut(tree, CUT_LEVELS, roots);
	fit_job job = {patches, tree, paths, roots};
	plait_parallel_for(&sim->parallel, fit_subtrees, &job, 0, count, 1);
	plait_flat_patches_fit_above(patches, tree, CUT_LEVELS);
}

typedef struct normals_job {
	collision_object *object;
	const plait_patch_paths *paths;
} normals_job;

static void find_normals(void *context, int begin, int end)
{
	const normals_job *job = context;
	plait_flat_patches_normals(&job->object->patches, job->paths, begin, end, job->object->normals);
}

#define NORMALS_GRAIN 4096

void plait_mesh_contacts_fit_patches(plait_sim *sim, plait_mesh_contacts *mc, const plait_patch_paths *paths,
                                     stage of)
{
	mc->patch_paths = *paths;
	mc->patches_fitted_for = (int)of;
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		if (o->patches.node_count == 0) {
			continue;
		}
		/* At a gather, a cloth's cross patches are fitted to the same paths: its triangles'
		 * normals are found once for both. */
		bool cross =
		    of == STAGE_GATHER && o->cross_of != NULL && mc->cull_cross && plait_mesh_contacts_cross_pays(o);
		plait_patch_paths object_paths = *paths;
		if (cross) {
			normals_job normals = {o, paths};
			plait_parallel_for(&sim->parallel, find_normals, &normals, 0, o->count, NORMALS_GRAIN);
			object_paths.normals = o->normals;
		}
		plait_mesh_contacts_fit_tree_patches(sim, &o->patches, &o->tree, &object_paths);
		if (of == STAGE_GATHER && o->cross_of != NULL) {
			plait_mesh_contacts_fit_cross(sim, o, &object_paths, cross);
		}
	}
}

bool plait_mesh_contacts_skip_flat(int node, void *context)
{
	const flat_skip *flat = context;
	vec3 axis;
	bool skip = plait_flat_patches_flat(flat->patches, node, flat->paths, &axis);
	if (skip && flat->culled != NULL) {
		/* One piece reaches a node's pair with itself (and the cut before it, the same). */
		flat->culled[node] = 1;
		flat->culled_axis[node] = axis;
	}
	return skip;
}

const plait_node_skip *plait_mesh_contacts_self_skip(const plait_mesh_contacts *mc, const collision_object *o,
                                                     const pair_pass *pass, flat_skip *flat,
                                                     plait_node_skip *skip)
{
	if (!plait_mesh_contacts_culls_flat(mc, pass) || !mc->cull_own) {
		return NULL;
	}
	bool gather = pass->stage == STAGE_GATHER;
	*flat =
	    (flat_skip){&o->patches, &mc->patch_paths, gather ? o->culled : NULL, gather ? o->culled_axis : NULL};
	*skip = (plait_node_skip){plait_mesh_contacts_skip_flat, NULL, flat};
	return skip;
}

/* Whether objects a < b meet in mesh contacts. */
bool plait_mesh_contacts_objects_meet(const plait_sim *sim, const plait_mesh_contacts *mc, int a, int b)
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
vec3 plait_mesh_contacts_listing_margin(const plait_mesh_contacts *mc, const pair_pass *pass, int a, int b)
{
	return pass->stage == STAGE_GATHER ? mc->allowance[a * mc->object_count + b] : v3(0.0f, 0.0f, 0.0f);
}

/* Every pair of elements that may touch: each self-colliding object with itself, then each
 * pair of objects that collide with each other. */
void plait_mesh_contacts_traverse_objects(plait_mesh_contacts *mc, pair_pass *pass)
{
	const plait_sim *sim = pass->sim;
	for (int a = 0; a < mc->object_count; ++a) {
		const collision_object *oa = &mc->objects[a];
		vec3 *la = mc->lower + oa->first, *ua = mc->upper + oa->first;
		object_pass self = {pass, oa->first, oa->first};
		if (oa->self) {
			flat_skip flat;
			plait_node_skip skip;
			plait_element_tree_pairs_skipping(
			    &oa->tree, la, ua, plait_mesh_contacts_self_skip(mc, &mc->objects[a], pass, &flat, &skip),
			    plait_mesh_contacts_visit_object_elements, &self);
		}
		for (int b = a + 1; b < mc->object_count; ++b) {
			if (!plait_mesh_contacts_objects_meet(sim, mc, a, b)) {
				continue;
			}
			const collision_object *ob = &mc->objects[b];
			object_pass between = {pass, oa->first, ob->first};
			smooth_skip floors;
			plait_node_skip smooth;
			plait_element_tree_pairs_between(&oa->tree, la, ua, &ob->tree, mc->lower + ob->first,
			                                 mc->upper + ob->first,
			                                 plait_mesh_contacts_listing_margin(mc, pass, a, b),
			                                 plait_mesh_contacts_smooth_skip(mc, a, b, &floors, &smooth),
			                                 plait_mesh_contacts_visit_object_elements, &between);
		}
	}
}

/* ---- The gather and its guards --------------------------------------------------------------- */

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

/* The gather lists the pairs that can come within reach while every vertex keeps near the
 * straight path it is on: its motion u over this substep so far (start to now), continued at
 * the same pace for LIST_SUBSTEPS more substeps. A vertex may stray from that path by its guard:
 * a quarter of its motion relative to its object's mean motion, gravity's bend of the path over
 * the substeps the list serves, a share of its radius (contact pushes: a fifth for a list that
 * serves on, a tenth for a short one) and a tenth of a millimetre in metres. Over substeps [gather - 1,
 * gather + LIST_SUBSTEPS] from now, vertices k and l then move relative to each other by at most
 * LIST_SUBSTEPS |u_k - u_l| plus their guards, and so do any two points of two primitives (points of a
 * primitive move by means of its vertices' motions); the element pair walk lists the pairs nearer than their
 * contact distance plus that. Neighbours that move together (a cloth falling or swinging as a whole) then
 * list only what is really close, and keep their list while they move steadily. Where vertices do not keep to
 * their paths (cloth thrown about on a collider, squeezed in folds), a list that serves on is gathered again
 * at the next substep anyway: there the lists are short (mc->short_lists) and serve only their own substep.
 * They list the pairs within their contact distance now (plus their guards) and those whose paths so far may
 * have met, not those that may meet in the next substep: a pair's reach is the larger of its contact distance
 * and its motion, not their sum. */
/* Gravity's bend of a path over the substeps a list serves. */
static float path_bend(const plait_sim *sim)
{
	float h = sim->substep_time, steps = (float)LIST_SUBSTEPS;
	return v3_length(sim->settings.gravity) * h * h * 0.5f * steps * (steps + 1.0f);
}

/* The share of a vertex's radius its guard allows for contact pushes. A list that serves on is
 * mended, not gathered again, while only a few vertices stray, and a larger allowance keeps
 * more of them on their paths (drape: 414 gathers in 540 substeps at a tenth, 166 at a fifth;
 * pile and twist faster too). A short list serves only its substep, and a larger allowance
 * would only lengthen it (arm). Whether the next lists are short is judged against the last
 * list's guards (plait_mesh_contacts_project: paths_kept), so the choice holds a little: after
 * short lists the vertices must keep within the smaller allowance for lists to serve on again.
 * performance.md, sessions 23 and 24. */
#define PUSH_SHARE_SERVING 0.2f
#define PUSH_SHARE_SHORT 0.1f

/* Particle i's guard, from its motion (mc->motion) and its object's mean (mc->shift). */
static float path_guard(const plait_sim *sim, const plait_mesh_contacts *mc, int i, float bend)
{
	int o = mc->object_of[i];
	float relative = o >= 0 ? v3_length(v3_add(mc->motion[i], mc->shift[o])) : v3_length(mc->motion[i]);
	float push_share = mc->list_serves > 0 ? PUSH_SHARE_SERVING : PUSH_SHARE_SHORT;
	return 0.25f * relative + bend + push_share * sim->particles.radius[i] + 1e-4f;
}

void plait_mesh_contacts_gather(plait_sim *sim, plait_mesh_contacts *mc)
{
	for (int k = 0; k < mc->pair_count; ++k) {
		if (plait_mesh_contacts_has_state(mc, &mc->pairs[k])) {
			plait_mesh_contacts_carry(sim, mc, &mc->pairs[k]);
		}
	}
	mc->pair_count = 0;
	mc->list_changes += 1;
	mc->planned = 0; /* a new list, in the gather's order (mesh_contact_plan.c) */
	mc->out_of_memory = false;
	mc->gather_serial = mc->substep_serial;
	mc->listings += 1;
	mc->list_serves = mc->short_lists ? 0 : LIST_SUBSTEPS;
	mc->list_rests = false;
	mc->rest_asked = false;
	const plait_particles *p = &sim->particles;
	for (int i = 0; i < p->count; ++i) {
		mc->x_gather[i] = p->point[i].x;
		mc->motion[i] = v3_sub(p->point[i].x, p->x_prev[i]);
		mc->path_end[i] = (float)LIST_SUBSTEPS;
	}
	object_shifts(sim, mc, p->x_prev, true); /* minus each object's mean motion */
	float bend = path_bend(sim);
	for (int i = 0; i < p->count; ++i) {
		mc->guard[i] = path_guard(sim, mc, i, bend);
	}
	/* Boxes reach across by their elements' motions relative to their objects' (fit_boxes) and
	 * the objects' relative motion (here): over substeps [-1, LIST_SUBSTEPS] from now one
	 * object moves against the other by s times the difference of their mean motions, which
	 * along each axis is at most LIST_SUBSTEPS times that axis's part of it. (Not its length
	 * along every axis: a cloth falling past a collider would meet every collider element
	 * beside its path as well as those on it.) */
	for (int a = 0; a < mc->object_count; ++a) {
		for (int b = 0; b < mc->object_count; ++b) {
			vec3 d = v3_sub(mc->shift[a], mc->shift[b]);
			float steps = (float)LIST_SUBSTEPS;
			mc->allowance[a * mc->object_count + b] =
			    v3(steps * fabsf(d.x) + 1e-4f, steps * fabsf(d.y) + 1e-4f, steps * fabsf(d.z) + 1e-4f);
		}
	}
	plait_mesh_contacts_fit_boxes(sim, mc, false, 0.0f);
	if (mc->cull_flat) {
		/* The paths the list expects, without their guards: a guess, which the failsafe checks
		 * along the substep's own paths (sweep_unflattened). */
		plait_patch_paths paths = {mc->x_gather, mc->motion, NULL, 1.0f, (float)mc->list_serves, NULL};
		plait_mesh_contacts_fit_patches(sim, mc, &paths, STAGE_GATHER);
		for (int k = 0; k < mc->object_count; ++k) {
			if (mc->objects[k].culled != NULL) {
				memset(mc->objects[k].culled, 0, (size_t)mc->objects[k].tree.node_count);
			}
		}
	}
	pair_pass pass = {.sim = sim,
	                  .mc = mc,
	                  .stage = STAGE_GATHER,
	                  .out_pairs = &mc->pairs,
	                  .out_count = &mc->pair_count,
	                  .out_capacity = &mc->pair_capacity};
	if (!(sim->parallel.worker_count > 1 && plait_mesh_contacts_gather_on_workers(sim, mc, &pass))) {
		plait_mesh_contacts_traverse_objects(mc, &pass);
	}
	mc->last_listed = mc->pair_count;
	mc->gather_met = pass.met;
	plait_mesh_contacts_count_cross(mc, pass.cross_skipped);
	mc->listing_met += pass.met;
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		for (int n = 0; o->culled != NULL && n < o->tree.node_count; ++n) {
			mc->culled_patches += o->culled[n];
		}
		for (int n = 0; o->cross_of != NULL && n < o->cross_tree.node_count; ++n) {
			mc->culled_patches += atomic_load_explicit(&o->cross_culled[n], memory_order_relaxed) != 0;
		}
	}
	mc->features_kept = pass.features_kept;
	mc->features_left_out = pass.features_left_out;
	mc->list_valid = !mc->out_of_memory;
	plait_mesh_contacts_drop_carried(mc);
}

/* Whether the list still holds every pair that can touch or cross: within LIST_LIFE substeps
 * of the gather's (LIST_SUBSTEPS for a short list), every vertex within its guard of its path
 * (see plait_mesh_contacts_gather; past its end, of where it ended: path_at) at the substep's
 * start and now. A substep's
 * paths run straight between those, so they keep as near the vertices' paths. With `strayed`
 * (one flag per particle), the vertices out of their guards are flagged and counted into
 * *stray_count instead: the list then holds every pair of two vertices that are not. */
typedef struct holds_job {
	const plait_sim *sim;
	const plait_mesh_contacts *mc;
	uint8_t *strayed;
	long since;
	_Atomic int strays;  /* newly flagged */
	_Atomic int movable; /* particles in mesh contacts that are not held still (inverse mass > 0) */
	_Atomic int out;     /* any out of its guard (without `strayed`) */
} holds_job;

#define HOLDS_GRAIN 4096

static void holds_range(void *context, int begin, int end)
{
	holds_job *job = context;
	const plait_particles *p = &job->sim->particles;
	const plait_mesh_contacts *mc = job->mc;
	int strays = 0, movable = 0;
	for (int i = begin; i < end; ++i) {
		if (mc->object_of[i] < 0) {
			continue;
		}
		movable += p->point[i].w > 0.0f;
		bool out = false;
		for (int when = 0; when < 2 && !out; ++when) {
			/* Substeps from the gather's end: its start is -1, now is the current substep's end. */
			vec3 x = when == 0 ? p->x_prev[i] : p->point[i].x;
			vec3 stray = v3_sub(x, path_at(mc, i, (float)(job->since - 1 + when)));
			out = v3_length_sq(stray) > mc->guard[i] * mc->guard[i];
		}
		if (out) {
			if (job->strayed == NULL) {
				atomic_store_explicit(&job->out, 1, memory_order_relaxed);
				return;
			}
			strays += !job->strayed[i];
			job->strayed[i] = 1;
		}
	}
	atomic_fetch_add_explicit(&job->strays, strays, memory_order_relaxed);
	atomic_fetch_add_explicit(&job->movable, movable, memory_order_relaxed);
}

/* The vertices out of their guards (holds_range), flagged in strayed and counted (those newly
 * flagged). */
static int count_strays(plait_sim *sim, const plait_mesh_contacts *mc, uint8_t *strayed, long since)
{
	holds_job job = {.sim = sim, .mc = mc, .strayed = strayed, .since = since};
	atomic_init(&job.strays, 0);
	atomic_init(&job.movable, 0);
	atomic_init(&job.out, 0);
	plait_parallel_for(&sim->parallel, holds_range, &job, 0, sim->particles.count, HOLDS_GRAIN);
	return atomic_load_explicit(&job.strays, memory_order_relaxed);
}

/* Resting lists from the substep after the gather's. Cloth resting on a collider or on itself
 * jitters about its place: a vertex that moved down at the gather's substep moves back up in the
 * next, a guard or more off the path that went on down, and so do hundreds of its neighbours; the
 * list was then gathered again at every substep (performance.md, session 35). A list that serves
 * on holds the pairs that can come within their contact distance while every vertex keeps
 * within its guard of x_gather + a u (u its motion at the gather over the substep so far) for
 * one `a` common to all, anywhere in [-1, 1] (plait_mesh_contacts_gather: two vertices there
 * have moved relative to each other by |a| times their relative motion, which the listing
 * allows them); a short list, only for a = 0 (it lists the pairs within their contact distance
 * at the gather, and of those farther off only the ones whose paths so far may have crossed).
 * So every path may stop at such an `a` for good (path_end a, a <= 0), with nothing listed
 * again: a = 0 where the gather found the vertices, -1 where they began its substep (settled at
 * the end of the one before; the gather comes after the substep's prediction). (A list that
 * serves on stops at 1, its paths' ends, past its window anyway.) In the substep after its
 * gather, a list whose vertices keep nearer one of these than to their paths (fewer strays), or
 * a short list whose vertices keep near the first all but a few, stops every path there and
 * serves on past its window (mc->list_rests), mended around those that leave, as any resting
 * list. */
#define REST_STOPS 2
static const float rest_stop[REST_STOPS] = {0.0f, -1.0f};

typedef struct rest_job {
	const plait_sim *sim;
	const plait_mesh_contacts *mc;
	int stops;                       /* of rest_stop[]: all for a list that serves on, 1 for a short one */
	_Atomic int on_paths;            /* out of their guards of their paths, at the substep's start or now */
	_Atomic int stopped[REST_STOPS]; /* out of their guards of x_gather + rest_stop[k] u */
} rest_job;

static void rest_range(void *context, int begin, int end)
{
	rest_job *job = context;
	const plait_particles *p = &job->sim->particles;
	const plait_mesh_contacts *mc = job->mc;
	int on_paths = 0, stopped[REST_STOPS] = {0};
	for (int i = begin; i < end; ++i) {
		if (mc->object_of[i] < 0) {
			continue;
		}
		float guard_sq = mc->guard[i] * mc->guard[i];
		vec3 start = p->x_prev[i], now = p->point[i].x;
		/* Substep 1 from the gather's: its start is path_at 0, now is path_at 1. */
		on_paths += v3_length_sq(v3_sub(start, path_at(mc, i, 0.0f))) > guard_sq ||
		            v3_length_sq(v3_sub(now, path_at(mc, i, 1.0f))) > guard_sq;
		for (int k = 0; k < job->stops; ++k) {
			vec3 stop = v3_mul_add(mc->x_gather[i], rest_stop[k], mc->motion[i]);
			stopped[k] +=
			    v3_length_sq(v3_sub(start, stop)) > guard_sq || v3_length_sq(v3_sub(now, stop)) > guard_sq;
		}
	}
	atomic_fetch_add_explicit(&job->on_paths, on_paths, memory_order_relaxed);
	for (int k = 0; k < job->stops; ++k) {
		atomic_fetch_add_explicit(&job->stopped[k], stopped[k], memory_order_relaxed);
	}
}

/* At the substep after the gather's: whether the list's paths stop at one of rest_stop[] (see
 * rest_job), and if so stops them there. */
static void maybe_rest(plait_sim *sim, plait_mesh_contacts *mc)
{
	rest_job job = {.sim = sim, .mc = mc, .stops = mc->list_serves > 0 ? REST_STOPS : 1};
	atomic_init(&job.on_paths, 0);
	for (int k = 0; k < REST_STOPS; ++k) {
		atomic_init(&job.stopped[k], 0);
	}
	int count = sim->particles.count;
	plait_parallel_for(&sim->parallel, rest_range, &job, 0, count, HOLDS_GRAIN);
	int best = 0;
	for (int k = 1; k < job.stops; ++k) {
		if (atomic_load_explicit(&job.stopped[k], memory_order_relaxed) <
		    atomic_load_explicit(&job.stopped[best], memory_order_relaxed)) {
			best = k;
		}
	}
	int strays = atomic_load_explicit(&job.stopped[best], memory_order_relaxed);
	bool rests = mc->list_serves > 0 ? strays < atomic_load_explicit(&job.on_paths, memory_order_relaxed)
	                                 : strays == 0 || plait_mesh_contacts_few_strays(strays, count);
	if (rests) {
		for (int i = 0; i < count; ++i) {
			mc->path_end[i] = rest_stop[best];
		}
		mc->list_rests = true;
	}
}

static bool list_holds(plait_sim *sim, plait_mesh_contacts *mc, uint8_t *strayed, int *stray_count)
{
	mc->paths_kept = false;
	if (!mc->list_valid) {
		return false;
	}
	long since = substeps_since_gather(mc);
	if (since == 1 && !mc->rest_asked && strayed != NULL) {
		mc->rest_asked = true;
		maybe_rest(sim, mc);
	}
	if (since < 0 || since > LIST_LIFE ||
	    (mc->list_serves == 0 && !mc->list_rests && since > LIST_SUBSTEPS)) {
		return false;
	}
	const plait_particles *p = &sim->particles;
	/* A short list past its own substep is gathered again whatever this finds; only whether
	 * the paths were kept (few strays) is asked. When the vertices out of their guards are
	 * already too many for that, the cloth edges' bounds, which could only add strays, are not
	 * measured (a falling cloth's hold test spent half its time there). */
	bool answered = mc->list_serves == 0 && !mc->list_rests && since >= 1 && strayed != NULL;
	int strays = 0;
	if (answered) {
		strays = count_strays(sim, mc, strayed, since);
		if (strays > 0 && !plait_mesh_contacts_few_strays(strays, p->count)) {
			if (stray_count != NULL) {
				*stray_count = strays;
			}
			return false;
		}
	}
	if (mc->features != NULL && !plait_mesh_contacts_cloth_edges_within_bounds(sim, mc)) {
		/* D of the colliders' corners and edges left out no longer holds for some elements:
		 * their vertices (and their neighbours', whose D reads their bound) strayed too. */
		if (strayed == NULL) {
			return false;
		}
		strays += plait_mesh_contacts_mark_outgrown(sim, mc, strayed);
	}
	/* Each vertex alone, on the workers; the count is a sum, the same in any order. (Counted
	 * above already for a short list past its substep: the outgrown edges' vertices marked
	 * since are newly flagged ones, and the two counts are of different vertices.) */
	holds_job job = {.sim = sim, .mc = mc, .strayed = strayed, .since = since};
	atomic_init(&job.strays, 0);
	atomic_init(&job.movable, 0);
	atomic_init(&job.out, 0);
	if (!answered) {
		plait_parallel_for(&sim->parallel, holds_range, &job, 0, p->count, HOLDS_GRAIN);
		if (atomic_load_explicit(&job.out, memory_order_relaxed)) {
			return false;
		}
		strays += atomic_load_explicit(&job.strays, memory_order_relaxed);
	}
	if (stray_count != NULL) {
		*stray_count = strays;
	}
	/* The paths held (as far as a list that served on would need), but a short list does not
	 * reach past its own substep. */
	mc->paths_kept = strays == 0 || plait_mesh_contacts_few_strays(strays, p->count);
	/* A list that serves on keeps serving past its window while its vertices rest at their
	 * paths' ends (path_at), and is mended around those that leave them: a few of the vertices
	 * that can move. (Counted among all, a small cloth moving beside a large mesh collider's
	 * still vertices would be mended around whole at every substep, which costs more than
	 * gathering it again.) */
	if (past_window(mc) && strays > 0 &&
	    !plait_mesh_contacts_few_strays(strays, atomic_load_explicit(&job.movable, memory_order_relaxed))) {
		return false;
	}
	return mc->list_serves > 0 || mc->list_rests || since <= 0;
}

bool plait_mesh_contacts_list_covers(plait_sim *sim, plait_mesh_contacts *mc)
{
	return list_holds(sim, mc, NULL, NULL);
}

bool plait_mesh_contacts_list_covers_except(plait_sim *sim, plait_mesh_contacts *mc, uint8_t *strayed,
                                            int *stray_count)
{
	return list_holds(sim, mc, strayed, stray_count);
}

int plait_mesh_contacts_mark_elements(plait_mesh_contacts *mc)
{
	int marked = 0;
	for (int e = 0; e < mc->element_count; ++e) {
		const element *el = &mc->elements[e];
		uint8_t any = 0;
		for (int k = 0; k < el->size; ++k) {
			any |= mc->around[el->v[k]];
		}
		mc->element_around[e] = any;
		marked += any;
	}
	return marked;
}

/* Before the first mending, the element pairs it is guessed to meet per element around a
 * strayed vertex. */
#define MEND_FIRST_GUESS 16.0f
/* What a gather costs beyond a mending, in element pairs per element: fitting the flat
 * patches and walking the trees' nodes. In hang-self --stiff falling free (37,000 elements) a
 * gather that met no pair took 3.3 ms and a mending around 2 vertices 1.85 ms; a mending
 * spent about 170 ns an element pair it met. */
#define GATHER_OVERHEAD 0.25f

bool plait_mesh_contacts_mending_pays(plait_mesh_contacts *mc)
{
	float per_element = mc->mend_met_per_element > 0.0f ? mc->mend_met_per_element : MEND_FIRST_GUESS;
	float expected = per_element * (float)plait_mesh_contacts_mark_elements(mc);
	return expected <= (float)mc->gather_met + GATHER_OVERHEAD * (float)mc->element_count;
}

/* An element pair met by a query around a flagged element: visited once, from the lower when
 * both are flagged, in element order (the objects' order). */
typedef struct around_query {
	void *context;
	const plait_mesh_contacts *mc;
	int element; /* global */
	int first;   /* the queried object's first element */
	int flat;    /* the flat patch the element lies in (mc->around_flat, its own object), or -1 */
	plait_element_pair_visitor *visit;
} around_query;

static void visit_around(int local, void *context)
{
	const around_query *query = context;
	int e = query->element, f = query->first + local;
	if (f == e || (query->mc->element_around[f] && f < e)) {
		return;
	}
	if (query->flat >= 0 && query->mc->element_flat[f] == query->flat) {
		return; /* within a patch that cannot touch itself (mc->around_flat) */
	}
	query->visit(e < f ? e : f, e < f ? f : e, query->context);
}

void plait_mesh_contacts_query_around_element(const plait_sim *sim, const plait_mesh_contacts *mc, int e,
                                              bool with_allowance, plait_element_pair_visitor *visit,
                                              void *context)
{
	int a = 0;
	while (a + 1 < mc->object_count && e >= mc->objects[a + 1].first) {
		++a; /* objects hold consecutive runs of elements, in order */
	}
	const collision_object *oa = &mc->objects[a];
	for (int b = 0; b < mc->object_count; ++b) {
		bool meet =
		    b == a ? oa->self : plait_mesh_contacts_objects_meet(sim, mc, a < b ? a : b, a < b ? b : a);
		if (!meet) {
			continue;
		}
		const collision_object *ob = &mc->objects[b];
		/* Past the list's window the boxes are in place, not relative to their objects
		 * (path_box_range): no allowance between objects. */
		vec3 margin = with_allowance && !past_window(mc) && b != a ? mc->allowance[a * mc->object_count + b]
		                                                           : v3(0.0f, 0.0f, 0.0f);
		int flat = mc->around_flat && b == a ? mc->element_flat[e] : -1;
		around_query query = {context, mc, e, ob->first, flat, visit};
		plait_element_tree_query(&ob->tree, mc->lower + ob->first, mc->upper + ob->first, mc->lower[e],
		                         mc->upper[e], margin, visit_around, &query);
	}
}

void plait_mesh_contacts_query_around(const plait_sim *sim, const plait_mesh_contacts *mc,
                                      bool with_allowance, plait_element_pair_visitor *visit, void *context)
{
	for (int e = 0; e < mc->element_count; ++e) {
		if (mc->element_around[e]) {
			plait_mesh_contacts_query_around_element(sim, mc, e, with_allowance, visit, context);
		}
	}
}

/* The strayed vertices take the paths they are on now (their motion over this substep so
 * far, continued), written back to the gather's substep so that every vertex's path keeps one
 * form (list_holds), with new guards. The pairs with one of them leave the list, and the
 * elements with one are queried against the trees: their boxes from their new paths, the
 * others' from the gather's (their paths), and each primitive pair with a strayed vertex is
 * listed as at a gather (with twice the guards: the others may be a guard off their paths
 * already). A pair of two vertices that kept to their paths is as the gather left it. */
void plait_mesh_contacts_relist_around(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_particles *p = &sim->particles;
	float since = (float)substeps_since_gather(mc), bend = path_bend(sim);
	bool stop = past_window(mc);
	for (int i = 0; i < p->count; ++i) {
		if (mc->around[i]) {
			mc->motion[i] = v3_sub(p->point[i].x, p->x_prev[i]);
			mc->x_gather[i] = v3_mul_add(p->point[i].x, -since, mc->motion[i]);
			/* Past the list's window the others' paths have stopped, and so does this one,
			 * where it is now: its listing still covers the motion of this substep. */
			mc->path_end[i] = stop ? since : (float)LIST_SUBSTEPS;
			mc->guard[i] = path_guard(sim, mc, i, bend);
		}
	}
	/* The pairs kept keep the plan's order and their groups (mesh_contact_plan.c), when the list
	 * had a plan. */
	bool groups = mc->plan_list == mc->list_changes && mc->planned > 0;
	int kept = 0, planned = 0;
	for (int k = 0; k < mc->pair_count; ++k) {
		const contact_pair *pair = &mc->pairs[k];
		uint8_t any = 0;
		for (int m = 0; m < pair_size[pair->type]; ++m) {
			any |= mc->around[pair->v[m]];
		}
		if (any && plait_mesh_contacts_has_state(mc, pair)) {
			plait_mesh_contacts_carry(sim, mc, pair); /* listed again below, most of them */
		}
		if (!any) {
			if (kept != k) { /* most pairs stay where they are */
				mc->pairs[kept] = *pair;
				if (groups && k < mc->planned) {
					mc->pair_group[kept] = mc->pair_group[k];
				}
			}
			planned += k < mc->planned;
			kept += 1;
		}
	}
	mc->pair_count = kept;
	mc->list_changes += 1;
	mc->planned = groups ? planned : 0;
	mc->plan_kept_list = groups ? mc->list_changes : -1;
	mc->out_of_memory = false;
	fit_boxes(sim, mc, false, 0.0f, false);
	if (mc->features != NULL) {
		plait_mesh_contacts_rebound_cloth_edges(sim, mc);
	}
	int marked = plait_mesh_contacts_mark_elements(mc);
	/* A gather passes over the pairs within a flat patch: so does the mending of a resting list
	 * (past its window), within a patch the gather passed over that the last substep's failsafe
	 * found still flat along that substep's paths (a guess, as the gather's is: this substep's
	 * failsafe checks it along its own). Not within the window, where the cloth still moves:
	 * there it changed the mesh arm's course into a squeeze the failsafe cannot undo
	 * (performance.md, session 26). */
	mc->around_flat = mc->element_flat_serial == mc->substep_serial - 1 && stop;
	pair_pass pass = {.sim = sim,
	                  .mc = mc,
	                  .stage = STAGE_GATHER,
	                  .around_only = true,
	                  .out_pairs = &mc->pairs,
	                  .out_count = &mc->pair_count,
	                  .out_capacity = &mc->pair_capacity};
	if (!(sim->parallel.worker_count > 1 && plait_mesh_contacts_relist_on_workers(sim, mc, &pass))) {
		object_pass objects = {&pass, 0, 0};
		plait_mesh_contacts_query_around(sim, mc, true, plait_mesh_contacts_visit_object_elements, &objects);
	}
	mc->around_flat = false;
	if (marked > 0) {
		mc->mend_met_per_element = (float)pass.met / (float)marked;
	}
	mc->listing_met += pass.met;
	mc->list_valid = !mc->out_of_memory;
	plait_mesh_contacts_drop_carried(mc);
}

long plait_mesh_contacts_listings(const plait_sim *sim)
{
	const plait_mesh_contacts *mc = sim->mesh_contacts;
	return mc != NULL ? mc->listings : 0;
}

void plait_mesh_contacts_flat_counts(const plait_sim *sim, long *culled, long *unflattened)
{
	const plait_mesh_contacts *mc = sim->mesh_contacts;
	*culled = mc != NULL ? mc->culled_patches : 0;
	*unflattened = mc != NULL ? mc->unflattened : 0;
}
