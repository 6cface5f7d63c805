/* The type-specific keys of scene objects: geometry, velocities, pins, shapes and keyframes. */
#include "grid.h"
#include "mesh_io.h"
#include "scene_keys.h"
#include "scene_parse.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

// [a, b] with both numbers (or integers) in range, e.g. a grid's size or resolution.
static bool plait_parse_pair(plait_scene_reader *r, const json_t *value, const char *what, bool integer,
                             double min, double max, bool min_excluded, double out[2])
{
	if (!json_is_array(value) || json_array_size(value) != 2) {
		char got[64];
		plait_json_describe(value, got, sizeof got);
		return plait_reader_fail(r, "expected %s (an array of 2 %s), got %s", what,
		                         integer ? "integers" : "numbers", got);
	}
	for (size_t i = 0; i < 2; ++i) {
		size_t old = plait_reader_push_index(r, i);
		bool ok;
		if (integer) {
			int v = 0;
			ok = plait_reader_int(r, json_array_get(value, i), min, max, &v);
			out[i] = v;
		} else {
			float v = 0.0f;
			ok = plait_reader_float(r, json_array_get(value, i), min, max, min_excluded, &v);
			out[i] = v;
		}
		plait_reader_pop(r, old);
		if (!ok)
			return false;
	}
	return true;
}

static bool plait_is_zero(plait_vec3 v)
{
	return v.x == 0.0f && v.y == 0.0f && v.z == 0.0f;
}

static void plait_take_soup(plait_scene_object *object, plait_soup *soup)
{
	object->positions = soup->positions;
	object->vertex_count = soup->vertex_count;
	object->face_sizes = soup->face_sizes;
	object->face_count = soup->face_count;
	object->face_indices = soup->face_indices;
	object->index_count = soup->index_count;
	*soup = (plait_soup){0};
}

static bool plait_parse_grid(plait_scene_loader *loader, const json_t *json, plait_scene_object *object)
{
	plait_scene_reader *r = &loader->reader;
	int count;
	const plait_scene_key *keys = plait_scene_keys(PLAIT_CONTEXT_GRID, &count);
	plait_grid_def grid = plait_default_grid_def();
	if (!plait_reader_expect_object(r, json) || !plait_reader_check_keys(r, json, keys, count) ||
	    !plait_reader_read_keys(r, json, keys, count, &grid))
		return false;
	double size[2], resolution[2];
	size_t old = plait_reader_push_key(r, "size");
	if (!plait_parse_pair(r, json_object_get(json, "size"), "[width, height] in metres", false, 0.0, INFINITY,
	                      true, size))
		return false;
	plait_reader_pop(r, old);
	old = plait_reader_push_key(r, "resolution");
	if (!plait_parse_pair(r, json_object_get(json, "resolution"), "[nx, ny] quads", true, 1.0, 2000.0, false,
	                      resolution))
		return false;
	plait_reader_pop(r, old);
	if (plait_is_zero(grid.normal)) {
		old = plait_reader_push_key(r, "normal");
		return plait_reader_fail(r, "expected a non-zero direction, got [0, 0, 0]");
	}
	grid.width = (float)size[0];
	grid.height = (float)size[1];
	grid.nx = (int)resolution[0];
	grid.ny = (int)resolution[1];
	plait_soup soup;
	if (!plait_grid_build(&grid, &soup))
		return plait_reader_fail(r, "out of memory building a %dx%d grid", grid.nx, grid.ny);
	plait_take_soup(object, &soup);
	return true;
}

