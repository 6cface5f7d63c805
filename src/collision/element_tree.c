#include "collision/element_tree.h"

#include "collision/axis_sort.h"

#include <math.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define LEAF_SIZE 4
_Static_assert(LEAF_SIZE <= 4, "leaf_pairs tests a leaf's elements in four lanes");

void plait_element_tree_destroy(plait_element_tree *tree, const plait_allocator *allocator)
{
	plait_free(allocator, tree->nodes);
	plait_free(allocator, tree->order);
	memset(tree, 0, sizeof *tree);
}

/* Builds node `node` over the elements in [first, first + count) of the orders and its subtree;
 * returns the next free node index and raises *depth to the subtree's depth. A leaf's elements
 * go to tree->order in the order of its parent's axis (root: as given). */
static int build_node(plait_element_tree *tree, const vec3 *centre, plait_axis_orders *orders, int node,
                      int first, int count, int next_free, int level, int *depth, int parent_axis)
{
	plait_tree_node *n = &tree->nodes[node];
	if (level > *depth) {
		*depth = level;
	}
	if (count <= LEAF_SIZE) {
		if (parent_axis >= 0) {
			memcpy(tree->order + first, orders->by_axis[parent_axis] + first, sizeof(int) * (size_t)count);
		}
		n->first = first;
		n->count = count;
		return next_free;
	}
	vec3 lower, upper;
	plait_axis_orders_bounds(orders, centre, first, count, &lower, &upper);
	vec3 extent = v3_sub(upper, lower);
	int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
	int left = next_free;
	n->first = left;
	n->count = 0;
	int half = count / 2;
	plait_axis_orders_split(orders, first, count, axis, half);
	next_free = build_node(tree, centre, orders, left, first, half, next_free + 2, level + 1, depth, axis);
	return build_node(tree, centre, orders, left + 1, first + half, count - half, next_free, level + 1, depth,
	                  axis);
}

bool plait_element_tree_build(plait_element_tree *tree, const plait_allocator *allocator, const vec3 *centres,
                              int count)
{
	plait_element_tree_destroy(tree, allocator);
	if (count <= 0) {
		return true;
	}
	int capacity = 2 * count; /* a binary tree with leaves of at least one element */
	tree->nodes = plait_alloc_zero(allocator, (size_t)capacity, sizeof *tree->nodes);
	tree->order = plait_alloc_zero(allocator, (size_t)count, sizeof(int));
	plait_axis_orders orders;
	if (tree->nodes == NULL || tree->order == NULL ||
	    !plait_axis_orders_make(&orders, allocator, centres, count)) {
		plait_element_tree_destroy(tree, allocator);
		return false;
	}
	for (int k = 0; k < count; ++k) {
		tree->order[k] = k;
	}
	int depth = 0;
	tree->node_count = build_node(tree, centres, &orders, 0, 0, count, 1, 0, &depth, -1);
	tree->element_count = count;
	plait_axis_orders_free(&orders, allocator);
	return true;
}

/* Node n's box from its elements' or its children's. */
static void refit_one(plait_element_tree *tree, int n, const vec3 *lower, const vec3 *upper)
{
	plait_tree_node *node = &tree->nodes[n];
	if (node->count > 0) {
		vec3 l = lower[tree->order[node->first]], u = upper[tree->order[node->first]];
		for (int k = node->first + 1; k < node->first + node->count; ++k) {
			l = v3_min(l, lower[tree->order[k]]);
			u = v3_max(u, upper[tree->order[k]]);
		}
		node->lower = l;
		node->upper = u;
	} else {
		const plait_tree_node *a = &tree->nodes[node->first], *b = &tree->nodes[node->first + 1];
		node->lower = v3_min(a->lower, b->lower);
		node->upper = v3_max(a->upper, b->upper);
	}
}

static void refit_under(plait_element_tree *tree, int n, const vec3 *lower, const vec3 *upper)
{
	if (tree->nodes[n].count == 0) {
		refit_under(tree, tree->nodes[n].first, lower, upper);
		refit_under(tree, tree->nodes[n].first + 1, lower, upper);
	}
	refit_one(tree, n, lower, upper);
}

void plait_element_tree_refit_subtree(plait_element_tree *tree, int root, const vec3 *lower,
                                      const vec3 *upper)
{
	refit_under(tree, root, lower, upper);
}

