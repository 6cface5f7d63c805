/* Checking one frame read back from files: crossing triangles between objects (cloth against
 * cloth and against collider surfaces) and within each cloth (triangles that share no vertex),
 * and vertices of cloth, curves and particles inside colliders. Objects that do not collide are
 * left out. The counts are exact for what the files hold: triangle pairs by
 * plait_triangles_intersect, and vertices against each collider's exact shape for planes
 * (below them), spheres, capsules and boxes, or by ray parity against a closed mesh. */
#ifndef PLAIT_FRAME_CHECK_H
#define PLAIT_FRAME_CHECK_H

#include "box_tree.h"
#include "frame_reader.h"
#include "manifest.h"

typedef struct plait_frame_counts {
	int intersections;    /* between_objects plus every cloth's self intersections */
	int between_objects;  /* crossing triangle pairs of two different objects */
	int inside_colliders; /* (vertex, collider) pairs with the vertex inside by more than tolerance */
	int *pairs;  /* object_count^2: [a * n + b], a <= b, pairs between a and b; [a * n + a] within a */
	int *inside; /* object_count: vertices inside collider c */
} plait_frame_counts;

typedef struct plait_frame_triangle {
	int object;
	int v[3]; /* into the checker's positions: every object's vertices back to back */
} plait_frame_triangle;

/* Scratch kept from frame to frame. */
typedef struct plait_frame_checker {
	const plait_manifest *manifest;
	double tolerance;  /* scene units */
	int *first_vertex; /* per object, into positions */
	plait_vec3 *positions;
	int position_capacity;
	plait_frame_triangle *triangles;
	plait_box *boxes;
	int triangle_capacity, box_capacity;
	plait_box_tree tree;
	/* A closed mesh collider's own triangles, for ray parity. */
	plait_frame_triangle *collider_triangles;
	plait_box *collider_boxes;
	int collider_capacity, collider_box_capacity;
	plait_box_tree collider_tree;
	plait_frame_counts counts;
} plait_frame_checker;

/* tolerance_m: how deep, in metres, a vertex must be inside a collider to count. */
bool plait_frame_checker_init(plait_frame_checker *checker, const plait_manifest *manifest,
                              double tolerance_m, plait_tool_error *error);
void plait_frame_checker_free(plait_frame_checker *checker);

/* Counts frame (the meshes as read for it) into checker->counts. */
bool plait_frame_check(plait_frame_checker *checker, const plait_frame_mesh *meshes, int frame,
                       plait_tool_error *error);

#endif