// layout (NULL unless a sequence follows) receives how the file's vertices became the mesh's.
static bool plait_parse_mesh(plait_scene_loader *loader, const json_t *json, plait_scene_object *object,
                             plait_mesh_layout *layout)
{
	plait_scene_reader *r = &loader->reader;
	if (!json_is_string(json) || json_string_length(json) == 0) {
		char got[64];
		plait_json_describe(json, got, sizeof got);
		return plait_reader_fail(r, "expected a mesh file path (relative to the scene file's folder), got %s",
		                         got);
	}
	const char *name = json_string_value(json);
	size_t size = strlen(loader->base_dir) + strlen(name) + 2;
	object->mesh_path = malloc(size);
	if (object->mesh_path == NULL)
		return plait_reader_fail(r, "out of memory");
	if (name[0] == '/')
		snprintf(object->mesh_path, size, "%s", name);
	else
		snprintf(object->mesh_path, size, "%s/%s", loader->base_dir, name);
	plait_soup soup;
	plait_mesh_report report;
	plait_tool_error mesh_error;
	if (!plait_mesh_load_layout(object->mesh_path, &soup, &report, layout, &mesh_error))
		return plait_reader_fail(r, "%s", mesh_error.message);
	plait_take_soup(object, &soup);
	if (report.degenerate_faces > 0)
		plait_scene_warn(loader, "dropped %d degenerate face%s (repeated vertex or zero area) of %s",
		                 report.degenerate_faces, report.degenerate_faces == 1 ? "" : "s", object->mesh_path);
	if (report.point_line_faces > 0)
		plait_scene_warn(loader, "ignored %d point or line primitive%s of %s", report.point_line_faces,
		                 report.point_line_faces == 1 ? "" : "s", object->mesh_path);
	if (report.unused_vertices > 0)
		plait_scene_warn(loader, "removed %d vertex%s no face uses from %s", report.unused_vertices,
		                 report.unused_vertices == 1 ? "" : "es", object->mesh_path);
	return true;
}

// One [x,y,z] for every vertex, or a list with one per vertex.
static bool plait_parse_velocities(plait_scene_reader *r, const json_t *json, plait_scene_object *object)
{
	size_t old = plait_reader_push_key(r, "velocities");
	int n = object->vertex_count;
	if (json_is_array(json) && json_array_size(json) == 3 && json_is_number(json_array_get(json, 0))) {
		plait_vec3 v;
		if (!plait_reader_vec3(r, json, &v))
			return false;
		object->velocities = malloc(sizeof(plait_vec3) * (size_t)n);
		if (object->velocities == NULL)
			return plait_reader_fail(r, "out of memory");
		for (int i = 0; i < n; ++i)
			object->velocities[i] = v;
	} else {
		if (!json_is_array(json) || json_array_size(json) != (size_t)n) {
			char got[64];
			plait_json_describe(json, got, sizeof got);
			return plait_reader_fail(
			    r, "expected one [x, y, z] for all vertices or %d of them (one per vertex), got %s", n, got);
		}
		int count;
		if (!plait_reader_vec3_array(r, json, &object->velocities, &count))
			return false;
	}
	plait_reader_pop(r, old);
	return true;
}

static int plait_compare_int(const void *a, const void *b)
{
	int x = *(const int *)a, y = *(const int *)b;
	return (x > y) - (x < y);
}

static bool plait_parse_pins(plait_scene_reader *r, const json_t *json, plait_scene_object *object)
{
	size_t old = plait_reader_push_key(r, "pins");
	if (!json_is_array(json)) {
		char got[64];
		plait_json_describe(json, got, sizeof got);
		return plait_reader_fail(r, "expected an array of vertex indices, got %s", got);
	}
	size_t n = json_array_size(json);
	object->pins = malloc(sizeof(int) * (n > 0 ? n : 1));
	if (object->pins == NULL)
		return plait_reader_fail(r, "out of memory");
	for (size_t i = 0; i < n; ++i) {
		size_t at = plait_reader_push_index(r, i);
		if (!plait_reader_int(r, json_array_get(json, i), 0, object->vertex_count - 1, &object->pins[i]))
			return false;
		plait_reader_pop(r, at);
	}
	// A vertex listed twice is pinned once.
	qsort(object->pins, n, sizeof(int), plait_compare_int);
	int unique = 0;
	for (size_t i = 0; i < n; ++i)
		if (unique == 0 || object->pins[unique - 1] != object->pins[i])
			object->pins[unique++] = object->pins[i];
	object->pin_count = unique;
	plait_reader_pop(r, old);
	return true;
}

// velocities and pins, read once the vertex count is known.
static bool plait_parse_vertex_extras(plait_scene_reader *r, const json_t *json, plait_scene_object *object)
{
	const json_t *velocities = json_object_get(json, "velocities");
	if (velocities != NULL && !plait_parse_velocities(r, velocities, object))
		return false;
	const json_t *pins = json_object_get(json, "pins");
	if (pins != NULL && !plait_parse_pins(r, pins, object))
		return false;
	return true;
}

