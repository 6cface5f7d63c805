/* A bounding volume hierarchy over axis-aligned boxes (one per triangle, say), built from
 * scratch each time: median splits along the widest spread of the boxes' centres. Queries
 * report box overlaps only; what overlaps is the caller's to test exactly. */
#ifndef PLAIT_BOX_TREE_H
#define PLAIT_BOX_TREE_H

#include <plait/plait.h>
#include <stdbool.h>

typedef struct plait_box {
	plait_vec3 lower, upper;
} plait_box;

typedef struct plait_box_node {
	plait_box box;
	int first; /* leaf: first entry of order; inner: left child (right is first + 1) */
	int count; /* leaf: entries; inner: 0 */
} plait_box_node;

typedef struct plait_box_tree {
	const plait_box *boxes; /* the caller's, as given to the last build */
	plait_box_node *nodes;
	int node_count, node_capacity;
	int *order;            /* box indices, leaf by leaf */
	plait_box *leaf_boxes; /* boxes[order[k]] at k: leaves read memory in a row */
	plait_vec3 *centers;
	int capacity;
} plait_box_tree;

/* Builds over boxes[0, count), which must stay alive and unchanged while the tree is used.
 * Keeps its arrays for the next build; false only when out of memory. */
bool plait_box_tree_build(plait_box_tree *tree, const plait_box *boxes, int count);
void plait_box_tree_free(plait_box_tree *tree);

/* The box around everything; false for an empty tree. */
bool plait_box_tree_bounds(const plait_box_tree *tree, plait_box *bounds);

typedef void plait_box_pair_fn(int a, int b, void *context);
typedef void plait_box_item_fn(int item, void *context);

/* Every pair of distinct boxes that overlap (touching counts), each pair once. */
void plait_box_tree_pairs(const plait_box_tree *tree, plait_box_pair_fn *visit, void *context);
/* Every box that overlaps query. */
void plait_box_tree_query(const plait_box_tree *tree, plait_box query, plait_box_item_fn *visit,
                          void *context);
/* Every box that the segment p-q passes through (slab test in double precision). */
void plait_box_tree_segment(const plait_box_tree *tree, const double p[3], const double q[3],
                            plait_box_item_fn *visit, void *context);

static inline bool plait_boxes_overlap(const plait_box *a, const plait_box *b)
{
	return a->lower.x <= b->upper.x && b->lower.x <= a->upper.x && a->lower.y <= b->upper.y &&
	       b->lower.y <= a->upper.y && a->lower.z <= b->upper.z && b->lower.z <= a->upper.z;
}

#endif
