#include "collision/mesh_shape.h"

#include "collision/axis_sort.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

#define LEAF_SIZE 4

void plait_mesh_shape_destroy(plait_mesh_shape *shape, const plait_allocator *allocator)
{
	plait_free(allocator, shape->positions);
	plait_free(allocator, shape->triangles);
	plait_free(allocator, shape->normals);
	plait_free(allocator, shape->nodes);
	plait_free(allocator, shape->triangle_order);
	plait_free(allocator, shape->slot_corners);
	plait_free(allocator, shape->slot_lower);
	plait_free(allocator, shape->slot_upper);
	plait_free(allocator, shape->start_positions);
	memset(shape, 0, sizeof *shape);
}

static void triangle_bounds(const plait_mesh_shape *shape, int t, vec3 *lower, vec3 *upper)
{
	const int *tri = shape->triangles[t];
	*lower = v3_min(shape->positions[tri[0]], v3_min(shape->positions[tri[1]], shape->positions[tri[2]]));
	*upper = v3_max(shape->positions[tri[0]], v3_max(shape->positions[tri[1]], shape->positions[tri[2]]));
	if (shape->start_positions != NULL) {
		const vec3 *start = shape->start_positions;
		*lower = v3_min(*lower, v3_min(start[tri[0]], v3_min(start[tri[1]], start[tri[2]])));
		*upper = v3_max(*upper, v3_max(start[tri[0]], v3_max(start[tri[1]], start[tri[2]])));
	}
}

/* The slots' corners and boxes, from positions (and start_positions when deforming). */
static void fill_slots(plait_mesh_shape *shape)
{
	for (int k = 0; k < shape->triangle_count; ++k) {
		int t = shape->triangle_order[k];
		const int *tri = shape->triangles[t];
		for (int c = 0; c < 3; ++c) {
			shape->slot_corners[3 * k + c] = shape->positions[tri[c]];
		}
		triangle_bounds(shape, t, &shape->slot_lower[k], &shape->slot_upper[k]);
	}
}

/* Node `node` over the triangles in [first, first + count) of the orders, and its subtree;
 * returns the next free node index. A leaf's triangles go to triangle_order in the order of
 * its parent's axis (root: as given). */
static int build_node(plait_mesh_shape *shape, const vec3 *centroid, plait_axis_orders *orders, int node,
                      int first, int count, int next_free, int parent_axis)
{
	plait_bvh_node *n = &shape->nodes[node];
	vec3 lower = {INFINITY, INFINITY, INFINITY}, upper = {-INFINITY, -INFINITY, -INFINITY};
	for (int k = first; k < first + count; ++k) {
		vec3 tl, tu;
		triangle_bounds(shape, orders->by_axis[0][k], &tl, &tu);
		lower = v3_min(lower, tl);
		upper = v3_max(upper, tu);
	}
	n->lower = lower;
	n->upper = upper;
	if (count <= LEAF_SIZE) {
		if (parent_axis >= 0) {
			memcpy(shape->triangle_order + first, orders->by_axis[parent_axis] + first,
			       sizeof(int) * (size_t)count);
		}
		n->first = first;
		n->count = count;
		return next_free;
	}
	vec3 c_lower, c_upper;
	plait_axis_orders_bounds(orders, centroid, first, count, &c_lower, &c_upper);
	vec3 extent = v3_sub(c_upper, c_lower);
	int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
	int half = count / 2;
	int left = next_free;
	n->first = left;
	n->count = 0;
	next_free += 2;
	plait_axis_orders_split(orders, first, count, axis, half);
	next_free = build_node(shape, centroid, orders, left, first, half, next_free, axis);
	return build_node(shape, centroid, orders, left + 1, first + half, count - half, next_free, axis);
}