bool plait_scene_parse_cloth(plait_scene_loader *loader, const json_t *json, plait_scene_object *object)
{
	plait_scene_reader *r = &loader->reader;
	const json_t *mesh = json_object_get(json, "mesh");
	const json_t *grid = json_object_get(json, "grid");
	if (mesh != NULL && grid != NULL)
		return plait_reader_fail(r, "a cloth takes either \"mesh\" or \"grid\", not both");
	if (mesh == NULL && grid == NULL)
		return plait_reader_fail(r, "a cloth needs either \"mesh\" (a file) or \"grid\" {size, resolution}");
	size_t old = plait_reader_push_key(r, mesh != NULL ? "mesh" : "grid");
	bool ok =
	    mesh != NULL ? plait_parse_mesh(loader, mesh, object, NULL) : plait_parse_grid(loader, grid, object);
	if (!ok)
		return false;
	plait_reader_pop(r, old);
	return plait_parse_vertex_extras(r, json, object);
}

static bool plait_parse_positions(plait_scene_reader *r, const json_t *json, plait_scene_object *object,
                                  int min_count)
{
	size_t old = plait_reader_push_key(r, "positions");
	if (!plait_reader_vec3_array(r, json_object_get(json, "positions"), &object->positions,
	                             &object->vertex_count))
		return false;
	if (object->vertex_count < min_count)
		return plait_reader_fail(r, "expected at least %d points, got %d", min_count, object->vertex_count);
	plait_reader_pop(r, old);
	return true;
}

bool plait_scene_parse_curve(plait_scene_loader *loader, const json_t *json, plait_scene_object *object)
{
	plait_scene_reader *r = &loader->reader;
	return plait_parse_positions(r, json, object, 2) && plait_parse_vertex_extras(r, json, object);
}

bool plait_scene_parse_particles(plait_scene_loader *loader, const json_t *json, plait_scene_object *object)
{
	plait_scene_reader *r = &loader->reader;
	return plait_parse_positions(r, json, object, 1) && plait_parse_vertex_extras(r, json, object);
}

static bool plait_parse_keyframes(plait_scene_reader *r, const json_t *json, plait_scene_object *object)
{
	size_t old = plait_reader_push_key(r, "keyframes");
	if (!json_is_array(json)) {
		char got[64];
		plait_json_describe(json, got, sizeof got);
		return plait_reader_fail(r, "expected an array of {frame, translate, rotate, scale}, got %s", got);
	}
	size_t n = json_array_size(json);
	object->keyframes = calloc(n > 0 ? n : 1, sizeof *object->keyframes);
	if (object->keyframes == NULL)
		return plait_reader_fail(r, "out of memory");
	int count;
	const plait_scene_key *keys = plait_scene_keys(PLAIT_CONTEXT_KEYFRAME, &count);
	for (size_t i = 0; i < n; ++i) {
		const json_t *item = json_array_get(json, i);
		plait_scene_keyframe *key = &object->keyframes[i];
		key->transform = plait_identity_transform();
		size_t at = plait_reader_push_index(r, i);
		if (!plait_reader_expect_object(r, item) || !plait_reader_check_keys(r, item, keys, count) ||
		    !plait_reader_read_keys(r, item, keys, count, key))
			return false;
		if (i > 0 && key->frame <= object->keyframes[i - 1].frame) {
			plait_reader_push_key(r, "frame");
			return plait_reader_fail(
			    r, "expected a frame after %d (keyframes go in increasing frame order), got %d",
			    object->keyframes[i - 1].frame, key->frame);
		}
		plait_reader_pop(r, at);
	}
	object->keyframe_count = (int)n;
	plait_reader_pop(r, old);
	return true;
}

