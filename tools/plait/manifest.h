/* DIR/manifest.json: what `plait run` wrote, so that `plait check` can read the frames back
 * without the scene: the format, the frames, and for each object its name, type, files, and for
 * colliders their shape where they were at each frame. docs/scene-format.md describes the file.
 * It is written last, when the frames are complete, and removed when a run starts: a folder
 * whose run was interrupted has none. */
#ifndef PLAIT_MANIFEST_H
#define PLAIT_MANIFEST_H

#include "scene.h"
#include "tool_error.h"
#include "writers.h"

#include <plait/plait.h>
#include <stdbool.h>

#define PLAIT_MANIFEST_NAME "manifest.json"
#define PLAIT_MANIFEST_VERSION 1
#define PLAIT_MANIFEST_FILE_SIZE 96

typedef struct plait_manifest_object {
	char name[64];
	plait_object_type type;
	bool collide;     /* takes part in collisions; `plait check` skips the others */
	int vertex_count; /* a collider's: its surface mesh's */
	/* obj: the frame files' name with "%04d" where the frame goes; pc2: the point cache. */
	char file[PLAIT_MANIFEST_FILE_SIZE];
	char mesh[PLAIT_MANIFEST_FILE_SIZE]; /* pc2: the OBJ with the faces; empty for obj */
	/* Colliders. */
	plait_shape_type shape;
	bool closed;                  /* has an inside (plait_collider_is_closed) */
	plait_collider_shape *shapes; /* one per frame, first_frame on; NULL for meshes */
	int shape_capacity;
} plait_manifest_object;

typedef struct plait_manifest {
	char format[8];              /* "obj" or "pc2" */
	int first_frame, last_frame; /* last < first: no frame */
	float fps, space_scale;
	plait_manifest_object *objects;
	int object_count;
} plait_manifest;

void plait_manifest_free(plait_manifest *manifest);

/* `plait run`: removes any old manifest from the writer's folder (so an interrupted run leaves
 * none) and lists the writer's objects, with collide flags from the scene. */
bool plait_manifest_begin(plait_manifest *manifest, const plait_writer *writer, const plait_scene *scene,
                          plait_tool_error *error);
/* After the writer wrote frame: records where each collider is. */
bool plait_manifest_record_frame(plait_manifest *manifest, const plait_writer *writer, int frame,
                                 plait_tool_error *error);
/* Writes DIR/manifest.json for the frames recorded. */
bool plait_manifest_commit(const plait_manifest *manifest, const char *dir, plait_tool_error *error);

/* `plait check`: reads and validates DIR/manifest.json. Messages name the file. */
bool plait_manifest_load(const char *dir, plait_manifest *manifest, plait_tool_error *error);

/* The file of object's frame, for obj (the "%04d" filled in); false if it does not fit. */
bool plait_manifest_frame_file(const plait_manifest_object *object, int frame, char *out, size_t size);

#endif