plait_result plait_mesh_shape_build(plait_mesh_shape *shape, const plait_allocator *allocator,
                                    const plait_mesh_def *mesh, plait_error *error)
{
	memset(shape, 0, sizeof *shape);
	if (mesh->vertex_count < 3 || mesh->face_count < 1 || mesh->positions == NULL ||
	    mesh->face_sizes == NULL || mesh->face_indices == NULL) {
		return plait_error_set(error, PLAIT_ERROR_INVALID_MESH, "a mesh collider needs vertices and faces");
	}
	int triangles = 0, index = 0;
	for (int f = 0; f < mesh->face_count; ++f) {
		int size = mesh->face_sizes[f];
		if (size < 3) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_MESH,
			                       "face %d has %d vertices; a face needs at least 3", f, size);
		}
		for (int k = 0; k < size; ++k) {
			int v = mesh->face_indices[index + k];
			if (v < 0 || v >= mesh->vertex_count) {
				return plait_error_set(error, PLAIT_ERROR_INVALID_MESH,
				                       "face %d uses vertex index %d, outside 0..%d", f, v,
				                       mesh->vertex_count - 1);
			}
		}
		index += size;
		triangles += size - 2;
	}
	for (int v = 0; v < mesh->vertex_count; ++v) {
		if (!v3_is_finite(mesh->positions[v])) {
			return plait_error_set(error, PLAIT_ERROR_INVALID_MESH, "mesh vertex %d is not finite", v);
		}
	}
	shape->vertex_count = mesh->vertex_count;
	shape->triangle_count = triangles;
	shape->node_count = 2 * triangles; /* a binary tree with leaves of >= 1 triangle */
	shape->positions = plait_alloc(allocator, sizeof(vec3) * (size_t)mesh->vertex_count);
	shape->triangles = plait_alloc(allocator, sizeof *shape->triangles * (size_t)triangles);
	shape->normals = plait_alloc(allocator, sizeof(vec3) * (size_t)triangles);
	shape->nodes = plait_alloc_zero(allocator, (size_t)shape->node_count, sizeof *shape->nodes);
	shape->triangle_order = plait_alloc(allocator, sizeof(int) * (size_t)triangles);
	shape->slot_corners = plait_alloc(allocator, sizeof(vec3) * 3 * (size_t)triangles);
	shape->slot_lower = plait_alloc(allocator, sizeof(vec3) * (size_t)triangles);
	shape->slot_upper = plait_alloc(allocator, sizeof(vec3) * (size_t)triangles);
	vec3 *centroid = plait_alloc(allocator, sizeof(vec3) * (size_t)triangles);
	if (!shape->positions || !shape->triangles || !shape->normals || !shape->nodes ||
	    !shape->triangle_order || !shape->slot_corners || !shape->slot_lower || !shape->slot_upper ||
	    !centroid) {
		plait_free(allocator, centroid);
		plait_mesh_shape_destroy(shape, allocator);
		return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory building a mesh collider");
	}
	memcpy(shape->positions, mesh->positions, sizeof(vec3) * (size_t)mesh->vertex_count);
	int t = 0;
	index = 0;
	for (int f = 0; f < mesh->face_count; ++f) {
		const int *face = mesh->face_indices + index;
		for (int k = 1; k + 1 < mesh->face_sizes[f]; ++k, ++t) {
			int tri[3] = {face[0], face[k], face[k + 1]};
			memcpy(shape->triangles[t], tri, sizeof tri);
			vec3 a = shape->positions[tri[0]], b = shape->positions[tri[1]], c = shape->positions[tri[2]];
			shape->normals[t] = v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
			centroid[t] = v3_scale(v3_add(v3_add(a, b), c), 1.0f / 3.0f);
			shape->triangle_order[t] = t;
		}
		index += mesh->face_sizes[f];
	}
	plait_axis_orders orders;
	if (!plait_axis_orders_make(&orders, allocator, centroid, triangles)) {
		plait_free(allocator, centroid);
		plait_mesh_shape_destroy(shape, allocator);
		return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory building a mesh collider");
	}
	int used = build_node(shape, centroid, &orders, 0, 0, triangles, 1, -1);
	shape->node_count = used;
	fill_slots(shape);
	plait_axis_orders_free(&orders, allocator);
	plait_free(allocator, centroid);
	shape->closed = plait_triangles_are_closed((const int(*)[3])shape->triangles, triangles, allocator);
	if (shape->closed) {
		double volume = 0.0;
		for (int k = 0; k < triangles; ++k) {
			vec3 a = shape->positions[shape->triangles[k][0]], b = shape->positions[shape->triangles[k][1]],
			     c = shape->positions[shape->triangles[k][2]];
			volume += (double)v3_dot(a, v3_cross(b, c));
		}
		shape->outward = volume >= 0.0 ? 1.0f : -1.0f;
	}
	return PLAIT_OK;
}

static int compare_edge_keys(const void *a, const void *b)
{
	uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
	return (x > y) - (x < y);
}

