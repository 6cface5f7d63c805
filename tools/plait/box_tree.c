#include "box_tree.h"

#include <stdlib.h>

#define PLAIT_BOX_LEAF_SIZE 4

void plait_box_tree_free(plait_box_tree *tree)
{
	free(tree->nodes);
	free(tree->order);
	free(tree->leaf_boxes);
	free(tree->centers);
	*tree = (plait_box_tree){0};
}

static float plait_axis(plait_vec3 v, int axis)
{
	return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

// Plain comparisons: fminf and fmaxf honour NaN and stay library calls (positions are finite).
static float plait_min(float a, float b)
{
	return a < b ? a : b;
}

static float plait_max(float a, float b)
{
	return a > b ? a : b;
}

static plait_vec3 plait_min3(plait_vec3 a, plait_vec3 b)
{
	return (plait_vec3){plait_min(a.x, b.x), plait_min(a.y, b.y), plait_min(a.z, b.z)};
}

static plait_vec3 plait_max3(plait_vec3 a, plait_vec3 b)
{
	return (plait_vec3){plait_max(a.x, b.x), plait_max(a.y, b.y), plait_max(a.z, b.z)};
}

static plait_box plait_box_union(plait_box a, plait_box b)
{
	return (plait_box){plait_min3(a.lower, b.lower), plait_max3(a.upper, b.upper)};
}

// Quickselect: puts the entry of rank k (by centre along axis) at order[k], smaller ones before
// it and larger ones after. Linear on average, which keeps the build at n log n.
static void plait_select(int *order, const plait_vec3 *centers, int count, int k, int axis)
{
	int low = 0, high = count - 1;
	while (low < high) {
		float pivot = plait_axis(centers[order[(low + high) / 2]], axis);
		int i = low, j = high;
		while (i <= j) {
			while (plait_axis(centers[order[i]], axis) < pivot)
				++i;
			while (plait_axis(centers[order[j]], axis) > pivot)
				--j;
			if (i <= j) {
				int swap = order[i];
				order[i] = order[j];
				order[j] = swap;
				++i;
				--j;
			}
		}
		if (k <= j)
			high = j;
		else if (k >= i)
			low = i;
		else
			return;
	}
}

static int plait_build_node(plait_box_tree *tree, int node, int first, int count, int next_free)
{
	plait_box_node *n = &tree->nodes[node];
	plait_box box = tree->boxes[tree->order[first]];
	plait_vec3 low = tree->centers[tree->order[first]], high = low;
	for (int k = first + 1; k < first + count; ++k) {
		box = plait_box_union(box, tree->boxes[tree->order[k]]);
		plait_vec3 c = tree->centers[tree->order[k]];
		low = plait_min3(low, c);
		high = plait_max3(high, c);
	}
	n->box = box;
	if (count <= PLAIT_BOX_LEAF_SIZE) {
		n->first = first;
		n->count = count;
		return next_free;
	}
	plait_vec3 spread = {high.x - low.x, high.y - low.y, high.z - low.z};
	int axis = spread.x >= spread.y && spread.x >= spread.z ? 0 : spread.y >= spread.z ? 1 : 2;
	int half = count / 2;
	plait_select(tree->order + first, tree->centers, count, half, axis);
	int left = next_free;
	n->first = left;
	n->count = 0;
	next_free = plait_build_node(tree, left, first, half, next_free + 2);
	return plait_build_node(tree, left + 1, first + half, count - half, next_free);
}

bool plait_box_tree_build(plait_box_tree *tree, const plait_box *boxes, int count)
{
	tree->boxes = boxes;
	tree->node_count = 0;
	if (count <= 0)
		return true;
	if (count > tree->capacity) {
		int *order = realloc(tree->order, sizeof *order * (size_t)count);
		if (order != NULL)
			tree->order = order;
		plait_vec3 *centers = realloc(tree->centers, sizeof *centers * (size_t)count);
		if (centers != NULL)
			tree->centers = centers;
		plait_box_node *nodes = realloc(tree->nodes, sizeof *nodes * 2 * (size_t)count);
		if (nodes != NULL)
			tree->nodes = nodes;
		plait_box *leaf_boxes = realloc(tree->leaf_boxes, sizeof *leaf_boxes * (size_t)count);
		if (leaf_boxes != NULL)
			tree->leaf_boxes = leaf_boxes;
		if (order == NULL || centers == NULL || nodes == NULL || leaf_boxes == NULL)
			return false;
		tree->capacity = count;
	}
	for (int i = 0; i < count; ++i) {
		tree->order[i] = i;
		plait_box b = boxes[i];
		tree->centers[i] = (plait_vec3){0.5f * (b.lower.x + b.upper.x), 0.5f * (b.lower.y + b.upper.y),
		                                0.5f * (b.lower.z + b.upper.z)};
	}
	tree->node_count = plait_build_node(tree, 0, 0, count, 1);
	for (int k = 0; k < count; ++k)
		tree->leaf_boxes[k] = boxes[tree->order[k]];
	return true;
}

bool plait_box_tree_bounds(const plait_box_tree *tree, plait_box *bounds)
{
	if (tree->node_count == 0)
		return false;
	*bounds = tree->nodes[0].box;
	return true;
}

typedef struct plait_pair_walk {
	const plait_box_tree *tree;
	plait_box_pair_fn *visit;
	void *context;
} plait_pair_walk;

static void plait_leaf_pairs(const plait_pair_walk *w, const plait_box_node *a, const plait_box_node *b)
{
	const plait_box_tree *t = w->tree;
	for (int i = a->first; i < a->first + a->count; ++i) {
		const plait_box *box = &t->leaf_boxes[i];
		for (int j = a == b ? i + 1 : b->first; j < b->first + b->count; ++j)
			if (plait_boxes_overlap(box, &t->leaf_boxes[j]))
				w->visit(t->order[i], t->order[j], w->context);
	}
}

// Half the surface area's worth: which of two nodes to open first (the larger one).
static float plait_box_size(const plait_box *box)
{
	float x = box->upper.x - box->lower.x, y = box->upper.y - box->lower.y, z = box->upper.z - box->lower.z;
	return x * y + y * z + z * x;
}

static void plait_cross_pairs(const plait_pair_walk *w, int a, int b)
{
	const plait_box_node *na = &w->tree->nodes[a], *nb = &w->tree->nodes[b];
	if (!plait_boxes_overlap(&na->box, &nb->box))
		return;
	if (na->count > 0 && nb->count > 0) {
		plait_leaf_pairs(w, na, nb);
	} else if (na->count > 0 || (nb->count == 0 && plait_box_size(&nb->box) > plait_box_size(&na->box))) {
		plait_cross_pairs(w, a, nb->first);
		plait_cross_pairs(w, a, nb->first + 1);
	} else {
		plait_cross_pairs(w, na->first, b);
		plait_cross_pairs(w, na->first + 1, b);
	}
}

static void plait_self_pairs(const plait_pair_walk *w, int node)
{
	const plait_box_node *n = &w->tree->nodes[node];
	if (n->count > 0) {
		plait_leaf_pairs(w, n, n);
		return;
	}
	plait_self_pairs(w, n->first);
	plait_self_pairs(w, n->first + 1);
	plait_cross_pairs(w, n->first, n->first + 1);
}

void plait_box_tree_pairs(const plait_box_tree *tree, plait_box_pair_fn *visit, void *context)
{
	if (tree->node_count == 0)
		return;
	plait_pair_walk walk = {tree, visit, context};
	plait_self_pairs(&walk, 0);
}

void plait_box_tree_query(const plait_box_tree *tree, plait_box query, plait_box_item_fn *visit,
                          void *context)
{
	if (tree->node_count == 0)
		return;
	int stack[128], depth = 0;
	stack[depth++] = 0;
	while (depth > 0) {
		const plait_box_node *n = &tree->nodes[stack[--depth]];
		if (!plait_boxes_overlap(&n->box, &query))
			continue;
		if (n->count > 0) {
			for (int k = n->first; k < n->first + n->count; ++k)
				if (plait_boxes_overlap(&tree->leaf_boxes[k], &query))
					visit(tree->order[k], context);
		} else {
			stack[depth++] = n->first + 1;
			stack[depth++] = n->first;
		}
	}
}

// Whether p + t (q - p), t in [0, 1], meets the box (borders included).
static bool plait_segment_meets_box(const double p[3], const double d[3], const plait_box *box)
{
	double enter = 0.0, leave = 1.0;
	const double low[3] = {box->lower.x, box->lower.y, box->lower.z};
	const double high[3] = {box->upper.x, box->upper.y, box->upper.z};
	for (int k = 0; k < 3; ++k) {
		if (d[k] == 0.0) {
			if (p[k] < low[k] || p[k] > high[k])
				return false;
			continue;
		}
		double t0 = (low[k] - p[k]) / d[k], t1 = (high[k] - p[k]) / d[k];
		if (t0 > t1) {
			double swap = t0;
			t0 = t1;
			t1 = swap;
		}
		enter = t0 > enter ? t0 : enter;
		leave = t1 < leave ? t1 : leave;
		if (enter > leave)
			return false;
	}
	return true;
}

void plait_box_tree_segment(const plait_box_tree *tree, const double p[3], const double q[3],
                            plait_box_item_fn *visit, void *context)
{
	if (tree->node_count == 0)
		return;
	const double d[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
	int stack[128], depth = 0;
	stack[depth++] = 0;
	while (depth > 0) {
		const plait_box_node *n = &tree->nodes[stack[--depth]];
		if (!plait_segment_meets_box(p, d, &n->box))
			continue;
		if (n->count > 0) {
			for (int k = n->first; k < n->first + n->count; ++k)
				if (plait_segment_meets_box(p, d, &tree->leaf_boxes[k]))
					visit(tree->order[k], context);
		} else {
			stack[depth++] = n->first + 1;
			stack[depth++] = n->first;
		}
	}
}