/* Writes the cut's roots under node n, `levels` below it, in order; returns the next free slot. */
static int cut_under(const plait_element_tree *tree, int n, int levels, int *roots, int count)
{
	if (levels == 0 || tree->nodes[n].count > 0) {
		roots[count] = n;
		return count + 1;
	}
	count = cut_under(tree, tree->nodes[n].first, levels - 1, roots, count);
	return cut_under(tree, tree->nodes[n].first + 1, levels - 1, roots, count);
}

int plait_element_tree_cut(const plait_element_tree *tree, int levels, int *roots)
{
	return tree->node_count > 0 ? cut_under(tree, 0, levels, roots, 0) : 0;
}

static void refit_above(plait_element_tree *tree, int n, int levels, const vec3 *lower, const vec3 *upper)
{
	if (levels == 0 || tree->nodes[n].count > 0) {
		return;
	}
	refit_above(tree, tree->nodes[n].first, levels - 1, lower, upper);
	refit_above(tree, tree->nodes[n].first + 1, levels - 1, lower, upper);
	refit_one(tree, n, lower, upper);
}

void plait_element_tree_refit_above(plait_element_tree *tree, int levels, const vec3 *lower,
                                    const vec3 *upper)
{
	if (tree->node_count > 0) {
		refit_above(tree, 0, levels, lower, upper);
	}
}

void plait_element_tree_refit(plait_element_tree *tree, const vec3 *lower, const vec3 *upper)
{
	for (int n = tree->node_count - 1; n >= 0; --n) {
		refit_one(tree, n, lower, upper); /* children come after their parent */
	}
}

/* Whether two boxes come within `margin` of each other, along each axis its own. */
static bool boxes_overlap(vec3 la, vec3 ua, vec3 lb, vec3 ub, vec3 margin)
{
	return la.x <= ub.x + margin.x && lb.x <= ua.x + margin.x && la.y <= ub.y + margin.y &&
	       lb.y <= ua.y + margin.y && la.z <= ub.z + margin.z && lb.z <= ua.z + margin.z;
}

/* Median splits halve the element count at every level, so no tree is deeper than 32 levels;
 * a depth-first pair traversal adds at most two pending pairs per level of either tree. */
#define STACK_PAIRS 160

#if defined(__SSE2__)
/* The index of the lowest set bit of a nonzero mask of at most 4 bits. */
static inline int lowest_bit(int mask)
{
#if defined(__GNUC__)
	return __builtin_ctz((unsigned)mask);
#else
	int k = 0;
	while (!(mask & (1 << k))) {
		++k;
	}
	return k;
#endif
}

/* The boxes of leaf b's elements side by side (lane k: its k-th), upper bounds grown by the
 * margin; lanes past its count are empty (lower +inf, upper -inf), and masked out by the caller
 * as well (an infinite box meets even those). */
typedef struct leaf_lanes {
	__m128 lx, ly, lz, ux, uy, uz;
} leaf_lanes;

static leaf_lanes leaf_lanes_of(const plait_element_tree *tree, const plait_tree_node *leaf,
                                const vec3 *lower, const vec3 *upper, vec3 margin)
{
	_Alignas(16) float l[3][4], u[3][4];
	for (int k = 0; k < 4; ++k) {
		for (int axis = 0; axis < 3; ++axis) {
			l[axis][k] = INFINITY;
			u[axis][k] = -INFINITY;
		}
	}
	for (int k = 0; k < leaf->count; ++k) {
		int e = tree->order[leaf->first + k];
		l[0][k] = lower[e].x;
		l[1][k] = lower[e].y;
		l[2][k] = lower[e].z;
		u[0][k] = upper[e].x + margin.x;
		u[1][k] = upper[e].y + margin.y;
		u[2][k] = upper[e].z + margin.z;
	}
	return (leaf_lanes){_mm_load_ps(l[0]), _mm_load_ps(l[1]), _mm_load_ps(l[2]),
	                    _mm_load_ps(u[0]), _mm_load_ps(u[1]), _mm_load_ps(u[2])};
}

/* Bit k set when element e's box meets lane k's: the comparisons of boxes_overlap, four at a
 * time (the same sums, so the same answers). */
static int leaf_lanes_meet(const leaf_lanes *b, vec3 lower, vec3 upper, vec3 margin)
{
	__m128 meet = _mm_and_ps(_mm_cmple_ps(_mm_set1_ps(lower.x), b->ux),
	                         _mm_cmple_ps(b->lx, _mm_set1_ps(upper.x + margin.x)));
	meet = _mm_and_ps(meet, _mm_cmple_ps(_mm_set1_ps(lower.y), b->uy));
	meet = _mm_and_ps(meet, _mm_cmple_ps(b->ly, _mm_set1_ps(upper.y + margin.y)));
	meet = _mm_and_ps(meet, _mm_cmple_ps(_mm_set1_ps(lower.z), b->uz));
	meet = _mm_and_ps(meet, _mm_cmple_ps(b->lz, _mm_set1_ps(upper.z + margin.z)));
	return _mm_movemask_ps(meet);
}
#endif

