/* Reading DIR/manifest.json for `plait check`: every value is checked, since the file may have
 * been edited, cut short or written by something else. */
#include "manifest.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const plait_type_words[] = {"cloth", "curve", "particles", "collider"};
static const char *const plait_shape_words[] = {"plane", "sphere", "capsule", "box", "mesh"};

// Frames and vertices far beyond any run, which keeps a corrupt count from asking for the moon.
#define PLAIT_MANIFEST_MAX_FRAMES 1000001
#define PLAIT_MANIFEST_MAX_VERTICES 50000000

typedef struct plait_manifest_reader {
	const char *path;
	plait_tool_error *error;
} plait_manifest_reader;

static bool plait_manifest_fail(plait_manifest_reader *r, const char *where, const char *what)
{
	return plait_tool_error_set(r->error, "%s: %s: %s", r->path, where, what);
}

static bool plait_read_int(plait_manifest_reader *r, const json_t *json, const char *key, const char *where,
                           long long low, long long high, int *out)
{
	const json_t *value = json_object_get(json, key);
	char place[160];
	snprintf(place, sizeof place, "%.100s%.40s", where, key); // key paths are short
	if (!json_is_integer(value) || json_integer_value(value) < low || json_integer_value(value) > high) {
		char what[96];
		snprintf(what, sizeof what, "expected an integer from %lld to %lld", low, high);
		return plait_manifest_fail(r, place, what);
	}
	*out = (int)json_integer_value(value);
	return true;
}

static bool plait_read_number(plait_manifest_reader *r, const json_t *value, const char *where, float *out)
{
	if (!json_is_number(value) || !isfinite(json_number_value(value)))
		return plait_manifest_fail(r, where, "expected a finite number");
	*out = (float)json_number_value(value);
	return true;
}

static bool plait_read_vec3_value(plait_manifest_reader *r, const json_t *value, const char *place,
                                  plait_vec3 *out)
{
	if (!json_is_array(value) || json_array_size(value) != 3)
		return plait_manifest_fail(r, place, "expected [x, y, z]");
	float v[3];
	for (size_t k = 0; k < 3; ++k)
		if (!plait_read_number(r, json_array_get(value, k), place, &v[k]))
			return false;
	*out = (plait_vec3){v[0], v[1], v[2]};
	return true;
}

static bool plait_read_vec3(plait_manifest_reader *r, const json_t *json, const char *key, const char *where,
                            plait_vec3 *out)
{
	char place[160];
	snprintf(place, sizeof place, "%.100s%.40s", where, key); // key paths are short
	return plait_read_vec3_value(r, json_object_get(json, key), place, out);
}

static bool plait_read_choice(plait_manifest_reader *r, const json_t *json, const char *key,
                              const char *where, const char *const *words, int count, int *out)
{
	const char *text = json_string_value(json_object_get(json, key));
	for (int i = 0; text != NULL && i < count; ++i) {
		if (strcmp(text, words[i]) == 0) {
			*out = i;
			return true;
		}
	}
	char place[160], what[160];
	snprintf(place, sizeof place, "%.100s%.40s", where, key); // key paths are short
	snprintf(what, sizeof what, "expected one of %s", words[0]);
	for (int i = 1; i < count; ++i)
		snprintf(what + strlen(what), sizeof what - strlen(what), ", %s", words[i]);
	return plait_manifest_fail(r, place, what);
}

// A file beside the manifest: no folders, nothing hidden, and for patterns one "%04d".
static bool plait_read_file_name(plait_manifest_reader *r, const json_t *json, const char *key,
                                 const char *where, bool pattern, char *out, size_t size)
{
	const char *text = json_string_value(json_object_get(json, key));
	char place[160];
	snprintf(place, sizeof place, "%.100s%.40s", where, key); // key paths are short
	if (text == NULL || text[0] == '\0' || text[0] == '.' || strchr(text, '/') != NULL ||
	    strchr(text, '\\') != NULL || strlen(text) >= size)
		return plait_manifest_fail(r, place, "expected the name of a file in the same folder");
	const char *percent = strchr(text, '%');
	bool one_pattern =
	    percent != NULL && strncmp(percent, "%04d", 4) == 0 && strchr(percent + 1, '%') == NULL;
	if (pattern ? !one_pattern : percent != NULL)
		return plait_manifest_fail(r, place,
		                           pattern ? "expected a file name with one %04d where the frame goes"
		                                   : "expected a file name without '%'");
	snprintf(out, size, "%s", text);
	return true;
}

