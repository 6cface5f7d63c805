/* Internal to the scene loader: shared state and the per-type object parsers. */
#ifndef PLAIT_SCENE_PARSE_H
#define PLAIT_SCENE_PARSE_H

#include "scene.h"
#include "scene_reader.h"

typedef struct plait_scene_loader {
	plait_scene_reader reader;
	const char *base_dir; /* folder that relative mesh paths start from */
	plait_scene *scene;
} plait_scene_loader;

/* Each reads the type-specific keys of one object (the reader's path is at the object). */
bool plait_scene_parse_cloth(plait_scene_loader *loader, const json_t *json, plait_scene_object *object);
bool plait_scene_parse_curve(plait_scene_loader *loader, const json_t *json, plait_scene_object *object);
bool plait_scene_parse_particles(plait_scene_loader *loader, const json_t *json, plait_scene_object *object);
bool plait_scene_parse_collider(plait_scene_loader *loader, const json_t *json, plait_scene_object *object);

/* Appends a warning ("FILE: PATH: text") to the scene; false when out of memory. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
bool plait_scene_warn(plait_scene_loader *loader, const char *format, ...);

#endif
