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

#endif
