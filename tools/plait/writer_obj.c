/* Wavefront OBJ, one file per object per frame: DIR/NAME.FRAME.obj (frame zero-padded to 4
 * digits). Cloth faces are written as given (quads stay quads), collider surfaces as triangles,
 * curves as one polyline, particles as bare vertices. Indices are 1-based. */
#include "files.h"
#include "writers.h"

#include <stdio.h>

static bool plait_obj_open(plait_writer *writer, plait_tool_error *error)
{
	return true;
}

bool plait_writer_write_obj(plait_writer *writer, const plait_output_object *object, const char *file_name,
                            int frame, plait_tool_error *error)
{
	if (!plait_writer_read_positions(writer, object, error))
		return false;
	plait_atomic_file out;
	if (!plait_atomic_open(&out, writer->dir, file_name, error))
		return false;
	FILE *f = out.file;
	fprintf(f, "# plait %d.%d.%d: object %s, frame %d\n", PLAIT_VERSION_MAJOR, PLAIT_VERSION_MINOR,
	        PLAIT_VERSION_PATCH, object->name, frame);
	fprintf(f, "o %s\n", object->name);
	// %.9g round-trips every float exactly.
	for (int i = 0; i < object->vertex_count; ++i) {
		plait_vec3 p = writer->positions[i];
		fprintf(f, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
	}
	if (object->type == PLAIT_OBJECT_CURVE && object->vertex_count > 1) {
		fputc('l', f);
		for (int i = 0; i < object->vertex_count; ++i)
			fprintf(f, " %d", i + 1);
		fputc('\n', f);
	}
	int read = 0;
	for (int i = 0; i < object->face_count; ++i) {
		fputc('f', f);
		for (int k = 0; k < object->face_sizes[i]; ++k)
			fprintf(f, " %d", object->face_indices[read + k] + 1);
		fputc('\n', f);
		read += object->face_sizes[i];
	}
	return plait_atomic_commit(&out, error);
}

static bool plait_obj_write_frame(plait_writer *writer, int frame, plait_tool_error *error)
{
	for (int i = 0; i < writer->object_count; ++i) {
		char name[96];
		snprintf(name, sizeof name, "%s.%04d.obj", writer->objects[i].name, frame);
		if (!plait_writer_write_obj(writer, &writer->objects[i], name, frame, error))
			return false;
	}
	return true;
}

static bool plait_obj_close(plait_writer *writer, plait_tool_error *error)
{
	return true;
}

const plait_writer_format plait_writer_obj = {"obj", "Wavefront OBJ, DIR/NAME.FRAME.obj per object and frame",
                                              plait_obj_open, plait_obj_write_frame, plait_obj_close};
