/* The collision elements of mesh contacts: each colliding cloth triangle, curve segment and
 * loose particle, grouped into objects with a tree each; the rest pairs and excluded element
 * pairs of self-colliding objects; and the scratch sized by the particles. */
#include "dynamics/mesh_contact_internal.h"

#include <stdlib.h>
#include <string.h>

void plait_mesh_contacts_free_elements(plait_mesh_contacts *mc, const plait_allocator *a)
{
	plait_free(a, mc->elements);
	plait_free(a, mc->element_reach);
	plait_free(a, mc->element_guard);
	mc->element_guard = NULL;
	plait_free(a, mc->element_motion);
	mc->element_motion = NULL;
	plait_free(a, mc->element_spread);
	mc->element_spread = NULL;
	plait_free(a, mc->element_substep_motion);
	mc->element_substep_motion = NULL;
	plait_free(a, mc->element_substep_spread);
	mc->element_substep_spread = NULL;
	plait_free(a, mc->element_around);
	mc->element_around = NULL;
	plait_free(a, mc->element_flat);
	mc->element_flat = NULL;
	plait_free(a, mc->shapes);
	mc->shapes = NULL;
	plait_free(a, mc->lower);
	plait_free(a, mc->upper);
	for (int k = 0; k < mc->object_count; ++k) {
		plait_element_tree_destroy(&mc->objects[k].tree, a);
		plait_flat_patches_destroy(&mc->objects[k].patches, a);
		plait_mesh_contacts_free_cross(&mc->objects[k], a);
		plait_free(a, mc->objects[k].culled);
		plait_free(a, mc->objects[k].culled_axis);
		plait_free(a, mc->objects[k].node_floor);
		plait_free(a, mc->objects[k].node_ceiling);
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
	plait_free(a, mc->near_start);
	plait_free(a, mc->near_list);
	plait_free(a, mc->rest_pairs);
	mc->rest_pairs = NULL;
	mc->rest_count = mc->rest_capacity = 0;
	plait_free(a, mc->rest_groups);
	mc->rest_groups = NULL;
	mc->rest_group_count = mc->rest_group_capacity = 0;
	mc->near_start = NULL;
	mc->near_list = NULL;
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

/* A self-colliding cloth's flat patches (collision/flat_patches.h), from its tree. */
static bool build_patches(plait_sim *sim, plait_mesh_contacts *mc, collision_object *o)
{
	const plait_allocator *a = &sim->allocator;
	int(*triangles)[3] = plait_alloc_zero(a, (size_t)o->count, sizeof *triangles);
	if (triangles == NULL) {
		return false;
	}
	for (int t = 0; t < o->count; ++t) {
		memcpy(triangles[t], mc->elements[o->first + t].v, sizeof triangles[t]);
	}
	bool ok = plait_flat_patches_build(&o->patches, a, &o->tree, (const int(*)[3])triangles, o->count,
	                                   sim->particles.x_start);
	ok = ok && plait_mesh_contacts_build_cross(sim, o, (const int(*)[3])triangles);
	plait_free(a, triangles);
	if (ok && o->tree.node_count > 0) {
		o->culled = plait_alloc_zero(a, (size_t)o->tree.node_count, sizeof(uint8_t));
		o->culled_axis = plait_alloc_zero(a, (size_t)o->tree.node_count, sizeof(vec3));
		ok = o->culled != NULL && o->culled_axis != NULL;
	}
	return ok;
}

bool plait_mesh_contacts_build_elements(plait_sim *sim, plait_mesh_contacts *mc)
{
	const plait_allocator *a = &sim->allocator;
	plait_particles *p = &sim->particles;
	plait_mesh_contacts_free_elements(mc, a);
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
	/* One object that does not collide with itself meets nothing here: its contacts with
	 * colliders are the particle pass's (contact.c). The objects are counted first, as the
	 * loops below make them, so that a lone cloth costs no elements (sorting a 512 x 512
	 * cloth's edges was most of its first frame). */
	int planned = 0, last_material = -1;
	bool only_self = false;
	for (int s = 0; s < sim->surface_count; ++s) {
		if (material_collides(sim, sim->surfaces[s].material)) {
			planned += 1;
			last_material = sim->surfaces[s].material;
			only_self = sim->materials[last_material].self_collide;
		}
	}
	for (int c = 0; c < sim->chain_count; ++c) {
		if (material_collides(sim, sim->chains[c].material) && sim->chains[c].count >= 2) {
			planned += 1;
			last_material = sim->chains[c].material;
			only_self = sim->materials[last_material].self_collide;
		}
	}
	for (int i = 0; i < p->count && planned < 2; ++i) {
		if (!in_surface[i] && (p->flags[i] & PLAIT_PARTICLE_COLLIDE) &&
		    material_collides(sim, p->material[i]) && (planned == 0 || p->material[i] != last_material)) {
			planned += 1;
			last_material = p->material[i];
			only_self = false; /* loose points never meet their own kind here */
		}
	}
	if (!(planned > 1 || (planned == 1 && only_self))) {
		plait_free(a, in_surface);
		return true;
	}
	int count = triangles + segments + points;
	mc->elements = plait_alloc_zero(a, (size_t)count, sizeof *mc->elements);
	mc->element_reach = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->element_guard = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->element_motion = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->element_spread = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->element_substep_motion = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->element_substep_spread = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->element_around = plait_alloc_zero(a, (size_t)count, sizeof(uint8_t));
	mc->element_flat = plait_alloc_zero(a, (size_t)count, sizeof(int));
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
	          mc->element_motion != NULL && mc->element_spread != NULL &&
	          mc->element_substep_motion != NULL && mc->element_substep_spread != NULL &&
	          mc->element_around != NULL && mc->element_flat != NULL && mc->shapes != NULL &&
	          mc->lower != NULL && mc->upper != NULL && edges != NULL && owned != NULL && mc->objects != NULL;
	if (ok) {
		int e = 0;
		for (int s = 0; s < sim->surface_count; ++s) {
			const plait_surface *surface = &sim->surfaces[s];
			if (!material_collides(sim, surface->material)) {
				continue;
			}
			const plait_material *m = &sim->materials[surface->material];
			mc->objects[mc->object_count++] = (collision_object){.first = e,
			                                                     .count = surface->shape->triangle_count,
			                                                     .material = surface->material,
			                                                     .self = m->self_collide,
			                                                     .features = -1};
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
			mc->objects[mc->object_count++] = (collision_object){.first = e,
			                                                     .count = chain->count - 1,
			                                                     .material = chain->material,
			                                                     .self = m->self_collide,
			                                                     .features = -1};
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
					    (collision_object){.first = e, .material = p->material[i], .features = -1};
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
		ok = plait_mesh_contacts_build_collider_features(sim, mc, edges, edge_count);
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
			if (ok && o->self && mc->elements[o->first].size == 3) {
				ok = build_patches(sim, mc, o);
			}
		}
		ok = ok && plait_mesh_contacts_build_node_floors(sim, mc);
		ok = ok && build_rest_pairs(sim, mc);
		int objects = mc->object_count;
		mc->shift = plait_alloc_zero(a, (size_t)objects, sizeof(vec3));
		mc->allowance = plait_alloc_zero(a, (size_t)(objects * objects), sizeof(vec3));
		mc->object_counts = plait_alloc_zero(a, (size_t)objects, sizeof(int));
		ok = ok && mc->shift != NULL && mc->allowance != NULL && mc->object_counts != NULL;
	}
	plait_free(a, edges);
	plait_free(a, owned);
	plait_free(a, in_surface);
	if (!ok) {
		plait_mesh_contacts_free_elements(mc, a);
		return false;
	}
	mc->active = active;
	if (!mc->active) {
		plait_mesh_contacts_free_elements(mc, a);
	}
	return true;
}

bool plait_mesh_contacts_reserve_particles(plait_sim *sim, plait_mesh_contacts *mc)
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
	plait_free(a, mc->sweep_end);
	plait_free(a, mc->sweep_motion);
	plait_free(a, mc->path_lower);
	plait_free(a, mc->path_upper);
	plait_free(a, mc->motion);
	plait_free(a, mc->path_end);
	plait_free(a, mc->guard);
	plait_free(a, mc->object_of);
	plait_free(a, mc->around);
	plait_free(a, mc->restitution_sum);
	plait_free(a, mc->restitution_weight);
	plait_free(a, mc->tangled);
	plait_free(a, mc->carry_head);
	mc->carried_count = 0;
	mc->carry_head = plait_alloc_zero(a, (size_t)count, sizeof(int));
	mc->tangled = plait_alloc_zero(a, (size_t)count, sizeof(uint8_t));
	mc->tangle_count = 0;
	mc->tangle_push_count = 0;
	mc->ever_tangled = false;
	mc->tangle_check_due = true; /* particles came */
	mc->restitution_sum = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->restitution_weight = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->around = plait_alloc_zero(a, (size_t)count, sizeof(uint8_t));
	mc->x_gather = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->sweep_end = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->sweep_motion = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->path_lower = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->path_upper = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->motion = plait_alloc_zero(a, (size_t)count, sizeof(vec3));
	mc->path_end = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->guard = plait_alloc_zero(a, (size_t)count, sizeof(float));
	mc->object_of = plait_alloc_zero(a, (size_t)count, sizeof(int));
	mc->list_valid = false;
	mc->zone_parent = plait_alloc_zero(a, (size_t)count, sizeof(int));
	mc->touched = plait_alloc_zero(a, (size_t)count, sizeof(int));
	mc->members = plait_alloc_zero(a, (size_t)count, sizeof *mc->members);
	if (mc->zone_parent == NULL || mc->touched == NULL || mc->members == NULL || mc->x_gather == NULL ||
	    mc->sweep_end == NULL || mc->sweep_motion == NULL || mc->path_lower == NULL ||
	    mc->path_upper == NULL || mc->motion == NULL || mc->path_end == NULL || mc->guard == NULL ||
	    mc->object_of == NULL || mc->around == NULL || mc->restitution_sum == NULL ||
	    mc->restitution_weight == NULL || mc->tangled == NULL || mc->carry_head == NULL) {
		mc->particle_capacity = 0;
		return false;
	}
	for (int i = 0; i < count; ++i) {
		mc->zone_parent[i] = -1;
		mc->carry_head[i] = -1;
	}
	mc->particle_capacity = count;
	return true;
}

static int compare_near_elements(const void *a, const void *b)
{
	const near_element *x = a, *y = b;
	return x->element < y->element ? -1 : x->element > y->element;
}

/* The rest pairs and the element pairs that own them (the near lists) of every self-colliding
 * object, from the start positions: element boxes grown so that primitives within their
 * contact distance at the start overlap. */
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
		plait_element_tree_pairs(&o->tree, mc->lower + o->first, mc->upper + o->first,
		                         plait_mesh_contacts_visit_object_elements, &self);
	}
	mc->near_start = plait_alloc_zero(a, (size_t)mc->element_count + 1, sizeof(int));
	mc->near_list =
	    plait_alloc_zero(a, (size_t)(pass.near_count > 0 ? pass.near_count : 1), sizeof *mc->near_list);
	bool ok = !pass.failed && mc->near_start != NULL && mc->near_list != NULL;
	if (ok && pass.near_count > 0) {
		/* Bucketed by the lower element (a counting sort), then each element's few sorted by
		 * the other: a sort of them all took most of a large cloth's set-up. */
		for (int k = 0; k < pass.near_count; ++k) {
			mc->near_start[pass.near[k].a + 1] += 1;
		}
		for (int e = 0; e < mc->element_count; ++e) {
			mc->near_start[e + 1] += mc->near_start[e];
		}
		int *next = mc->near_start; /* filled, then shifted back below */
		for (int k = 0; k < pass.near_count; ++k) {
			mc->near_list[next[pass.near[k].a]++] = (near_element){pass.near[k].b, pass.near[k].rest_slots};
		}
		for (int e = mc->element_count; e > 0; --e) {
			mc->near_start[e] = mc->near_start[e - 1];
		}
		mc->near_start[0] = 0;
		for (int e = 0; e < mc->element_count; ++e) {
			near_element *run = mc->near_list + mc->near_start[e];
			int count = mc->near_start[e + 1] - mc->near_start[e];
			if (count > 32) { /* a crumpled start can crowd an element */
				qsort(run, (size_t)count, sizeof *run, compare_near_elements);
				continue;
			}
			for (int i = 1; i < count; ++i) {
				near_element x = run[i];
				int j = i;
				while (j > 0 && run[j - 1].element > x.element) {
					run[j] = run[j - 1];
					--j;
				}
				run[j] = x;
			}
		}
	}
	plait_free(a, pass.near);
	return ok;
}