// A deforming mesh collider's shape frame by frame, every file read and checked now.
static bool plait_parse_sequence(plait_scene_loader *loader, const json_t *json, plait_scene_object *object,
                                 const plait_mesh_layout *layout)
{
	plait_scene_reader *r = &loader->reader;
	size_t old = plait_reader_push_key(r, "sequence");
	char got[64];
	plait_json_describe(json, got, sizeof got);
	if (!json_is_string(json) || json_string_length(json) == 0)
		return plait_reader_fail(
		    r,
		    "expected a file path pattern with one frame number, as in \"arm.%%04d.obj\" "
		    "(relative to the scene file's folder), got %s",
		    got);
	plait_frame_pattern pattern;
	char why[128];
	if (!plait_frame_pattern_parse(loader->base_dir, json_string_value(json), &pattern, why, sizeof why))
		return plait_reader_fail(r,
		                         "expected a file path pattern with one frame number, %%d or %%0Nd as in "
		                         "\"arm.%%04d.obj\", got %s (%s)",
		                         got, why);
	plait_tool_error sequence_error;
	bool ok = plait_mesh_sequence_load(&pattern, layout, &object->sequence, &sequence_error);
	plait_frame_pattern_free(&pattern);
	if (!ok)
		return plait_reader_fail(r, "%s", sequence_error.message);
	plait_reader_pop(r, old);
	return true;
}

bool plait_scene_parse_collider(plait_scene_loader *loader, const json_t *json, plait_scene_object *object)
{
	plait_scene_reader *r = &loader->reader;
	static const char *const shapes[] = {"plane", "sphere", "capsule", "box", "mesh"};
	// The geometry keys each shape takes; the others are mistakes worth reporting.
	static const char *const shape_keys[5][3] = {{"point", "normal", NULL},
	                                             {"center", "radius", NULL},
	                                             {"a", "b", "radius"},
	                                             {"center", "size", "rotation"},
	                                             {"mesh", "sequence", NULL}};
	static const char *const all_geometry[] = {"point", "normal", "center",   "radius", "a",
	                                           "b",     "size",   "rotation", "mesh",   "sequence"};
	size_t old = plait_reader_push_key(r, "shape");
	int shape;
	if (!plait_reader_choice(r, json_object_get(json, "shape"), shapes, 5, &shape))
		return false;
	plait_reader_pop(r, old);
	object->collider.shape = (plait_shape_type)shape;
	if (shape == PLAIT_SHAPE_MESH) {
		const json_t *mesh = json_object_get(json, "mesh");
		if (mesh == NULL)
			return plait_reader_fail(r, "a mesh collider needs \"mesh\": the path of a mesh file");
		const json_t *sequence = json_object_get(json, "sequence");
		plait_mesh_layout layout;
		size_t at = plait_reader_push_key(r, "mesh");
		if (!plait_parse_mesh(loader, mesh, object, sequence != NULL ? &layout : NULL))
			return false;
		plait_reader_pop(r, at);
		if (sequence != NULL) {
			bool ok = plait_parse_sequence(loader, sequence, object, &layout);
			plait_mesh_layout_free(&layout);
			if (!ok)
				return false;
		}
	}
	for (int i = 0; i < 10; ++i) {
		if (json_object_get(json, all_geometry[i]) == NULL)
			continue;
		bool used = false;
		for (int k = 0; k < 3; ++k)
			used =
			    used || (shape_keys[shape][k] != NULL && strcmp(shape_keys[shape][k], all_geometry[i]) == 0);
		if (!used) {
			plait_reader_push_key(r, all_geometry[i]);
			return plait_reader_fail(r, "not used by a %s collider (a %s takes %s, %s%s%s)", shapes[shape],
			                         shapes[shape], shape_keys[shape][0], shape_keys[shape][1],
			                         shape_keys[shape][2] != NULL ? ", " : "",
			                         shape_keys[shape][2] != NULL ? shape_keys[shape][2] : "");
		}
	}
	plait_collider_def *def = &object->collider;
	if (shape == PLAIT_SHAPE_PLANE && plait_is_zero(def->normal)) {
		plait_reader_push_key(r, "normal");
		return plait_reader_fail(r, "expected a non-zero direction, got [0, 0, 0]");
	}
	if (shape == PLAIT_SHAPE_BOX && !(def->size.x > 0.0f && def->size.y > 0.0f && def->size.z > 0.0f)) {
		plait_reader_push_key(r, "size");
		return plait_reader_fail(r, "expected full extents [x, y, z] all > 0, got [%g, %g, %g]", def->size.x,
		                         def->size.y, def->size.z);
	}
	const json_t *keyframes = json_object_get(json, "keyframes");
	if (keyframes != NULL && !plait_parse_keyframes(r, keyframes, object))
		return false;
	def->transform = plait_scene_collider_transform(object, 0);
	return true;
}
