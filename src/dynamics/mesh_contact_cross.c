/* Cross patches: a second cover of a self-colliding cloth by flat patches, whose seams run
 * across the first one's.
 *
 * A gather passes over the pairs within a flat patch of the object's tree (flat_patches.h).
 * On a cloth that is smooth but curved (draped over a ball, a sleeve round an arm) what is left
 * is the seams: the pairs of triangles on either side of the border between two flat nodes
 * whose union is not flat. They are neighbours on the surface, and a patch that holds both is
 * usually flat, only not one of the tree's. So such a cloth has a second tree, built the same
 * way from its rest shape turned 45 degrees about the rest shape's thinnest axis: its median
 * splits run across the first tree's, and most of the first tree's seams lie inside one of its
 * flat patches (hang-self --stiff: two thirds of the element pairs its gathers met).
 *
 * At a gather the second tree's patches are fitted to the gather's paths (the triangles'
 * normals found once for both trees) and the largest flat ones found top down; an element pair
 * met within one such patch is passed over, and the patch is marked: the failsafe checks it
 * along the substep's own paths and sweeps its pairs if it did not keep flat, as it does the
 * first tree's (mesh_contact_failsafe.c). Marks are set from the workers' pieces side by side:
 * a relaxed atomic store of the same value, and which patches are marked does not depend on
 * how the traversal was shared out.
 *
 * Fitting them costs about what passing over one element pair saves, per triangle; where they
 * pass over fewer pairs than the cloth has triangles (a cloth lying flat, a pile whose pairs are
 * between sheets) they are left off, and tried again every CROSS_RETRY gathers. The counts are
 * of element pairs, not times, so the choice is the same for any thread count.
 */
#include "dynamics/mesh_contact_internal.h"

#include <stdatomic.h>

void plait_mesh_contacts_free_cross(collision_object *o, const plait_allocator *allocator)
{
	plait_element_tree_destroy(&o->cross_tree, allocator);
	plait_flat_patches_destroy(&o->cross, allocator);
	plait_free(allocator, o->cross_of);
	plait_free(allocator, (void *)o->cross_culled);
	plait_free(allocator, o->cross_axis);
	plait_free(allocator, o->normals);
	o->normals = NULL;
	o->cross_of = NULL;
	o->cross_culled = NULL;
	o->cross_axis = NULL;
}

/* The first gather fits them (see plait_mesh_contacts_cross_pays). */
#define CROSS_RETRY_FIRST 1000

bool plait_mesh_contacts_build_cross(plait_sim *sim, collision_object *o, const int (*triangles)[3])
{
	const plait_allocator *a = &sim->allocator;
	const vec3 *rest = sim->particles.x_start;
	vec3 *centres = plait_alloc_zero(a, (size_t)o->count, sizeof *centres);
	if (centres == NULL) {
		return false;
	}
	/* The rest shape's box: the turn is about its thinnest axis (a flat sheet's normal), which
	 * moves the splits along the other two. */
	vec3 lower = rest[triangles[0][0]], upper = lower;
	for (int t = 0; t < o->count; ++t) {
		for (int k = 0; k < 3; ++k) {
			lower = v3_min(lower, rest[triangles[t][k]]);
			upper = v3_max(upper, rest[triangles[t][k]]);
		}
	}
	vec3 extent = v3_sub(upper, lower);
	int thin = extent.x <= extent.y && extent.x <= extent.z ? 0 : extent.y <= extent.z ? 1 : 2;
	const float half = 0.70710678f; /* cos 45 = sin 45 degrees */
	for (int t = 0; t < o->count; ++t) {
		vec3 c = v3_scale(v3_add(rest[triangles[t][0]], v3_add(rest[triangles[t][1]], rest[triangles[t][2]])),
		                  1.0f / 3.0f);
		float u = thin == 0 ? c.y : c.x, w = thin == 2 ? c.y : c.z;
		float turned_u = half * (u - w), turned_w = half * (u + w);
		centres[t] = thin == 0   ? v3(c.x, turned_u, turned_w)
		             : thin == 1 ? v3(turned_u, c.y, turned_w)
		                         : v3(turned_u, turned_w, c.z);
	}
	bool ok = plait_element_tree_build(&o->cross_tree, a, centres, o->count);
	plait_free(a, centres);
	ok = ok && plait_flat_patches_build(&o->cross, a, &o->cross_tree, triangles, o->count, rest);
	if (ok) {
		o->cross_of = plait_alloc_zero(a, (size_t)o->count, sizeof(int));
		o->cross_culled = plait_alloc_zero(a, (size_t)o->cross_tree.node_count, sizeof(uint8_t));
		o->cross_axis = plait_alloc_zero(a, (size_t)o->cross_tree.node_count, sizeof(vec3));
		o->normals = plait_alloc_zero(a, (size_t)o->count, sizeof(plait_triangle_normals));
		ok = o->cross_of != NULL && o->cross_culled != NULL && o->cross_axis != NULL && o->normals != NULL;
	}
	if (!ok) {
		plait_mesh_contacts_free_cross(o, a);
		return false;
	}
	o->cross_fitted = false;
	o->cross_skipped = 0;
	o->cross_idle = CROSS_RETRY_FIRST;
	return true;
}

