#include "scene.h"

#include "scene_keys.h"
#include "scene_parse.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const plait_type_names[] = {"cloth", "curve", "particles", "collider"};

bool plait_scene_warn(plait_scene_loader *loader, const char *format, ...)
{
	char detail[PLAIT_TOOL_ERROR_SIZE];
	va_list args;
	va_start(args, format);
	vsnprintf(detail, sizeof detail, format, args);
	va_end(args);
	plait_scene *scene = loader->scene;
	char **grown = realloc(scene->warnings, sizeof(char *) * (size_t)(scene->warning_count + 1));
	if (grown == NULL)
		return false;
	scene->warnings = grown;
	size_t size = strlen(loader->reader.file) + strlen(loader->reader.path) + strlen(detail) + 8;
	char *text = malloc(size);
	if (text == NULL)
		return false;
	snprintf(text, size, "%s: %s: %s", loader->reader.file, loader->reader.path, detail);
	scene->warnings[scene->warning_count++] = text;
	return true;
}

// Names become output file names, so they stay in a portable file-name alphabet.
static bool plait_name_is_valid(const char *name)
{
	size_t length = strlen(name);
	if (length == 0 || length >= PLAIT_SCENE_NAME_SIZE || name[0] == '.')
		return false;
	for (size_t i = 0; i < length; ++i) {
		char c = name[i];
		bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
		          c == '-' || c == '.';
		if (!ok)
			return false;
	}
	return true;
}

static bool plait_parse_name(plait_scene_loader *loader, const json_t *json, int index,
                             plait_scene_object *object)
{
	plait_scene_reader *r = &loader->reader;
	const json_t *value = json_object_get(json, "name");
	if (value == NULL) {
		snprintf(object->name, sizeof object->name, "%s%d", plait_type_names[object->type], index);
	} else {
		size_t old = plait_reader_push_key(r, "name");
		if (!json_is_string(value) || !plait_name_is_valid(json_string_value(value))) {
			char got[64];
			plait_json_describe(value, got, sizeof got);
			plait_reader_fail(
			    r,
			    "expected a name of 1 to %d letters, digits, '_', '-' or '.' not starting with '.' "
			    "(it names output files), got %s",
			    PLAIT_SCENE_NAME_SIZE - 1, got);
			return false;
		}
		snprintf(object->name, sizeof object->name, "%s", json_string_value(value));
		plait_reader_pop(r, old);
	}
	for (int i = 0; i < index; ++i) {
		if (strcmp(loader->scene->objects[i].name, object->name) == 0) {
			size_t old = plait_reader_push_key(r, "name");
			plait_reader_fail(r, "\"%s\" is already the name of objects[%d]; names must be unique",
			                  object->name, i);
			plait_reader_pop(r, old);
			return false;
		}
	}
	return true;
}

static bool plait_parse_object(plait_scene_loader *loader, const json_t *json, int index)
{
	plait_scene_reader *r = &loader->reader;
	plait_scene_object *object = &loader->scene->objects[index];
	if (!plait_reader_expect_object(r, json))
		return false;
	// The type decides which keys are valid, so it is read before anything else.
	const json_t *type = json_object_get(json, "type");
	size_t old = plait_reader_push_key(r, "type");
	if (type == NULL) {
		plait_reader_fail(r, "required key is missing (expected one of cloth, curve, particles, collider)");
		return false;
	}
	int type_index;
	if (!plait_reader_choice(r, type, plait_type_names, 4, &type_index))
		return false;
	plait_reader_pop(r, old);
	object->type = (plait_object_type)type_index;

	static const plait_scene_context contexts[] = {PLAIT_CONTEXT_CLOTH, PLAIT_CONTEXT_CURVE,
	                                               PLAIT_CONTEXT_PARTICLES, PLAIT_CONTEXT_COLLIDER};
	int key_count;
	const plait_scene_key *keys = plait_scene_keys(contexts[type_index], &key_count);
	if (!plait_reader_check_keys(r, json, keys, key_count) || !plait_parse_name(loader, json, index, object))
		return false;
	switch (object->type) {
	case PLAIT_OBJECT_CLOTH:
		object->cloth = plait_default_cloth_def();
		return plait_reader_read_keys(r, json, keys, key_count, &object->cloth) &&
		       plait_scene_parse_cloth(loader, json, object);
	case PLAIT_OBJECT_CURVE:
		object->curve = plait_default_curve_def();
		return plait_reader_read_keys(r, json, keys, key_count, &object->curve) &&
		       plait_scene_parse_curve(loader, json, object);
	case PLAIT_OBJECT_PARTICLES:
		object->particles = plait_default_particles_def();
		return plait_reader_read_keys(r, json, keys, key_count, &object->particles) &&
		       plait_scene_parse_particles(loader, json, object);
	case PLAIT_OBJECT_COLLIDER:
		object->collider = plait_default_collider_def();
		return plait_reader_read_keys(r, json, keys, key_count, &object->collider) &&
		       plait_scene_parse_collider(loader, json, object);
	}
	return false;
}

static bool plait_parse_world(plait_scene_loader *loader, const json_t *json)
{
	plait_scene_reader *r = &loader->reader;
	plait_world_def *world = &loader->scene->world;
	int count;
	const plait_scene_key *keys = plait_scene_keys(PLAIT_CONTEXT_WORLD, &count);
	if (!plait_reader_expect_object(r, json) || !plait_reader_check_keys(r, json, keys, count) ||
	    !plait_reader_read_keys(r, json, keys, count, world))
		return false;
	const json_t *wind = json_object_get(json, "wind");
	if (wind != NULL) {
		size_t old = plait_reader_push_key(r, "wind");
		keys = plait_scene_keys(PLAIT_CONTEXT_WIND, &count);
		if (!plait_reader_expect_object(r, wind) || !plait_reader_check_keys(r, wind, keys, count) ||
		    !plait_reader_read_keys(r, wind, keys, count, world))
			return false;
		plait_reader_pop(r, old);
	}
	return true;
}