/* Visits the element pairs of leaves a and b whose boxes meet, a's elements in order and for
 * each b's in order. The tests are a quarter of the self-traversal's time and go either way
 * at random, so four are made at once, without a branch each (SSE2). */
static void leaf_pairs(const plait_element_tree *tree_a, const plait_tree_node *a, const vec3 *lower_a,
                       const vec3 *upper_a, const plait_element_tree *tree_b, const plait_tree_node *b,
                       const vec3 *lower_b, const vec3 *upper_b, vec3 margin,
                       plait_element_pair_visitor *visit, void *context)
{
	bool same = a == b;
#if defined(__SSE2__)
	leaf_lanes lanes = leaf_lanes_of(tree_b, b, lower_b, upper_b, margin);
	const int *order_b = tree_b->order + b->first;
	for (int i = 0; i < a->count; ++i) {
		int ei = tree_a->order[a->first + i];
		/* Only b's own lanes: an infinite box (a frame gone non-finite) meets the empty ones. */
		int meet = leaf_lanes_meet(&lanes, lower_a[ei], upper_a[ei], margin) & ((1 << b->count) - 1);
		if (same) {
			meet &= ~((2 << i) - 1); /* the pairs after i */
		}
		while (meet != 0) {
			int k = lowest_bit(meet);
			meet &= meet - 1;
			visit(ei, order_b[k], context);
		}
	}
#else
	for (int i = a->first; i < a->first + a->count; ++i) {
		int ei = tree_a->order[i];
		for (int j = same ? i + 1 : b->first; j < b->first + b->count; ++j) {
			int ej = tree_b->order[j];
			if (boxes_overlap(lower_a[ei], upper_a[ei], lower_b[ej], upper_b[ej], margin)) {
				visit(ei, ej, context);
			}
		}
	}
#endif
}

/* The traversal for both queries, from node pair (start_a, start_b) (0, 0: the whole trees);
 * `self` when the two trees are one. With pieces != NULL it does not descend below `depth`
 * pair splits: the node pairs it stops at (and the leaf pairs above that depth) go to pieces in
 * the order the full traversal would meet them, and their count is returned (-1 past
 * capacity). With skip, a node's pairs with itself, or a node pair's, are passed over when it
 * says so. */
static int traverse(const plait_element_tree *tree_a, const vec3 *lower_a, const vec3 *upper_a,
                    const plait_element_tree *tree_b, const vec3 *lower_b, const vec3 *upper_b, bool self,
                    vec3 margin, int start_a, int start_b, const plait_node_skip *skip,
                    plait_element_pair_visitor *visit, void *context, int depth, int (*pieces)[2],
                    int capacity)
{
	if (tree_a->node_count == 0 || tree_b->node_count == 0) {
		return 0;
	}
	int stack[3 * STACK_PAIRS];
	int top = 0, count = 0;
	stack[top++] = start_a;
	stack[top++] = start_b;
	stack[top++] = 0;
	while (top > 0) {
		int level = stack[--top], nb = stack[--top], na = stack[--top];
		const plait_tree_node *a = &tree_a->nodes[na], *b = &tree_b->nodes[nb];
		bool same = self && na == nb;
		if (skip != NULL && (same ? skip->skip != NULL && skip->skip(na, skip->context)
		                          : skip->skip_pair != NULL && skip->skip_pair(na, nb, skip->context))) {
			continue;
		}
		if (!same && !boxes_overlap(a->lower, a->upper, b->lower, b->upper, margin)) {
			continue;
		}
		if (pieces != NULL && (level >= depth || (a->count > 0 && b->count > 0))) {
			if (count == capacity) {
				return -1;
			}
			pieces[count][0] = na;
			pieces[count++][1] = nb;
			continue;
		}
		if (a->count > 0 && b->count > 0) {
			leaf_pairs(tree_a, a, lower_a, upper_a, tree_b, b, lower_b, upper_b, margin, visit, context);
			continue;
		}
		/* Pairs pushed in reverse so they pop in a fixed, natural order. */
		if (same) {
			int l = a->first, r = a->first + 1;
			int pushes[3][2] = {{r, r}, {l, r}, {l, l}};
			for (int k = 0; k < 3; ++k) {
				stack[top++] = pushes[k][0];
				stack[top++] = pushes[k][1];
				stack[top++] = level + 1;
			}
		} else if (b->count > 0 || (a->count == 0 && na <= nb)) {
			/* Split the inner node (the shallower one when both are inner: a balanced descent). */
			stack[top++] = a->first + 1;
			stack[top++] = nb;
			stack[top++] = level + 1;
			stack[top++] = a->first;
			stack[top++] = nb;
			stack[top++] = level + 1;
		} else {
			stack[top++] = na;
			stack[top++] = b->first + 1;
			stack[top++] = level + 1;
			stack[top++] = na;
			stack[top++] = b->first;
			stack[top++] = level + 1;
		}
	}
	return count;
}

