#include "writers.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const plait_writer_format *const plait_formats[] = {&plait_writer_obj, &plait_writer_pc2};

const plait_writer_format *plait_writer_find_format(const char *name)
{
	for (int i = 0; i < plait_writer_format_count(); ++i)
		if (strcmp(plait_formats[i]->name, name) == 0)
			return plait_formats[i];
	return NULL;
}

int plait_writer_format_count(void)
{
	return (int)(sizeof plait_formats / sizeof plait_formats[0]);
}

const plait_writer_format *plait_writer_format_at(int index)
{
	return plait_formats[index];
}

static void plait_writer_free(plait_writer *writer)
{
	for (int i = 0; i < writer->object_count; ++i) {
		free(writer->objects[i].face_sizes);
		free(writer->objects[i].face_indices);
	}
	free(writer->objects);
	free(writer->positions);
	free(writer->dir);
	free(writer);
}

// Reads a cloth's faces, or a collider surface's triangles as faces of 3.
static bool plait_writer_read_faces(plait_output_object *object, plait_tool_error *error)
{
	int index_count = 0, face_count = 0;
	if (object->type == PLAIT_OBJECT_CLOTH) {
		face_count = plait_object_get_faces(object->id, NULL, NULL, &index_count);
	} else if (object->type == PLAIT_OBJECT_COLLIDER) {
		face_count = plait_collider_get_surface_triangles(object->id, NULL, 0);
		index_count = 3 * face_count;
	}
	if (face_count <= 0)
		return true;
	object->face_sizes = malloc(sizeof(int) * (size_t)face_count);
	object->face_indices = malloc(sizeof(int) * (size_t)index_count);
	if (object->face_sizes == NULL || object->face_indices == NULL)
		return plait_tool_error_set(error, "out of memory");
	if (object->type == PLAIT_OBJECT_CLOTH) {
		object->face_count =
		    plait_object_get_faces(object->id, object->face_sizes, object->face_indices, &index_count);
	} else {
		object->face_count =
		    plait_collider_get_surface_triangles(object->id, object->face_indices, face_count);
		for (int i = 0; i < object->face_count; ++i)
			object->face_sizes[i] = 3;
	}
	return true;
}

// Lists the objects that have vertices, with their faces read once.
static bool plait_writer_collect(plait_writer *writer, plait_tool_error *error)
{
	int count = plait_world_get_object_count(writer->world);
	writer->objects = calloc(count > 0 ? (size_t)count : 1, sizeof *writer->objects);
	if (writer->objects == NULL)
		return plait_tool_error_set(error, "out of memory");
	int most_vertices = 1;
	for (int i = 0; i < count; ++i) {
		plait_object_id id = plait_world_get_object(writer->world, i);
		plait_object_type type = plait_object_get_type(id);
		int vertex_count = type == PLAIT_OBJECT_COLLIDER ? plait_collider_get_surface_vertex_count(id)
		                                                 : plait_object_get_vertex_count(id);
		if (vertex_count <= 0)
			continue;
		plait_output_object *object = &writer->objects[writer->object_count++];
		object->id = id;
		object->world_index = i;
		object->type = type;
		object->vertex_count = vertex_count;
		const char *name = plait_object_get_name(id);
		if (name != NULL && name[0] != '\0')
			snprintf(object->name, sizeof object->name, "%s", name);
		else
			snprintf(object->name, sizeof object->name, "object%d", i);
		most_vertices = vertex_count > most_vertices ? vertex_count : most_vertices;
		if (!plait_writer_read_faces(object, error))
			return false;
	}
	writer->positions = malloc(sizeof(plait_vec3) * (size_t)most_vertices);
	if (writer->positions == NULL)
		return plait_tool_error_set(error, "out of memory");
	return true;
}

plait_writer *plait_writer_open(const plait_writer_format *format, const char *dir, plait_world_id world,
                                plait_tool_error *error)
{
	plait_writer *writer = calloc(1, sizeof *writer);
	if (writer == NULL) {
		plait_tool_error_set(error, "out of memory");
		return NULL;
	}
	writer->format = format;
	writer->world = world;
	writer->dir = strdup(dir);
	if (writer->dir == NULL || !plait_writer_collect(writer, error)) {
		if (writer->dir == NULL)
			plait_tool_error_set(error, "out of memory");
		plait_writer_free(writer);
		return NULL;
	}
	if (!format->open(writer, error)) {
		plait_writer_free(writer);
		return NULL;
	}
	return writer;
}

bool plait_writer_write_frame(plait_writer *writer, int frame, plait_tool_error *error)
{
	if (!writer->format->write_frame(writer, frame, error))
		return false;
	writer->frames_written++;
	return true;
}

bool plait_writer_close(plait_writer *writer, plait_tool_error *error)
{
	if (writer == NULL)
		return true;
	bool ok = writer->format->close(writer, error);
	plait_writer_free(writer);
	return ok;
}

bool plait_writer_read_positions(plait_writer *writer, const plait_output_object *object,
                                 plait_tool_error *error)
{
	plait_error core_error = {0};
	plait_result result =
	    object->type == PLAIT_OBJECT_COLLIDER
	        ? plait_collider_get_surface_positions(object->id, 0, object->vertex_count, writer->positions,
	                                               &core_error)
	        : plait_object_get_positions(object->id, 0, object->vertex_count, writer->positions, &core_error);
	if (result != PLAIT_OK)
		return plait_tool_error_set(error, "cannot read positions of \"%s\": %s", object->name,
		                            core_error.message);
	return true;
}
