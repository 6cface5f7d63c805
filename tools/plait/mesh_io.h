/* Reading cloth meshes from files through assimp (OBJ, PLY, OFF, glTF, ...). */
#ifndef PLAIT_MESH_IO_H
#define PLAIT_MESH_IO_H

#include "soup.h"
#include "tool_error.h"

#include <stdbool.h>

/* What loading dropped or merged without failing; the caller decides how to warn. */
typedef struct plait_mesh_report {
	int degenerate_faces; /* repeated vertex or zero area: dropped */
	int point_line_faces; /* primitives with fewer than 3 vertices: dropped */
	int unused_vertices;  /* vertices no remaining face uses: removed */
	int mesh_count;       /* meshes in the file, merged into one soup */
} plait_mesh_report;

/* Loads every mesh of the file (with node transforms applied) into one polygon soup. Polygons
 * are kept as they are (quads stay quads); vertices at exactly the same position are merged,
 * also across meshes, so a mesh split by materials or normals stays one piece of cloth.
 * Fails with a message naming the file for a missing or unreadable file, no meshes, an index
 * out of range, a non-finite coordinate, or no usable face. */
bool plait_mesh_load(const char *path, plait_soup *soup, plait_mesh_report *report, plait_tool_error *error);

/* How a file's vertices became a soup's: what it takes to read another file of the same mesh (a
 * frame of an animation) into the same vertices, matching them by their place in the file
 * rather than by position, so that nothing is merged or dropped differently from frame to frame. */
typedef struct plait_mesh_layout {
	char *path;                               /* the file it was made from */
	int vertex_count, face_count;             /* of the soup */
	int file_vertex_count;                    /* as the file lists them (OBJ: per face corner) */
	int file_face_count, file_index_count;    /* faces as listed, before any was dropped */
	int *file_face_sizes, *file_face_indices; /* in file vertices */
	int *vertex_of; /* per file vertex: the soup vertex it became, or -1 (removed) */
} plait_mesh_layout;

/* plait_mesh_load that also fills layout (free with plait_mesh_layout_free) when not NULL. */
bool plait_mesh_load_layout(const char *path, plait_soup *soup, plait_mesh_report *report,
                            plait_mesh_layout *layout, plait_tool_error *error);
void plait_mesh_layout_free(plait_mesh_layout *layout);

/* Reads the vertex positions of a file with the layout's faces over the same vertices into
 * positions (layout->vertex_count of them). Fails with a message naming the file when it cannot
 * be read (as plait_mesh_load) or its faces differ: other counts, or vertices joined otherwise. */
bool plait_mesh_load_positions(const char *path, const plait_mesh_layout *layout, plait_vec3 *positions,
                               plait_tool_error *error);

#endif
