#include "scene_reader.h"

#include "edit_distance.h"

#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

size_t plait_reader_push_key(plait_scene_reader *reader, const char *key)
{
	size_t old = reader->path_length;
	int written = snprintf(reader->path + old, sizeof reader->path - old, "%s%s", old > 0 ? "." : "", key);
	reader->path_length = strnlen(reader->path, sizeof reader->path - 1);
	(void)written;
	return old;
}

size_t plait_reader_push_index(plait_scene_reader *reader, size_t index)
{
	size_t old = reader->path_length;
	snprintf(reader->path + old, sizeof reader->path - old, "[%zu]", index);
	reader->path_length = strnlen(reader->path, sizeof reader->path - 1);
	return old;
}

void plait_reader_pop(plait_scene_reader *reader, size_t length)
{
	reader->path_length = length;
	reader->path[length] = '\0';
}

bool plait_reader_fail(plait_scene_reader *reader, const char *format, ...)
{
	char detail[PLAIT_TOOL_ERROR_SIZE];
	va_list args;
	va_start(args, format);
	vsnprintf(detail, sizeof detail, format, args);
	va_end(args);
	if (reader->path_length > 0)
		return plait_tool_error_set(reader->error, "%s: %s: %s", reader->file, reader->path, detail);
	return plait_tool_error_set(reader->error, "%s: %s", reader->file, detail);
}

void plait_json_describe(const json_t *value, char *buffer, size_t size)
{
	switch (json_typeof(value)) {
	case JSON_INTEGER:
		snprintf(buffer, size, "%" JSON_INTEGER_FORMAT, json_integer_value(value));
		break;
	case JSON_REAL:
		snprintf(buffer, size, "%.10g", json_real_value(value));
		break;
	case JSON_STRING: {
		const char *text = json_string_value(value);
		if (strlen(text) > 40)
			snprintf(buffer, size, "\"%.40s...\"", text);
		else
			snprintf(buffer, size, "\"%s\"", text);
		break;
	}
	case JSON_ARRAY: {
		size_t n = json_array_size(value);
		if (n == 0)
			snprintf(buffer, size, "an empty array");
		else
			snprintf(buffer, size, "an array of %zu item%s", n, n == 1 ? "" : "s");
		break;
	}
	case JSON_OBJECT:
		snprintf(buffer, size, "an object");
		break;
	case JSON_TRUE:
		snprintf(buffer, size, "true");
		break;
	case JSON_FALSE:
		snprintf(buffer, size, "false");
		break;
	default:
		snprintf(buffer, size, "null");
		break;
	}
}

// "> 0", ">= 0", "from 0 to 1" or "" (any value), for "expected a number > 0".
static void plait_describe_range(double min, double max, bool min_excluded, char *buffer, size_t size)
{
	if (isinf(min) && isinf(max))
		buffer[0] = '\0';
	else if (isinf(max))
		snprintf(buffer, size, " %s %.10g", min_excluded ? ">" : ">=", min);
	else if (min_excluded)
		snprintf(buffer, size, " > %.10g and <= %.10g", min, max);
	else
		snprintf(buffer, size, " from %.10g to %.10g", min, max);
}

static bool plait_has_key(const plait_scene_key *keys, int key_count, const char *name)
{
	for (int i = 0; i < key_count; ++i) {
		if (strcmp(keys[i].name, name) == 0)
			return true;
	}
	return false;
}

