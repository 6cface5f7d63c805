/* Patches of a cloth that cannot touch themselves: self-collision culling for the nodes of an
 * element tree over a triangle mesh.
 *
 * A node's triangles form a patch. If, along some direction d, every triangle of the patch faces
 * d (its normal within 90 degrees of d) and the patch's boundary, seen along d, winds once round
 * a point c with every boundary edge turning the same way round c (a star-shaped contour), then
 * the patch seen along d covers each point at most once: no two of its points meet, and a
 * self-traversal may pass over the node's pairs with itself. (Normal cones: Volino and
 * Magnenat-Thalmann 1994; star contours: Schvartzman, Perez and Otaduy 2010.)
 *
 * Here that must hold for as long as a list of pairs serves, so every vertex is taken anywhere
 * within its guard of a straight path: the normal of a triangle whose vertices move straight is
 * quadratic in time, bounded by its three Bernstein coefficients (Tang et al.'s continuous normal
 * cones), and so is each boundary edge's turn round c; the guards widen both bounds.
 *
 * The boundary a node's triangles leave is often a zigzag (a median split cuts through the
 * middle of quads), which is never star-shaped: each node's patch takes in the triangles outside
 * it that share two of its edges (its notches), which straightens it. A patch covering more is
 * still a sound test: if the larger patch cannot touch itself, neither can the node's.
 *
 * The centre c of each patch is chosen once, in the rest shape: the centroid of its contour's
 * kernel (the points every boundary edge turns forward round), kept as a point of one of its
 * triangles so that it moves with them; the contour's mean is tried after it.
 *
 * The patches' shapes (contours, notches, centres) are built once from the tree and the
 * triangles; the cones are refitted before each traversal. Nodes whose patch is no disk (several
 * pieces, holes, a boundary that touches itself) or is small are never taken as flat. The
 * callers (dynamics/mesh_contact_*.c) take a patch flat on a guess and check it afterwards along
 * the paths really taken (plait_flat_patches_keeps_flat). */
#ifndef PLAIT_COLLISION_FLAT_PATCHES_H
#define PLAIT_COLLISION_FLAT_PATCHES_H

#include "collision/element_tree.h"
#include "core/alloc.h"
#include "core/math.h"

/* The directions within `angle` (radians) of `axis` (unit); angle >= pi/2 bounds nothing useful. */
typedef struct plait_cone {
	vec3 axis;
	float angle;
} plait_cone;

/* A point of a patch: weights of one of its triangles' vertices (triangle -1: none). */
typedef struct plait_patch_centre {
	int triangle;
	float weight[3];
} plait_patch_centre;

typedef struct plait_flat_patches {
	int node_count;
	int triangle_count;
	int (*triangles)[3]; /* particle indices, in the tree's element numbering */
	/* Node n's contour: the particles contour[contour_first[n] .. contour_first[n + 1]) in the
	 * order its triangles run round it (empty: never flat). Its notches: the triangles
	 * notch[notch_first[n] .. notch_first[n + 1]). */
	int *contour_first, *contour;
	int *notch_first, *notch;
	/* Per node: the centre its contour is star-shaped round in the rest shape, if any (else the
	 * contour's mean is tried). */
	plait_patch_centre *centre;
	plait_cone *patch_cone;     /* per node: its own triangles' normals (refitted; notches' when tested) */
	int *node_begin, *node_end; /* per node: its triangles, order[node_begin .. node_end) */
	int *order;                 /* the tree's order of triangles */
} plait_flat_patches;

/* Where each vertex may be while a list serves: within guard[i] of the straight path from
 * at[i] - back motion[i] to at[i] + on motion[i] (all vertices at the same point of their paths
 * at any one time). guard NULL: on the paths; motion NULL: standing at `at`. */
/* A triangle's normal over the paths: with its vertices moving straight it is
 * n(s) = sum B_k(s) n[k] (quadratic Bernstein basis), so inside the cone of n[0], n[1], n[2];
 * the guards and rounding add a vector of length at most rho to it. */
typedef struct plait_triangle_normals {
	vec3 n[3];
	float rho;
} plait_triangle_normals;

typedef struct plait_patch_paths {
	const vec3 *at;
	const vec3 *motion;
	const float *guard;
	float back, on;
	/* Per triangle (the patches' numbering), its normals over these paths when found already
	 * (plait_flat_patches_normals), so that patches of two trees over one mesh share them; or
	 * NULL. */
	const plait_triangle_normals *normals;
} plait_patch_paths;

/* Builds the patches of `tree`'s nodes over its triangles (particle indices, the tree's element
 * numbering), their centres chosen in the rest shape (per particle; NULL: none). Returns false
 * when out of memory (fp is then empty). */
bool plait_flat_patches_build(plait_flat_patches *fp, const plait_allocator *allocator,
                              const plait_element_tree *tree, const int (*triangles)[3], int triangle_count,
                              const vec3 *rest);
void plait_flat_patches_destroy(plait_flat_patches *fp, const plait_allocator *allocator);

/* The normals over the paths of triangles [begin, end) (the patches' numbering), into out[]:
 * the same to the bit as the fits find them. Each triangle alone: ranges side by side. */
void plait_flat_patches_normals(const plait_flat_patches *fp, const plait_patch_paths *paths, int begin,
                                int end, plait_triangle_normals *out);

/* Refits every node's normal cone over the paths: the leaves' from their triangles, the
 * parents' by merging their children's. The same in parts, for workers: each subtree under the
 * roots of a cut (plait_element_tree_cut; side by side), then the nodes above them (one caller).
 * A node's cone depends only on its children's or its triangles, so the cones are the same. */
void plait_flat_patches_fit(plait_flat_patches *fp, const plait_element_tree *tree,
                            const plait_patch_paths *paths);
void plait_flat_patches_fit_subtree(plait_flat_patches *fp, const plait_element_tree *tree,
                                    const plait_patch_paths *paths, int root);
void plait_flat_patches_fit_above(plait_flat_patches *fp, const plait_element_tree *tree, int levels);

/* Whether node `node`'s patch cannot touch itself anywhere on the paths (the last fit's cones,
 * and its contour checked here); *axis (unless NULL): the direction it faces. Reads only: safe
 * from several threads at once. */
bool plait_flat_patches_flat(const plait_flat_patches *fp, int node, const plait_patch_paths *paths,
                             vec3 *axis);

/* The same along other paths for a patch found flat facing `axis` (no fit needed): every
 * triangle still faces it all along them, and the contour is still star-shaped. */
bool plait_flat_patches_keeps_flat(const plait_flat_patches *fp, int node, vec3 axis,
                                   const plait_patch_paths *paths);

/* A cone holding both, about the smallest (angle >= pi/2 when none under a right angle does). */
plait_cone plait_cone_merge(plait_cone a, plait_cone b);

/* The fast arctangent the cones are measured with: atan2(y, x) for y >= 0 (for tests). */
float plait_flat_patches_atan2(float y, float x);

#endif
