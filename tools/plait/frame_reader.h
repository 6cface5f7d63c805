/* Reading back the frames `plait run` wrote, as the manifest lists them: OBJ files per object
 * and frame, or PC2 point caches with the OBJ meshes beside them. Anything cut short or out of
 * range is an error naming the file; nothing is trusted. */
#ifndef PLAIT_FRAME_READER_H
#define PLAIT_FRAME_READER_H

#include "manifest.h"
#include "tool_error.h"

#include <plait/plait.h>
#include <stdbool.h>
#include <stdio.h>

/* One object in one frame: its vertices and its faces fanned into triangles. */
typedef struct plait_frame_mesh {
	plait_vec3 *positions;
	int vertex_count, vertex_capacity;
	int (*triangles)[3];
	int triangle_count, triangle_capacity;
} plait_frame_mesh;

typedef struct plait_frame_reader {
	char *dir;
	const plait_manifest *manifest;
	plait_frame_mesh *meshes; /* one per manifest object */
	FILE **caches;            /* pc2: one per object */
	char *text;               /* scratch: the OBJ file being read */
	size_t text_capacity;
	unsigned char *sample; /* scratch: one PC2 sample */
} plait_frame_reader;

/* For pc2, opens the caches, checks their headers against the manifest and reads the faces
 * from the meshes beside them. */
bool plait_frame_reader_open(plait_frame_reader *reader, const char *dir, const plait_manifest *manifest,
                             plait_tool_error *error);
/* Fills reader->meshes with frame (first_frame <= frame <= last_frame). */
bool plait_frame_reader_read(plait_frame_reader *reader, int frame, plait_tool_error *error);
void plait_frame_reader_close(plait_frame_reader *reader);

/* Parses OBJ text (NUL-terminated, size bytes) into mesh: "v x y z" and "f i j k ..." lines
 * (1-based or negative indices, "i/t/n" forms), the rest ignored. path names it in messages. */
bool plait_obj_parse(const char *text, size_t size, const char *path, plait_frame_mesh *mesh,
                     plait_tool_error *error);

#endif