bool plait_reader_check_keys(plait_scene_reader *reader, const json_t *object, const plait_scene_key *keys,
                             int key_count)
{
	const char *key;
	json_t *value;
	// Cast: jansson's iteration macro takes a non-const object but does not modify it.
	json_object_foreach((json_t *)object, key, value)
	{
		if (plait_has_key(keys, key_count, key))
			continue;
		const char *names[64];
		int name_count = key_count < 64 ? key_count : 64;
		for (int i = 0; i < name_count; ++i)
			names[i] = keys[i].name;
		const char *suggestion = plait_closest_name(key, names, name_count);
		size_t old = plait_reader_push_key(reader, key);
		bool result;
		if (suggestion != NULL) {
			result = plait_reader_fail(reader, "unknown key (did you mean \"%s\"?)", suggestion);
		} else {
			char list[300] = "";
			size_t used = 0;
			for (int i = 0; i < name_count && used + 8 < sizeof list; ++i) {
				int n = snprintf(list + used, sizeof list - used, "%s%s", i > 0 ? ", " : "", names[i]);
				if (n < 0 || used + (size_t)n >= sizeof list - 5) {
					snprintf(list + used, sizeof list - used, ", ...");
					break;
				}
				used += (size_t)n;
			}
			result = plait_reader_fail(reader, "unknown key (valid keys here: %s)", list);
		}
		plait_reader_pop(reader, old);
		return result;
	}
	for (int i = 0; i < key_count; ++i) {
		if (keys[i].required && json_object_get(object, keys[i].name) == NULL) {
			size_t old = plait_reader_push_key(reader, keys[i].name);
			plait_reader_fail(reader, "required key is missing");
			plait_reader_pop(reader, old);
			return false;
		}
	}
	return true;
}

bool plait_reader_read_keys(plait_scene_reader *reader, const json_t *object, const plait_scene_key *keys,
                            int key_count, void *destination)
{
	char *base = destination;
	for (int i = 0; i < key_count; ++i) {
		const plait_scene_key *k = &keys[i];
		const json_t *value = json_object_get(object, k->name);
		if (value == NULL || k->kind == PLAIT_KEY_SPECIAL)
			continue;
		// Ignored keys are still validated, into a scratch slot.
		union {
			float f;
			int i;
			uint32_t u;
			bool b;
			plait_vec3 v;
		} scratch;
		void *slot = k->offset == PLAIT_KEY_IGNORED ? (void *)&scratch : (void *)(base + k->offset);
		size_t old = plait_reader_push_key(reader, k->name);
		bool ok = true;
		switch (k->kind) {
		case PLAIT_KEY_FLOAT:
			ok = plait_reader_float(reader, value, k->min, k->max, k->min_excluded, slot);
			break;
		case PLAIT_KEY_INT:
			ok = plait_reader_int(reader, value, k->min, k->max, slot);
			break;
		case PLAIT_KEY_UINT32: {
			double v = json_is_number(value) ? json_number_value(value) : -1.0;
			if (!json_is_integer(value) || v < 0.0 || v > 4294967295.0) {
				char got[64];
				plait_json_describe(value, got, sizeof got);
				ok = plait_reader_fail(reader, "expected an integer from 0 to 4294967295, got %s", got);
			} else {
				uint32_t u = (uint32_t)json_integer_value(value);
				memcpy(slot, &u, sizeof u);
			}
			break;
		}
		case PLAIT_KEY_BOOL:
			ok = plait_reader_bool(reader, value, slot);
			break;
		case PLAIT_KEY_VEC3:
			ok = plait_reader_vec3(reader, value, slot);
			break;
		case PLAIT_KEY_CHOICE: {
			// The destination is a C enum, which scene_keys.c checks is the size of an int.
			int choice = 0;
			ok = plait_reader_choice(reader, value, k->choices, k->choice_count, &choice);
			if (ok)
				memcpy(slot, &choice, sizeof choice);
			break;
		}
		case PLAIT_KEY_SPECIAL:
			break;
		}
		plait_reader_pop(reader, old);
		if (!ok)
			return false;
	}
	return true;
}

bool plait_reader_expect_object(plait_scene_reader *reader, const json_t *value)
{
	if (json_is_object(value))
		return true;
	char got[64];
	plait_json_describe(value, got, sizeof got);
	return plait_reader_fail(reader, "expected an object {...}, got %s", got);
}

bool plait_reader_float(plait_scene_reader *reader, const json_t *value, double min, double max,
                        bool min_excluded, float *out)
{
	char range[96];
	plait_describe_range(min, max, min_excluded, range, sizeof range);
	char got[64];
	plait_json_describe(value, got, sizeof got);
	if (!json_is_number(value))
		return plait_reader_fail(reader, "expected a number%s, got %s", range, got);
	double v = json_number_value(value);
	bool in_range = (min_excluded ? v > min : v >= min) && v <= max;
	if (!in_range)
		return plait_reader_fail(reader, "expected a number%s, got %s", range, got);
	// Values are single precision in the solver: 1e39 is valid JSON but not a float.
	if (!isfinite((float)v))
		return plait_reader_fail(reader, "expected a number%s, got %s (too large for single precision)",
		                         range, got);
	*out = (float)v;
	return true;
}

