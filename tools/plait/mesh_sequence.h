/* Mesh sequences: the shape of a deforming mesh collider frame by frame, one mesh file per
 * frame, named by a pattern with one frame number ("arm.%04d.obj"). Every file is read and
 * checked against the collider's mesh when the scene loads, so a run never stops on one. */
#ifndef PLAIT_MESH_SEQUENCE_H
#define PLAIT_MESH_SEQUENCE_H

#include "mesh_io.h"
#include "tool_error.h"

#include <stdbool.h>
#include <stddef.h>

/* A file name pattern: literal text around one frame number, at least width digits (padded
 * with zeros when zero_pad, else the plain number). */
typedef struct plait_frame_pattern {
	char *folder; /* the folder part, without the final '/' ("." when there is none) */
	char *prefix; /* file name text before the number */
	char *suffix; /* file name text after it */
	int width;
	bool zero_pad;
} plait_frame_pattern;

/* Parses a pattern path, relative to base_dir unless absolute: printf style with exactly one %d
 * or %0Nd (N from 1 to 9) in the file name part, and %% for a literal %. On failure returns
 * false with the reason in why. */
bool plait_frame_pattern_parse(const char *base_dir, const char *pattern, plait_frame_pattern *parsed,
                               char *why, size_t why_size);
void plait_frame_pattern_free(plait_frame_pattern *pattern);

/* The path of frame's file. */
void plait_frame_pattern_path(const plait_frame_pattern *pattern, int frame, char *path, size_t size);

typedef struct plait_mesh_sequence {
	int frame_count;       /* the files of frames 1 to frame_count */
	int vertex_count;      /* per frame */
	plait_vec3 *positions; /* frame f (from 1) starts at (f - 1) * vertex_count */
} plait_mesh_sequence;

/* Finds the pattern's files (frame numbers 1 to 1000000; a file for frame 0 is not read) and
 * reads them all into the layout's vertices. They must run from frame 1 without a gap. Fails
 * with a message naming the file: one missing, or unreadable, or with other faces. */
bool plait_mesh_sequence_load(const plait_frame_pattern *pattern, const plait_mesh_layout *layout,
                              plait_mesh_sequence *sequence, plait_tool_error *error);
void plait_mesh_sequence_free(plait_mesh_sequence *sequence);

/* The positions at the end of frame (>= 1): after the last file, the last shape holds. */
const plait_vec3 *plait_mesh_sequence_frame(const plait_mesh_sequence *sequence, int frame);

#endif