void plait_element_tree_pairs(const plait_element_tree *tree, const vec3 *lower, const vec3 *upper,
                              plait_element_pair_visitor *visit, void *context)
{
	(void)traverse(tree, lower, upper, tree, lower, upper, true, v3(0.0f, 0.0f, 0.0f), 0, 0, NULL, visit,
	               context, 0, NULL, 0);
}

void plait_element_tree_pairs_skipping(const plait_element_tree *tree, const vec3 *lower, const vec3 *upper,
                                       const plait_node_skip *skip, plait_element_pair_visitor *visit,
                                       void *context)
{
	(void)traverse(tree, lower, upper, tree, lower, upper, true, v3(0.0f, 0.0f, 0.0f), 0, 0, skip, visit,
	               context, 0, NULL, 0);
}

void plait_element_tree_pairs_between(const plait_element_tree *tree_a, const vec3 *lower_a,
                                      const vec3 *upper_a, const plait_element_tree *tree_b,
                                      const vec3 *lower_b, const vec3 *upper_b, vec3 margin,
                                      const plait_node_skip *skip, plait_element_pair_visitor *visit,
                                      void *context)
{
	(void)traverse(tree_a, lower_a, upper_a, tree_b, lower_b, upper_b, false, margin, 0, 0, skip, visit,
	               context, 0, NULL, 0);
}

int plait_element_tree_split(const plait_element_tree *tree_a, const plait_element_tree *tree_b, bool self,
                             vec3 margin, const plait_node_skip *skip, int depth, int (*pieces)[2],
                             int capacity)
{
	return traverse(tree_a, NULL, NULL, tree_b, NULL, NULL, self, margin, 0, 0, skip, NULL, NULL, depth,
	                pieces, capacity);
}

void plait_element_tree_piece_pairs(const plait_element_tree *tree_a, const vec3 *lower_a,
                                    const vec3 *upper_a, const plait_element_tree *tree_b,
                                    const vec3 *lower_b, const vec3 *upper_b, bool self, vec3 margin,
                                    const plait_node_skip *skip, const int piece[2],
                                    plait_element_pair_visitor *visit, void *context)
{
	(void)traverse(tree_a, lower_a, upper_a, tree_b, lower_b, upper_b, self, margin, piece[0], piece[1], skip,
	               visit, context, 0, NULL, 0);
}

static bool boxes_within(vec3 la, vec3 ua, vec3 lb, vec3 ub, vec3 margin)
{
	return la.x - ub.x <= margin.x && lb.x - ua.x <= margin.x && la.y - ub.y <= margin.y &&
	       lb.y - ua.y <= margin.y && la.z - ub.z <= margin.z && lb.z - ua.z <= margin.z;
}

void plait_element_tree_query(const plait_element_tree *tree, const vec3 *lower, const vec3 *upper,
                              vec3 box_lower, vec3 box_upper, vec3 margin, plait_element_visitor *visit,
                              void *context)
{
	if (tree->node_count == 0) {
		return;
	}
	/* The depth of a tree of median splits over at most 2^31 elements stays well under this. */
	int stack[128];
	int top = 0;
	stack[top++] = 0;
	while (top > 0) {
		const plait_tree_node *n = &tree->nodes[stack[--top]];
		if (!boxes_within(n->lower, n->upper, box_lower, box_upper, margin)) {
			continue;
		}
		if (n->count > 0) {
			for (int k = n->first; k < n->first + n->count; ++k) {
				int e = tree->order[k];
				if (boxes_within(lower[e], upper[e], box_lower, box_upper, margin)) {
					visit(e, context);
				}
			}
			continue;
		}
		stack[top++] = n->first + 1; /* right, popped after the left */
		stack[top++] = n->first;
	}
}
