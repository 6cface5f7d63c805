/* Reading JSON values with a key path, so every error says where it is and what was expected:
 * `scene.json: objects[2].grid.resolution[0]: expected an integer from 1 to 2000, got 0`. */
#ifndef PLAIT_SCENE_READER_H
#define PLAIT_SCENE_READER_H

#include "tool_error.h"

#include <jansson.h>
#include <plait/plait.h>
#include <stdbool.h>
#include <stddef.h>

#define PLAIT_KEY_PATH_SIZE 200

typedef struct plait_scene_reader {
	const char *file; /* as the user named it */
	char path[PLAIT_KEY_PATH_SIZE];
	size_t path_length;
	plait_tool_error *error;
} plait_scene_reader;

/* What a key holds. SPECIAL keys are read by hand; the table only knows they exist. */
typedef enum plait_key_kind {
	PLAIT_KEY_FLOAT = 0,
	PLAIT_KEY_INT,
	PLAIT_KEY_UINT32,
	PLAIT_KEY_BOOL,
	PLAIT_KEY_VEC3,
	PLAIT_KEY_CHOICE, /* a string naming a value of a C enum (an int), e.g. bend_model */
	PLAIT_KEY_SPECIAL,
} plait_key_kind;

/* Offset of a key that is validated but not stored (collider damp). */
#define PLAIT_KEY_IGNORED ((size_t)-1)

/* One valid key of a JSON object: its kind, valid range and where its value goes in a def. */
typedef struct plait_scene_key {
	const char *name;
	plait_key_kind kind;
	double min, max;   /* valid range of FLOAT and INT values */
	bool min_excluded; /* the range is (min, max] rather than [min, max] */
	size_t offset;     /* byte offset into the destination struct */
	bool required;
	const char *const *choices; /* CHOICE: the value names, choices[v] naming enum value v */
	int choice_count;
} plait_scene_key;

/* Key path editing: push returns the old length to give back to pop. */
size_t plait_reader_push_key(plait_scene_reader *reader, const char *key);
size_t plait_reader_push_index(plait_scene_reader *reader, size_t index);
void plait_reader_pop(plait_scene_reader *reader, size_t length);

/* Sets "FILE: PATH: message" and returns false. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
bool plait_reader_fail(plait_scene_reader *reader, const char *format, ...);

/* A short description of a JSON value for messages: -3, "clth", true, an array of 2, ... */
void plait_json_describe(const json_t *value, char *buffer, size_t size);

/* Rejects keys not in the table (suggesting the closest one) and missing required keys. */
bool plait_reader_check_keys(plait_scene_reader *reader, const json_t *object, const plait_scene_key *keys,
                             int key_count);
/* Reads every present non-SPECIAL key of the table into destination. */
bool plait_reader_read_keys(plait_scene_reader *reader, const json_t *object, const plait_scene_key *keys,
                            int key_count, void *destination);

/* Typed reads of the value at the current path. */
bool plait_reader_expect_object(plait_scene_reader *reader, const json_t *value);
bool plait_reader_float(plait_scene_reader *reader, const json_t *value, double min, double max,
                        bool min_excluded, float *out);
bool plait_reader_int(plait_scene_reader *reader, const json_t *value, double min, double max, int *out);
bool plait_reader_bool(plait_scene_reader *reader, const json_t *value, bool *out);
bool plait_reader_vec3(plait_scene_reader *reader, const json_t *value, plait_vec3 *out);
/* A non-empty array of [x,y,z]; *out is malloc'ed. */
bool plait_reader_vec3_array(plait_scene_reader *reader, const json_t *value, plait_vec3 **out, int *count);
/* One of choices (by index); the message lists them all. */
bool plait_reader_choice(plait_scene_reader *reader, const json_t *value, const char *const *choices,
                         int choice_count, int *out);

#endif