bool plait_reader_int(plait_scene_reader *reader, const json_t *value, double min, double max, int *out)
{
	// An unbounded range (keys whose range the library checks) is described as none at all.
	char range[96];
	plait_describe_range(min, max, false, range, sizeof range);
	char got[64];
	plait_json_describe(value, got, sizeof got);
	// 3.0 is accepted as 3: some exporters write every number as a real.
	double v = json_is_number(value) ? json_number_value(value) : NAN;
	if (!json_is_number(value) || v != floor(v) || v < min || v > max)
		return plait_reader_fail(reader, "expected an integer%s, got %s", range, got);
	if (v < (double)INT_MIN || v > (double)INT_MAX)
		return plait_reader_fail(reader, "expected an integer%s, got %s (too large for a 32-bit integer)",
		                         range, got);
	*out = (int)v;
	return true;
}

bool plait_reader_bool(plait_scene_reader *reader, const json_t *value, bool *out)
{
	if (!json_is_boolean(value)) {
		char got[64];
		plait_json_describe(value, got, sizeof got);
		return plait_reader_fail(reader, "expected true or false, got %s", got);
	}
	*out = json_is_true(value);
	return true;
}

bool plait_reader_vec3(plait_scene_reader *reader, const json_t *value, plait_vec3 *out)
{
	if (!json_is_array(value) || json_array_size(value) != 3) {
		char got[64];
		plait_json_describe(value, got, sizeof got);
		return plait_reader_fail(reader, "expected [x, y, z] (an array of 3 numbers), got %s", got);
	}
	float v[3];
	for (size_t i = 0; i < 3; ++i) {
		size_t old = plait_reader_push_index(reader, i);
		bool ok = plait_reader_float(reader, json_array_get(value, i), -INFINITY, INFINITY, false, &v[i]);
		plait_reader_pop(reader, old);
		if (!ok)
			return false;
	}
	*out = (plait_vec3){v[0], v[1], v[2]};
	return true;
}

bool plait_reader_vec3_array(plait_scene_reader *reader, const json_t *value, plait_vec3 **out, int *count)
{
	*out = NULL;
	*count = 0;
	if (!json_is_array(value) || json_array_size(value) == 0 || json_array_size(value) > INT_MAX / 16) {
		char got[64];
		plait_json_describe(value, got, sizeof got);
		return plait_reader_fail(reader, "expected a non-empty array of [x, y, z] points, got %s", got);
	}
	size_t n = json_array_size(value);
	plait_vec3 *points = malloc(n * sizeof *points);
	if (points == NULL)
		return plait_reader_fail(reader, "out of memory reading %zu points", n);
	for (size_t i = 0; i < n; ++i) {
		size_t old = plait_reader_push_index(reader, i);
		bool ok = plait_reader_vec3(reader, json_array_get(value, i), &points[i]);
		plait_reader_pop(reader, old);
		if (!ok) {
			free(points);
			return false;
		}
	}
	*out = points;
	*count = (int)n;
	return true;
}

bool plait_reader_choice(plait_scene_reader *reader, const json_t *value, const char *const *choices,
                         int choice_count, int *out)
{
	if (json_is_string(value)) {
		for (int i = 0; i < choice_count; ++i) {
			if (strcmp(json_string_value(value), choices[i]) == 0) {
				*out = i;
				return true;
			}
		}
	}
	char list[200] = "";
	size_t used = 0;
	for (int i = 0; i < choice_count; ++i) {
		int n = snprintf(list + used, sizeof list - used, "%s%s", i > 0 ? ", " : "", choices[i]);
		if (n > 0)
			used += (size_t)n;
		if (used >= sizeof list)
			break;
	}
	char got[64];
	plait_json_describe(value, got, sizeof got);
	return plait_reader_fail(reader, "expected one of %s, got %s", list, got);
}