static bool plait_read_shape(plait_manifest_reader *r, const json_t *json, const char *where,
                             plait_shape_type type, plait_collider_shape *shape)
{
	*shape = (plait_collider_shape){.type = type};
	if (!json_is_object(json))
		return plait_manifest_fail(r, where, "expected an object");
	char place[160];
	snprintf(place, sizeof place, "%.100s.", where);
	switch (type) {
	case PLAIT_SHAPE_PLANE:
		return plait_read_vec3(r, json, "point", place, &shape->point) &&
		       plait_read_vec3(r, json, "normal", place, &shape->normal);
	case PLAIT_SHAPE_SPHERE:
		return plait_read_vec3(r, json, "center", place, &shape->center) &&
		       plait_read_number(r, json_object_get(json, "radius"), place, &shape->radius);
	case PLAIT_SHAPE_CAPSULE:
		return plait_read_vec3(r, json, "a", place, &shape->a) &&
		       plait_read_vec3(r, json, "b", place, &shape->b) &&
		       plait_read_number(r, json_object_get(json, "radius"), place, &shape->radius);
	case PLAIT_SHAPE_BOX: {
		if (!plait_read_vec3(r, json, "center", place, &shape->center) ||
		    !plait_read_vec3(r, json, "half_extents", place, &shape->half_extents))
			return false;
		const json_t *axes = json_object_get(json, "axes");
		snprintf(place, sizeof place, "%.100s.axes", where);
		if (!json_is_array(axes) || json_array_size(axes) != 3)
			return plait_manifest_fail(r, place, "expected three [x, y, z]");
		for (size_t k = 0; k < 3; ++k)
			if (!plait_read_vec3_value(r, json_array_get(axes, k), place, &shape->axes[k]))
				return false;
		return true;
	}
	case PLAIT_SHAPE_MESH:
		return true;
	}
	return false;
}

static bool plait_read_object(plait_manifest_reader *r, const json_t *json, int index,
                              const plait_manifest *m, plait_manifest_object *object)
{
	char where[64];
	snprintf(where, sizeof where, "objects[%d].", index);
	if (!json_is_object(json))
		return plait_manifest_fail(r, where, "expected an object");
	const char *name = json_string_value(json_object_get(json, "name"));
	if (name == NULL || name[0] == '\0' || strlen(name) >= sizeof object->name)
		return plait_manifest_fail(r, where, "name: expected a name of 1 to 63 characters");
	snprintf(object->name, sizeof object->name, "%s", name);
	int type = 0;
	if (!plait_read_choice(r, json, "type", where, plait_type_words, 4, &type) ||
	    !plait_read_int(r, json, "vertices", where, 0, PLAIT_MANIFEST_MAX_VERTICES, &object->vertex_count))
		return false;
	object->type = (plait_object_type)type;
	const json_t *collide = json_object_get(json, "collide");
	if (collide != NULL && !json_is_boolean(collide))
		return plait_manifest_fail(r, where, "collide: expected true or false");
	object->collide = collide == NULL || json_is_true(collide);
	bool pc2 = strcmp(m->format, "pc2") == 0;
	if (!plait_read_file_name(r, json, "file", where, !pc2, object->file, sizeof object->file))
		return false;
	if (pc2 && !plait_read_file_name(r, json, "mesh", where, false, object->mesh, sizeof object->mesh))
		return false;
	if (object->type != PLAIT_OBJECT_COLLIDER)
		return true;
	int shape = 0;
	if (!plait_read_choice(r, json, "shape", where, plait_shape_words, 5, &shape))
		return false;
	object->shape = (plait_shape_type)shape;
	const json_t *closed = json_object_get(json, "closed");
	if (!json_is_boolean(closed))
		return plait_manifest_fail(r, where, "closed: expected true or false");
	object->closed = json_is_true(closed);
	if (object->shape == PLAIT_SHAPE_MESH)
		return true;
	const json_t *shapes = json_object_get(json, "shapes");
	size_t frames = (size_t)(m->last_frame - m->first_frame + 1);
	if (!json_is_array(shapes) || json_array_size(shapes) != frames) {
		char what[96];
		snprintf(what, sizeof what, "shapes: expected a list of %zu shapes, one per frame", frames);
		return plait_manifest_fail(r, where, what);
	}
	object->shapes = malloc(sizeof *object->shapes * (frames > 0 ? frames : 1));
	if (object->shapes == NULL)
		return plait_tool_error_set(r->error, "out of memory");
	object->shape_capacity = (int)frames;
	for (size_t k = 0; k < frames; ++k) {
		char place[96];
		snprintf(place, sizeof place, "%sshapes[%zu]", where, k);
		if (!plait_read_shape(r, json_array_get(shapes, k), place, object->shape, &object->shapes[k]))
			return false;
	}
	return true;
}