bool plait_triangles_are_closed(const int (*triangles)[3], int triangle_count,
                                const plait_allocator *allocator)
{
	if (triangle_count <= 0) {
		return false;
	}
	size_t edge_count = 3 * (size_t)triangle_count;
	uint64_t *edges = plait_alloc(allocator, sizeof *edges * edge_count);
	if (edges == NULL) {
		return false; /* unknown: treated as open, which only skips the trapped check */
	}
	for (int t = 0; t < triangle_count; ++t) {
		for (int k = 0; k < 3; ++k) {
			uint32_t i = (uint32_t)triangles[t][k], j = (uint32_t)triangles[t][(k + 1) % 3];
			edges[3 * (size_t)t + (size_t)k] = i < j ? (uint64_t)i << 32 | j : (uint64_t)j << 32 | i;
		}
	}
	qsort(edges, edge_count, sizeof *edges, compare_edge_keys);
	bool closed = true;
	for (size_t e = 0; closed && e < edge_count;) {
		size_t run = 1;
		while (e + run < edge_count && edges[e + run] == edges[e]) {
			++run;
		}
		closed = run == 2;
		e += run;
	}
	plait_free(allocator, edges);
	return closed;
}

plait_result plait_mesh_shape_make_deforming(plait_mesh_shape *shape, const plait_allocator *allocator,
                                             plait_error *error)
{
	shape->start_positions = plait_alloc(allocator, sizeof(vec3) * (size_t)shape->vertex_count);
	if (shape->start_positions == NULL) {
		return plait_error_set(error, PLAIT_ERROR_OUT_OF_MEMORY, "out of memory building a mesh collider");
	}
	memcpy(shape->start_positions, shape->positions, sizeof(vec3) * (size_t)shape->vertex_count);
	return PLAIT_OK;
}

/* Exact at both ends (t = 0 gives a, t = 1 gives b), so a frame ends exactly on its target. */
static vec3 lerp_exact(vec3 a, vec3 b, float t)
{
	float s = 1.0f - t;
	return v3(s * a.x + t * b.x, s * a.y + t * b.y, s * a.z + t * b.z);
}

void plait_mesh_shape_deform(plait_mesh_shape *shape, const vec3 *from, const vec3 *to, float t0, float t1)
{
	float largest_sq = 0.0f;
	for (int v = 0; v < shape->vertex_count; ++v) {
		vec3 start = lerp_exact(from[v], to[v], t0), end = lerp_exact(from[v], to[v], t1);
		shape->start_positions[v] = start;
		shape->positions[v] = end;
		largest_sq = plait_maxf(largest_sq, v3_length_sq(v3_sub(end, start)));
	}
	shape->largest_move = sqrtf(largest_sq);
	for (int t = 0; t < shape->triangle_count; ++t) {
		const int *tri = shape->triangles[t];
		vec3 a = shape->positions[tri[0]], b = shape->positions[tri[1]], c = shape->positions[tri[2]];
		shape->normals[t] = v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
	}
	fill_slots(shape);
	/* Children always come after their parent (build_node), so one backward pass refits. */
	for (int n = shape->node_count - 1; n >= 0; --n) {
		plait_bvh_node *node = &shape->nodes[n];
		if (node->count > 0) {
			vec3 lower = {INFINITY, INFINITY, INFINITY}, upper = {-INFINITY, -INFINITY, -INFINITY};
			for (int k = node->first; k < node->first + node->count; ++k) {
				lower = v3_min(lower, shape->slot_lower[k]);
				upper = v3_max(upper, shape->slot_upper[k]);
			}
			node->lower = lower;
			node->upper = upper;
		} else {
			const plait_bvh_node *left = &shape->nodes[node->first], *right = &shape->nodes[node->first + 1];
			node->lower = v3_min(left->lower, right->lower);
			node->upper = v3_max(left->upper, right->upper);
		}
	}
}

static bool boxes_overlap(vec3 al, vec3 au, vec3 bl, vec3 bu)
{
	return al.x <= bu.x && bl.x <= au.x && al.y <= bu.y && bl.y <= au.y && al.z <= bu.z && bl.z <= au.z;
}

/* The walk of plait_mesh_shape_visit; with first_only it stops at the first triangle whose own
 * box overlaps, without visiting it, and says whether there was one (plait_mesh_shape_any).
 * Depth first, left child first; a child's box is tested before it is pushed, so a node that
 * cannot overlap is never loaded again. */
static inline bool walk_boxes(const plait_mesh_shape *shape, vec3 lower, vec3 upper, bool test_triangles,
                              plait_triangle_visitor *visit, void *context, bool first_only)
{
	const plait_bvh_node *nodes = shape->nodes;
	if (!boxes_overlap(nodes[0].lower, nodes[0].upper, lower, upper)) {
		return false;
	}
	int stack[64], depth = 0;
	stack[depth++] = 0;
	while (depth > 0) {
		const plait_bvh_node *n = &nodes[stack[--depth]];
		if (n->count > 0) {
			for (int k = n->first; k < n->first + n->count; ++k) {
				if (test_triangles &&
				    !boxes_overlap(shape->slot_lower[k], shape->slot_upper[k], lower, upper)) {
					continue;
				}
				if (first_only) {
					return true;
				}
				visit(shape->triangle_order[k], context);
			}
		} else if (depth + 2 <= 64) {
			const plait_bvh_node *left = &nodes[n->first], *right = left + 1;
			if (boxes_overlap(right->lower, right->upper, lower, upper)) {
				stack[depth++] = n->first + 1;
			}
			if (boxes_overlap(left->lower, left->upper, lower, upper)) {
				stack[depth++] = n->first;
			}
		}
	}
	return false;
}

