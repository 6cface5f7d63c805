/* Writing simulated frames to files. A table of formats (obj, pc2) behind one interface:
 * open for a world, write frame after frame, close. Colliders are written as their surface
 * meshes (plait_collider_get_surface_*), which follow their keyframes. */
#ifndef PLAIT_WRITERS_H
#define PLAIT_WRITERS_H

#include "tool_error.h"

#include <plait/plait.h>
#include <stdbool.h>

/* One object whose vertices are written, with what was read once at open. */
typedef struct plait_output_object {
	plait_object_id id;
	int world_index; /* plait_world_get_object(world, world_index) == id */
	plait_object_type type;
	char name[64];
	int vertex_count; /* a collider's: its surface's */
	int *face_sizes;  /* cloth: its faces; collider: its surface's triangles */
	int *face_indices;
	int face_count;
} plait_output_object;

typedef struct plait_writer plait_writer;

typedef struct plait_writer_format {
	const char *name;
	const char *description;
	bool (*open)(plait_writer *writer, plait_tool_error *error);
	bool (*write_frame)(plait_writer *writer, int frame, plait_tool_error *error);
	bool (*close)(plait_writer *writer, plait_tool_error *error); /* keeps what was written */
} plait_writer_format;

struct plait_writer {
	const plait_writer_format *format;
	char *dir;
	plait_world_id world;
	plait_output_object *objects;
	int object_count;
	plait_vec3 *positions; /* scratch, large enough for any object */
	void *state;           /* the format's own */
	int frames_written;
};

/* The formats, by name ("obj", "pc2"); NULL when unknown. */
const plait_writer_format *plait_writer_find_format(const char *name);
int plait_writer_format_count(void);
const plait_writer_format *plait_writer_format_at(int index);

/* The folder must exist. Returns NULL on failure, having written nothing. */
plait_writer *plait_writer_open(const plait_writer_format *format, const char *dir, plait_world_id world,
                                plait_tool_error *error);
/* Writes the world's current state as frame. */
bool plait_writer_write_frame(plait_writer *writer, int frame, plait_tool_error *error);
/* Finishes every file (frames written so far stay) and frees the writer. */
bool plait_writer_close(plait_writer *writer, plait_tool_error *error);

/* Reads an output object's positions into writer->positions. */
bool plait_writer_read_positions(plait_writer *writer, const plait_output_object *object,
                                 plait_tool_error *error);

/* Writes the object as it is now to DIR/file_name in OBJ (writer_obj.c): the frame files of
 * --format obj, and the meshes that go with --format pc2's point caches. */
bool plait_writer_write_obj(plait_writer *writer, const plait_output_object *object, const char *file_name,
                            int frame, plait_tool_error *error);

extern const plait_writer_format plait_writer_obj;
extern const plait_writer_format plait_writer_pc2;

#endif
