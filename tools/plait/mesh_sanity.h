/* Cheap checks before assimp reads a file. Some formats declare element counts in a header and
 * assimp allocates for them up front: a corrupt OFF header of 10^12 vertices costs it minutes
 * and tens of gigabytes before failing. Counts no file of this size can hold are refused here. */
#ifndef PLAIT_MESH_SANITY_H
#define PLAIT_MESH_SANITY_H

#include "tool_error.h"

#include <stdbool.h>

/* False (with a message naming the file) when an OFF or PLY header declares more elements than
 * the file's size allows; true for every other file. */
bool plait_mesh_check_header(const char *path, plait_tool_error *error);

#endif