void plait_mesh_shape_visit(const plait_mesh_shape *shape, vec3 lower, vec3 upper, bool test_triangles,
                            plait_triangle_visitor *visit, void *context)
{
	(void)walk_boxes(shape, lower, upper, test_triangles, visit, context, false);
}

bool plait_mesh_shape_any(const plait_mesh_shape *shape, vec3 lower, vec3 upper)
{
	return walk_boxes(shape, lower, upper, true, NULL, NULL, true);
}

static vec3 weighted(vec3 a, vec3 b, vec3 c, float wa, float wb, float wc, float weights[3])
{
	if (weights != NULL) {
		weights[0] = wa;
		weights[1] = wb;
		weights[2] = wc;
	}
	return v3_add(v3_add(v3_scale(a, wa), v3_scale(b, wb)), v3_scale(c, wc));
}

vec3 plait_closest_point_on_triangle(vec3 p, vec3 a, vec3 b, vec3 c, int *region, float weights[3])
{
	/* Voronoi regions of the corners, then of the edges, else the face (Ericson, RTCD 5.1.5). */
	vec3 ab = v3_sub(b, a), ac = v3_sub(c, a), ap = v3_sub(p, a);
	float d1 = v3_dot(ab, ap), d2 = v3_dot(ac, ap);
	*region = 1;
	if (d1 <= 0.0f && d2 <= 0.0f) {
		return weighted(a, b, c, 1.0f, 0.0f, 0.0f, weights);
	}
	vec3 bp = v3_sub(p, b);
	float d3 = v3_dot(ab, bp), d4 = v3_dot(ac, bp);
	if (d3 >= 0.0f && d4 <= d3) {
		return weighted(a, b, c, 0.0f, 1.0f, 0.0f, weights);
	}
	float vc = d1 * d4 - d3 * d2;
	if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
		float t = d1 / (d1 - d3);
		return weighted(a, b, c, 1.0f - t, t, 0.0f, weights);
	}
	vec3 cp = v3_sub(p, c);
	float d5 = v3_dot(ab, cp), d6 = v3_dot(ac, cp);
	if (d6 >= 0.0f && d5 <= d6) {
		return weighted(a, b, c, 0.0f, 0.0f, 1.0f, weights);
	}
	float vb = d5 * d2 - d1 * d6;
	if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
		float t = d2 / (d2 - d6);
		return weighted(a, b, c, 1.0f - t, 0.0f, t, weights);
	}
	float va = d3 * d6 - d5 * d4;
	if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
		float t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
		return weighted(a, b, c, 0.0f, 1.0f - t, t, weights);
	}
	float denominator = va + vb + vc;
	if (!(denominator > 0.0f)) {
		return weighted(a, b, c, 1.0f, 0.0f, 0.0f, weights); /* degenerate triangle */
	}
	*region = 0;
	float v = vb / denominator, w = vc / denominator;
	return weighted(a, b, c, 1.0f - v - w, v, w, weights);
}

/* Squared distance from p to the box of n (0 inside it). */
static inline float box_distance_sq(const plait_bvh_node *n, vec3 p)
{
	return v3_length_sq(v3_sub(v3_max(n->lower, v3_min(p, n->upper)), p));
}

/* The squared distances below which a triangle is nearer than the nearest so far (best_sq), and
 * up to which it ties with it: within 5e-6 of the distance plus `slack`, what rounding leaves of
 * two triangles' distances to one point they share (plait_mesh_shape_distance). */
static void tie_window(float best_sq, float slack, float *nearer_sq, float *tied_sq)
{
	float best = sqrtf(best_sq), tolerance = 5e-6f * best + slack;
	float low = best - tolerance, high = best + tolerance;
	*nearer_sq = low > 0.0f ? low * low : 0.0f;
	*tied_sq = high * high;
}

