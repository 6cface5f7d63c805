/* Scene files: a JSON description of a world and its objects, loaded into plain data and fully
 * validated before any world exists, then turned into a world through the public API.
 * docs/scene-format.md is the reference of every key. */
#ifndef PLAIT_SCENE_H
#define PLAIT_SCENE_H

#include "mesh_sequence.h"
#include "tool_error.h"

#include <plait/plait.h>
#include <stdbool.h>

#define PLAIT_SCENE_NAME_SIZE 64

/* Frames simulated when the scene does not say (5 s at 24 fps). */
#define PLAIT_SCENE_DEFAULT_FRAMES 120

/* A collider transform at one frame; between keyframes the transform is interpolated linearly. */
typedef struct plait_scene_keyframe {
	int frame;
	plait_transform transform;
} plait_scene_keyframe;

/* One object with all its values. Only the def matching type is used; its array pointers are
 * left NULL here and pointed at the arrays below when the world is created. */
typedef struct plait_scene_object {
	plait_object_type type;
	char name[PLAIT_SCENE_NAME_SIZE];
	plait_cloth_def cloth;
	plait_curve_def curve;
	plait_particles_def particles;
	plait_collider_def collider;

	/* Cloth, curve and particles: start positions (scene units) and optional velocities. */
	plait_vec3 *positions;
	int vertex_count;
	plait_vec3 *velocities; /* NULL or vertex_count entries */

	/* Cloth faces (polygon soup, 0-based). */
	int *face_sizes;
	int face_count;
	int *face_indices;
	int index_count;

	/* Vertices held at their start position. */
	int *pins;
	int pin_count;

	/* Colliders: keyframes in increasing frame order (may be none). */
	plait_scene_keyframe *keyframes;
	int keyframe_count;

	/* Cloth from a mesh file: the path as resolved against the scene's folder; NULL for grids. */
	char *mesh_path;

	/* Deforming mesh colliders: the shape at the end of each frame from 1, in the vertices of
	 * the mesh (frame_count 0 for a rigid collider). */
	plait_mesh_sequence sequence;
} plait_scene_object;

typedef struct plait_scene {
	char *file; /* the name used in messages */
	plait_world_def world;
	int frames; /* frames to simulate after frame 0 */
	plait_scene_object *objects;
	int object_count;
	/* Problems that did not stop loading (e.g. dropped degenerate faces), full sentences. */
	char **warnings;
	int warning_count;
} plait_scene;

/* Loads and validates a scene file. On failure returns false, fills error, and leaves *scene
 * empty (nothing to free). */
bool plait_scene_load(const char *path, plait_scene *scene, plait_tool_error *error);

/* Same from JSON text; file names it in messages, base_dir resolves relative mesh paths. */
bool plait_scene_load_string(const char *json_text, const char *file, const char *base_dir,
                             plait_scene *scene, plait_tool_error *error);

void plait_scene_free(plait_scene *scene);

/* Creates the world and every object in scene order, so world object i is scene object i. On
 * failure nothing is left behind and *world is null. */
bool plait_scene_create_world(const plait_scene *scene, plait_world_id *world, plait_tool_error *error);

/* Call before stepping to frame `frame`: sets collider transforms from keyframes and the shapes
 * of deforming colliders from their sequences for that frame, and holds pinned vertices at
 * their start positions. */
bool plait_scene_apply_frame(const plait_scene *scene, plait_world_id world, int frame,
                             plait_tool_error *error);

/* The transform of a collider at frame: linear between keyframes, held outside their range,
 * identity without keyframes. */
plait_transform plait_scene_collider_transform(const plait_scene_object *object, int frame);

#endif
