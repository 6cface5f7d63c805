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

// Lists the objects that have vertices, with cloth faces read once.
static bool plait_writer_collect(plait_writer *writer, plait_tool_error *error)
{
	int count = plait_world_get_object_count(writer->world);
	writer->objects = calloc(count > 0 ? (size_t)count : 1, sizeof *writer->objects);
	if (writer->objects == NULL)
		return plait_tool_error_set(error, "out of memory");
	int most_vertices = 1;
	for (int i = 0; i < count; ++i) {
		plait_object_id id = plait_world_get_object(writer->world, i);
		int vertex_count = plait_object_get_vertex_count(id);
		if (plait_object_get_type(id) == PLAIT_OBJECT_COLLIDER || vertex_count <= 0)
			continue;
		plait_output_object *object = &writer->objects[writer->object_count++];
		object->id = id;
		object->type = plait_object_get_type(id);
		object->vertex_count = vertex_count;
		const char *name = plait_object_get_name(id);
		if (name != NULL && name[0] != '\0')
			snprintf(object->name, sizeof object->name, "%s", name);
		else
			snprintf(object->name, sizeof object->name, "object%d", i);
		most_vertices = vertex_count > most_vertices ? vertex_count : most_vertices;
		if (object->type == PLAIT_OBJECT_CLOTH) {
			int index_count = 0;
			int face_count = plait_object_get_faces(id, NULL, NULL, &index_count);
			object->face_sizes = malloc(sizeof(int) * (size_t)(face_count > 0 ? face_count : 1));
			object->face_indices = malloc(sizeof(int) * (size_t)(index_count > 0 ? index_count : 1));
			if (object->face_sizes == NULL || object->face_indices == NULL)
				return plait_tool_error_set(error, "out of memory");
			object->face_count =
			    plait_object_get_faces(id, object->face_sizes, object->face_indices, &index_count);
		}
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
	if (plait_object_get_positions(object->id, 0, object->vertex_count, writer->positions, &core_error) !=
	    PLAIT_OK)
		return plait_tool_error_set(error, "cannot read positions of \"%s\": %s", object->name,
		                            core_error.message);
	return true;
}