float plait_mesh_shape_distance(const plait_mesh_shape *shape, vec3 p, vec3 *normal)
{
	/* Branch and bound over the hierarchy. Where several triangles share the nearest point (an
	 * edge or a corner), the sign comes from the one p is most in front of: beyond a convex edge
	 * that is positive, inside negative, so a point beyond a sharp edge is not taken for
	 * inside. A child goes on the stack with its box's distance, only if that is within the
	 * bound at the time, and is passed over when it is popped if the bound has come nearer
	 * since (the nearer child is pushed last, popped first: its triangles tighten the bound
	 * that prunes the other).
	 *
	 * Two triangles' distances to a point they share agree only to rounding, which is absolute,
	 * about the float spacing of the coordinates, not a share of the distance: 9.7 mm beside a
	 * table's rim, 0.75 m up and 2.3 um under its top, the top's distance (to the rim) came out
	 * 1.2e-5 of itself nearer than the side's (to its face), so the top gave the sign, and a
	 * vertex outside the table was taken for 9.7 mm inside it. Hence `slack`: 4e-6 of the largest
	 * coordinate of p and of the mesh's box, about thirty times the float spacing there. */
	const plait_bvh_node *root = &shape->nodes[0];
	vec3 far = v3_max(v3_max(v3(fabsf(p.x), fabsf(p.y), fabsf(p.z)),
	                         v3(fabsf(root->lower.x), fabsf(root->lower.y), fabsf(root->lower.z))),
	                  v3(fabsf(root->upper.x), fabsf(root->upper.y), fabsf(root->upper.z)));
	float slack = 4e-6f * plait_maxf(far.x, plait_maxf(far.y, far.z));
	float best_sq = INFINITY, nearer_sq = INFINITY, tied_sq = INFINITY, best_alignment = -INFINITY;
	float nearest_sq = INFINITY; /* of every triangle nearer or tied: the distance returned */
	int best = -1;
	vec3 best_point = p;
	int stack[64], depth = 0;
	float stack_distance_sq[64];
	stack[depth] = 0;
	stack_distance_sq[depth++] = box_distance_sq(&shape->nodes[0], p);
	while (depth > 0) {
		--depth;
		if (stack_distance_sq[depth] > tied_sq) {
			continue;
		}
		const plait_bvh_node *n = &shape->nodes[stack[depth]];
		if (n->count > 0) {
			for (int k = n->first; k < n->first + n->count; ++k) {
				/* The triangle's box is a bound as cheap as the node's: a triangle whose box is
				 * beyond the bound is neither nearer nor tied. */
				vec3 to_box = v3_sub(v3_max(shape->slot_lower[k], v3_min(p, shape->slot_upper[k])), p);
				if (v3_length_sq(to_box) > tied_sq) {
					continue;
				}
				const vec3 *corner = &shape->slot_corners[3 * k];
				int region;
				vec3 q = plait_closest_point_on_triangle(p, corner[0], corner[1], corner[2], &region, NULL);
				vec3 d = v3_sub(p, q);
				float d_sq = v3_length_sq(d);
				bool nearer = d_sq < nearer_sq;
				bool tied = !nearer && d_sq <= tied_sq;
				if (!nearer && !tied) {
					continue;
				}
				nearest_sq = plait_minf(nearest_sq, d_sq);
				int t = shape->triangle_order[k];
				float alignment = v3_dot(d, shape->normals[t]);
				if (nearer || alignment > best_alignment) {
					best_sq = nearer ? d_sq : plait_minf(best_sq, d_sq);
					tie_window(best_sq, slack, &nearer_sq, &tied_sq);
					best_alignment = alignment;
					best = t;
					best_point = q;
				}
			}
		} else if (depth + 2 <= 64) {
			const plait_bvh_node *left = &shape->nodes[n->first], *right = left + 1;
			float to_left = box_distance_sq(left, p), to_right = box_distance_sq(right, p);
			bool left_first = to_left <= to_right;
			int near_child = left_first ? n->first : n->first + 1;
			float near_sq = left_first ? to_left : to_right, far_sq = left_first ? to_right : to_left;
			float bound = tied_sq;
			if (far_sq <= bound) {
				stack[depth] = left_first ? n->first + 1 : n->first;
				stack_distance_sq[depth++] = far_sq;
			}
			if (near_sq <= bound) {
				stack[depth] = near_child;
				stack_distance_sq[depth++] = near_sq;
			}
		}
	}
	if (best < 0) {
		*normal = v3(0.0f, 1.0f, 0.0f);
		return INFINITY;
	}
	vec3 n = shape->normals[best];
	*normal = v3_length_sq(n) > 0.0f ? n : v3(0.0f, 1.0f, 0.0f);
	float distance = sqrtf(nearest_sq);
	return v3_dot(v3_sub(p, best_point), *normal) < 0.0f ? -distance : distance;
}