static bool plait_parse_scene(plait_scene_loader *loader, const json_t *root)
{
	plait_scene_reader *r = &loader->reader;
	plait_scene *scene = loader->scene;
	if (!json_is_object(root)) {
		char got[64];
		plait_json_describe(root, got, sizeof got);
		return plait_reader_fail(r, "expected an object {...} at the top level, got %s", got);
	}
	int count;
	const plait_scene_key *keys = plait_scene_keys(PLAIT_CONTEXT_TOP, &count);
	if (!plait_reader_check_keys(r, root, keys, count) ||
	    !plait_reader_read_keys(r, root, keys, count, scene))
		return false;
	const json_t *world = json_object_get(root, "world");
	if (world != NULL) {
		size_t old = plait_reader_push_key(r, "world");
		if (!plait_parse_world(loader, world))
			return false;
		plait_reader_pop(r, old);
	}
	const json_t *objects = json_object_get(root, "objects");
	size_t old = plait_reader_push_key(r, "objects");
	if (!json_is_array(objects) || json_array_size(objects) == 0 || json_array_size(objects) > 100000) {
		char got[64];
		plait_json_describe(objects, got, sizeof got);
		return plait_reader_fail(r, "expected a non-empty array of objects, got %s", got);
	}
	size_t n = json_array_size(objects);
	scene->objects = calloc(n, sizeof *scene->objects);
	if (scene->objects == NULL)
		return plait_reader_fail(r, "out of memory");
	scene->object_count = (int)n;
	for (size_t i = 0; i < n; ++i) {
		size_t at = plait_reader_push_index(r, i);
		if (!plait_parse_object(loader, json_array_get(objects, i), (int)i))
			return false;
		plait_reader_pop(r, at);
	}
	plait_reader_pop(r, old);
	return true;
}

bool plait_scene_load_string(const char *json_text, const char *file, const char *base_dir,
                             plait_scene *scene, plait_tool_error *error)
{
	*scene = (plait_scene){0};
	json_error_t json_error;
	json_t *root = json_loads(json_text, JSON_REJECT_DUPLICATES, &json_error);
	if (root == NULL)
		return plait_tool_error_set(error, "%s:%d:%d: JSON syntax error: %s", file, json_error.line,
		                            json_error.column, json_error.text);
	scene->file = strdup(file);
	scene->world = plait_default_world_def();
	scene->frames = PLAIT_SCENE_DEFAULT_FRAMES;
	plait_scene_loader loader = {
	    .reader = {.file = file, .error = error}, .base_dir = base_dir, .scene = scene};
	bool ok =
	    scene->file != NULL ? plait_parse_scene(&loader, root) : plait_tool_error_set(error, "out of memory");
	json_decref(root);
	if (!ok)
		plait_scene_free(scene);
	return ok;
}

bool plait_scene_load(const char *path, plait_scene *scene, plait_tool_error *error)
{
	*scene = (plait_scene){0};
	FILE *file = fopen(path, "rb");
	if (file == NULL)
		return plait_tool_error_set(error, "%s: cannot open scene file: %s", path, strerror(errno));
	char *text = NULL;
	size_t length = 0, capacity = 0;
	for (;;) {
		if (length + 4096 + 1 > capacity) {
			capacity = capacity > 0 ? capacity * 2 : 65536;
			char *grown = realloc(text, capacity);
			if (grown == NULL) {
				free(text);
				fclose(file);
				return plait_tool_error_set(error, "%s: out of memory reading the scene file", path);
			}
			text = grown;
		}
		size_t got = fread(text + length, 1, capacity - length - 1, file);
		length += got;
		if (got == 0)
			break;
	}
	bool read_failed = ferror(file) != 0;
	fclose(file);
	if (read_failed) {
		free(text);
		return plait_tool_error_set(error, "%s: cannot read scene file", path);
	}
	text[length] = '\0';
	if (strlen(text) != length) {
		free(text);
		return plait_tool_error_set(error, "%s: not a text file (contains a NUL byte)", path);
	}
	// Mesh paths are relative to the scene file's folder.
	char *base_dir = strdup(path);
	if (base_dir == NULL) {
		free(text);
		return plait_tool_error_set(error, "out of memory");
	}
	char *slash = strrchr(base_dir, '/');
	if (slash == NULL)
		strcpy(base_dir, ".");
	else if (slash == base_dir)
		base_dir[1] = '\0';
	else
		*slash = '\0';
	bool ok = plait_scene_load_string(text, path, base_dir, scene, error);
	free(base_dir);
	free(text);
	return ok;
}

void plait_scene_free(plait_scene *scene)
{
	for (int i = 0; i < scene->object_count; ++i) {
		plait_scene_object *object = &scene->objects[i];
		free(object->positions);
		free(object->velocities);
		free(object->face_sizes);
		free(object->face_indices);
		free(object->pins);
		free(object->keyframes);
		free(object->mesh_path);
		plait_mesh_sequence_free(&object->sequence);
	}
	for (int i = 0; i < scene->warning_count; ++i)
		free(scene->warnings[i]);
	free(scene->warnings);
	free(scene->objects);
	free(scene->file);
	*scene = (plait_scene){0};
}
