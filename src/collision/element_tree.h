/* A bounding volume hierarchy (axis-aligned boxes) over the collision elements of deforming
 * objects: triangles, edges or points whose vertices move every substep. The tree's shape is
 * built once from the elements' positions (median splits), and only its boxes change after
 * that: they are refitted from the elements' boxes whenever the caller asks, which stays cheap
 * and good as long as the objects do not tear apart. Rebuild when the topology changes.
 *
 * The pair query is a self-traversal: every pair of elements whose boxes overlap is reported
 * once, in an order fixed by the tree (deterministic). */
#ifndef PLAIT_COLLISION_ELEMENT_TREE_H
#define PLAIT_COLLISION_ELEMENT_TREE_H

#include "core/alloc.h"
#include "core/math.h"

typedef struct plait_tree_node {
	vec3 lower, upper;
	int first; /* leaf: first entry in order; inner: left child (right is left + 1) */
	int count; /* leaf: element count; inner: 0 */
} plait_tree_node;

typedef struct plait_element_tree {
	int element_count;
	int node_count;
	plait_tree_node *nodes; /* parents before children */
	int *order;             /* elements in leaf order */
} plait_element_tree;

/* Builds the tree's shape over `count` elements from their centres. Returns false when out of
 * memory (the tree is then empty). */
bool plait_element_tree_build(plait_element_tree *tree, const plait_allocator *allocator, const vec3 *centres,
                              int count);
void plait_element_tree_destroy(plait_element_tree *tree, const plait_allocator *allocator);

/* Sets every node's box from the elements' boxes (indexed by element). */
void plait_element_tree_refit(plait_element_tree *tree, const vec3 *lower, const vec3 *upper);
/* The same in parts, for workers: the nodes `levels` below the root (and leaves above that),
 * in order, into roots (room for 2^levels); each one's subtree refitted on its own (any order,
 * side by side); then the nodes above them. A node's box depends only on its children's or its
 * elements' (minima and maxima), so the boxes are the ones plait_element_tree_refit sets. */
int plait_element_tree_cut(const plait_element_tree *tree, int levels, int *roots);
void plait_element_tree_refit_subtree(plait_element_tree *tree, int root, const vec3 *lower,
                                      const vec3 *upper);
void plait_element_tree_refit_above(plait_element_tree *tree, int levels, const vec3 *lower,
                                    const vec3 *upper);

/* Calls visit(a, b, context) once for every pair of distinct elements whose boxes overlap;
 * a < b is not promised. Uses the boxes given to the last refit. */
typedef void plait_element_pair_visitor(int a, int b, void *context);
void plait_element_tree_pairs(const plait_element_tree *tree, const vec3 *lower, const vec3 *upper,
                              plait_element_pair_visitor *visit, void *context);

/* What a traversal may pass over. In a self-traversal, skip(node, context) says whether the
 * node's pairs with itself (all of them, down to its leaves) may be; between two trees,
 * skip_pair(node_a, node_b, context) whether a node pair's may (either function may be NULL).
 * Called for the nodes and node pairs a traversal reaches (a piece's first again), from several
 * threads at once when pieces run side by side: they must answer the same each time. */
typedef struct plait_node_skip {
	bool (*skip)(int node, void *context);
	bool (*skip_pair)(int node_a, int node_b, void *context);
	void *context;
} plait_node_skip;
/* As plait_element_tree_pairs, passing over what skip says. */
void plait_element_tree_pairs_skipping(const plait_element_tree *tree, const vec3 *lower, const vec3 *upper,
                                       const plait_node_skip *skip, plait_element_pair_visitor *visit,
                                       void *context);

/* As above between two trees: visit(a, b) with a an element of tree_a, b one of tree_b (each
 * in its own tree's numbering, boxes from its own arrays), for boxes within `margin` of each
 * other along each axis (its own margin each: how far one tree's boxes may move against the
 * other's along x, y and z), passing over the node pairs skip says (NULL: none). */
void plait_element_tree_pairs_between(const plait_element_tree *tree_a, const vec3 *lower_a,
                                      const vec3 *upper_a, const plait_element_tree *tree_b,
                                      const vec3 *lower_b, const vec3 *upper_b, vec3 margin,
                                      const plait_node_skip *skip, plait_element_pair_visitor *visit,
                                      void *context);

/* Calls visit(e, context) for every element e whose box comes within `margin` (along each
 * axis) of the box [box_lower, box_upper], in the tree's order. Uses the boxes given to the last refit. */
typedef void plait_element_visitor(int element, void *context);
void plait_element_tree_query(const plait_element_tree *tree, const vec3 *lower, const vec3 *upper,
                              vec3 box_lower, vec3 box_upper, vec3 margin, plait_element_visitor *visit,
                              void *context);

/* The same traversals cut into pieces for workers: writes the node pairs (a, b) reached after
 * `depth` splits (and the leaf pairs reached before), in the order the traversal meets them,
 * and returns how many; -1 when more than capacity. The pairs of all pieces, each traversed by
 * plait_element_tree_piece_pairs and taken in piece order, are the whole traversal's pairs in
 * its order. self and margin as for the two queries above (self: tree_b is tree_a, margin 0);
 * skip as for the two queries (NULL: none); uses the node boxes of the last refit. */
int plait_element_tree_split(const plait_element_tree *tree_a, const plait_element_tree *tree_b, bool self,
                             vec3 margin, const plait_node_skip *skip, int depth, int (*pieces)[2],
                             int capacity);
void plait_element_tree_piece_pairs(const plait_element_tree *tree_a, const vec3 *lower_a,
                                    const vec3 *upper_a, const plait_element_tree *tree_b,
                                    const vec3 *lower_b, const vec3 *upper_b, bool self, vec3 margin,
                                    const plait_node_skip *skip, const int piece[2],
                                    plait_element_pair_visitor *visit, void *context);

#endif