/* The largest flat cross patches along the paths, top down: cross_of per element. */
static void find_flat(collision_object *o, const plait_patch_paths *paths)
{
	const plait_flat_patches *fp = &o->cross;
	const plait_element_tree *tree = &o->cross_tree;
	int stack[2 * 64], depth = 0;
	stack[depth++] = 0;
	while (depth > 0) {
		int n = stack[--depth];
		const plait_tree_node *node = &tree->nodes[n];
		vec3 axis;
		bool flat = plait_flat_patches_flat(fp, n, paths, &axis);
		if (flat) {
			o->cross_axis[n] = axis;
		}
		if (flat || node->count > 0 || depth + 2 > (int)(sizeof stack / sizeof stack[0])) {
			for (int m = fp->node_begin[n]; m < fp->node_end[n]; ++m) {
				o->cross_of[fp->order[m]] = flat ? n : -1;
			}
			continue;
		}
		stack[depth++] = node->first + 1;
		stack[depth++] = node->first;
	}
}

/* Gathers after which cross patches that did not pay are tried again. */
#define CROSS_RETRY 8

bool plait_mesh_contacts_cross_pays(collision_object *o)
{
	if (o->cross_fitted) {
		return o->cross_skipped >= o->count;
	}
	return o->cross_idle + 1 >= CROSS_RETRY;
}

void plait_mesh_contacts_count_cross(plait_mesh_contacts *mc, long skipped)
{
	long triangles = 0;
	for (int k = 0; k < mc->object_count; ++k) {
		triangles += mc->objects[k].cross_fitted ? mc->objects[k].count : 0;
	}
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		if (o->cross_fitted) {
			o->cross_skipped = (long)((double)skipped * (double)o->count / (double)triangles);
		}
	}
}

void plait_mesh_contacts_fit_cross(plait_sim *sim, collision_object *o, const plait_patch_paths *paths,
                                   bool fit)
{
	o->cross_fitted = fit;
	o->cross_idle = fit ? 0 : o->cross_idle + 1;
	for (int n = 0; n < o->cross_tree.node_count; ++n) {
		atomic_store_explicit(&o->cross_culled[n], 0, memory_order_relaxed);
	}
	if (!fit) {
		return;
	}
	plait_mesh_contacts_fit_tree_patches(sim, &o->cross, &o->cross_tree, paths);
	find_flat(o, paths);
}

bool plait_mesh_contacts_in_cross(collision_object *o, int a, int b)
{
	int c = o->cross_of[a];
	if (c < 0 || o->cross_of[b] != c) {
		return false;
	}
	if (atomic_load_explicit(&o->cross_culled[c], memory_order_relaxed) == 0) {
		atomic_store_explicit(&o->cross_culled[c], 1, memory_order_relaxed);
	}
	return true;
}

typedef struct cross_check_job {
	collision_object *object;
	const plait_patch_paths *paths;
} cross_check_job;

static void check_cross_nodes(void *context, int begin, int end)
{
	const cross_check_job *job = context;
	collision_object *o = job->object;
	for (int n = begin; n < end; ++n) {
		if (atomic_load_explicit(&o->cross_culled[n], memory_order_relaxed) == 1 &&
		    !plait_flat_patches_keeps_flat(&o->cross, n, o->cross_axis[n], job->paths)) {
			atomic_store_explicit(&o->cross_culled[n], 2, memory_order_relaxed);
		}
	}
}

#define CROSS_CHECK_GRAIN 256

bool plait_mesh_contacts_any_cross(const plait_mesh_contacts *mc)
{
	for (int k = 0; k < mc->object_count; ++k) {
		const collision_object *o = &mc->objects[k];
		for (int n = 0; o->cross_of != NULL && n < o->cross_tree.node_count; ++n) {
			if (atomic_load_explicit(&o->cross_culled[n], memory_order_relaxed) != 0) {
				return true;
			}
		}
	}
	return false;
}

void plait_mesh_contacts_check_cross(plait_sim *sim, plait_mesh_contacts *mc, const plait_patch_paths *paths)
{
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		if (o->cross_of != NULL) {
			cross_check_job job = {o, paths};
			plait_parallel_for(&sim->parallel, check_cross_nodes, &job, 0, o->cross_tree.node_count,
			                   CROSS_CHECK_GRAIN);
		}
	}
}

int plait_mesh_contacts_sweep_cross(plait_mesh_contacts *mc, pair_pass *pass)
{
	int swept = 0;
	for (int k = 0; k < mc->object_count; ++k) {
		collision_object *o = &mc->objects[k];
		bool refitted = false;
		for (int n = 0; o->cross_of != NULL && n < o->cross_tree.node_count; ++n) {
			if (atomic_load_explicit(&o->cross_culled[n], memory_order_relaxed) != 2) {
				continue;
			}
			atomic_store_explicit(&o->cross_culled[n], 1, memory_order_relaxed);
			const vec3 *lower = mc->lower + o->first, *upper = mc->upper + o->first;
			if (!refitted) {
				/* Its boxes are needed only here (rarely): from the elements' boxes around
				 * the substep's paths, fitted by the caller. */
				plait_element_tree_refit(&o->cross_tree, lower, upper);
				refitted = true;
			}
			object_pass self = {pass, o->first, o->first};
			int node[2] = {n, n};
			plait_element_tree_piece_pairs(&o->cross_tree, lower, upper, &o->cross_tree, lower, upper, true,
			                               v3(0.0f, 0.0f, 0.0f), NULL, node,
			                               plait_mesh_contacts_visit_object_elements, &self);
			swept += 1;
		}
	}
	return swept;
}
