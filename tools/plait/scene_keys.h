/* The valid keys of every JSON object in a scene file, with kinds, ranges and destinations.
 * One table per context; docs/scene-format.md has one table per context too. */
#ifndef PLAIT_SCENE_KEYS_H
#define PLAIT_SCENE_KEYS_H

#include "scene_reader.h"

typedef enum plait_scene_context {
	PLAIT_CONTEXT_TOP = 0, /* destination: plait_scene */
	PLAIT_CONTEXT_WORLD,   /* plait_world_def */
	PLAIT_CONTEXT_WIND,    /* plait_world_def (wind.*) */
	PLAIT_CONTEXT_CLOTH,   /* plait_cloth_def */
	PLAIT_CONTEXT_GRID,    /* plait_grid_def */
	PLAIT_CONTEXT_CURVE,   /* plait_curve_def */
	PLAIT_CONTEXT_PARTICLES,
	PLAIT_CONTEXT_COLLIDER,
	PLAIT_CONTEXT_KEYFRAME, /* plait_scene_keyframe */
	PLAIT_CONTEXT_COUNT,
} plait_scene_context;

/* The key table of a context and its length. */
const plait_scene_key *plait_scene_keys(plait_scene_context context, int *count);

/* A context's name as the docs' headings use it ("world", "cloth", "grid", ...). */
const char *plait_scene_context_name(plait_scene_context context);

#endif