static bool plait_manifest_parse(plait_manifest_reader *r, const json_t *json, plait_manifest *m)
{
	if (!json_is_object(json))
		return plait_manifest_fail(r, "top level", "expected a JSON object");
	int version;
	if (!plait_read_int(r, json, "manifest", "", 1, PLAIT_MANIFEST_VERSION, &version))
		return false;
	const char *format = json_string_value(json_object_get(json, "format"));
	if (format == NULL || (strcmp(format, "obj") != 0 && strcmp(format, "pc2") != 0))
		return plait_manifest_fail(r, "format", "expected \"obj\" or \"pc2\"");
	snprintf(m->format, sizeof m->format, "%s", format);
	if (!plait_read_int(r, json, "first_frame", "", 0, PLAIT_MANIFEST_MAX_FRAMES, &m->first_frame) ||
	    !plait_read_int(r, json, "last_frame", "", m->first_frame - 1, PLAIT_MANIFEST_MAX_FRAMES,
	                    &m->last_frame))
		return false;
	m->fps = 24.0f;
	m->space_scale = 1.0f;
	const json_t *fps = json_object_get(json, "fps"), *scale = json_object_get(json, "space_scale");
	if ((fps != NULL && !plait_read_number(r, fps, "fps", &m->fps)) ||
	    (scale != NULL && !plait_read_number(r, scale, "space_scale", &m->space_scale)))
		return false;
	if (!(m->space_scale > 0.0f))
		return plait_manifest_fail(r, "space_scale", "expected a number > 0");
	const json_t *objects = json_object_get(json, "objects");
	if (!json_is_array(objects))
		return plait_manifest_fail(r, "objects", "expected a list of objects");
	size_t count = json_array_size(objects);
	m->objects = calloc(count > 0 ? count : 1, sizeof *m->objects);
	if (m->objects == NULL)
		return plait_tool_error_set(r->error, "out of memory");
	m->object_count = (int)count;
	for (size_t i = 0; i < count; ++i) {
		if (!plait_read_object(r, json_array_get(objects, i), (int)i, m, &m->objects[i]))
			return false;
		for (size_t j = 0; j < i; ++j) {
			if (strcmp(m->objects[j].name, m->objects[i].name) == 0) {
				char where[64];
				snprintf(where, sizeof where, "objects[%zu].name", i);
				return plait_manifest_fail(r, where, "already the name of another object");
			}
		}
	}
	return true;
}

bool plait_manifest_load(const char *dir, plait_manifest *manifest, plait_tool_error *error)
{
	*manifest = (plait_manifest){0};
	size_t size = strlen(dir) + sizeof PLAIT_MANIFEST_NAME + 1;
	char *path = malloc(size);
	if (path == NULL)
		return plait_tool_error_set(error, "out of memory");
	snprintf(path, size, "%s/%s", dir, PLAIT_MANIFEST_NAME);
	FILE *probe = fopen(path, "rb");
	if (probe == NULL) {
		int code = errno;
		if (code == ENOENT)
			plait_tool_error_set(error,
			                     "%s: no manifest: not the output of `plait run --out DIR`, or a run that "
			                     "did not finish",
			                     path);
		else
			plait_tool_error_set(error, "%s: cannot read: %s", path, strerror(code));
		free(path);
		return false;
	}
	json_error_t json_error;
	json_t *json = json_loadf(probe, JSON_REJECT_DUPLICATES, &json_error);
	fclose(probe);
	if (json == NULL) {
		plait_tool_error_set(error, "%s:%d:%d: JSON syntax error: %s", path, json_error.line,
		                     json_error.column, json_error.text);
		free(path);
		return false;
	}
	plait_manifest_reader reader = {path, error};
	bool ok = plait_manifest_parse(&reader, json, manifest);
	json_decref(json);
	free(path);
	if (!ok)
		plait_manifest_free(manifest);
	return ok;
}

bool plait_manifest_frame_file(const plait_manifest_object *object, int frame, char *out, size_t size)
{
	const char *percent = strstr(object->file, "%04d");
	if (percent == NULL) {
		int n = snprintf(out, size, "%s", object->file);
		return n >= 0 && (size_t)n < size;
	}
	// Filled by hand: the pattern comes from a file and is never a printf format.
	int n =
	    snprintf(out, size, "%.*s%04d%s", (int)(percent - object->file), object->file, frame, percent + 4);
	return n >= 0 && (size_t)n < size;
}
