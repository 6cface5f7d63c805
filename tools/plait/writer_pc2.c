/* PC2 point caches (Blender, 3ds Max), one DIR/NAME.pc2 per object, little endian:
 *   char[12] "POINTCACHE2\0", int32 version = 1, int32 numPoints, float32 startFrame,
 *   float32 sampleRate, int32 numSamples, then numSamples * numPoints float32 x, y, z.
 * numSamples is known only at the end: it is patched in before the file is renamed into place.
 * Beside each cache, DIR/NAME.obj holds the mesh it animates (faces, and the positions at open):
 * what Blender's Mesh Cache modifier is put on, and where `plait check` finds the topology. */
#include "files.h"
#include "writers.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PLAIT_PC2_SAMPLES_OFFSET 28

typedef struct plait_pc2_state {
	plait_atomic_file *files; /* one per output object */
	unsigned char *buffer;    /* one sample of the largest object */
} plait_pc2_state;

static void plait_put_u32(unsigned char *out, uint32_t v)
{
	out[0] = (unsigned char)(v & 0xffu);
	out[1] = (unsigned char)((v >> 8) & 0xffu);
	out[2] = (unsigned char)((v >> 16) & 0xffu);
	out[3] = (unsigned char)((v >> 24) & 0xffu);
}

static void plait_put_f32(unsigned char *out, float f)
{
	uint32_t bits;
	memcpy(&bits, &f, sizeof bits);
	plait_put_u32(out, bits);
}

static void plait_pc2_free(plait_writer *writer)
{
	plait_pc2_state *state = writer->state;
	if (state == NULL)
		return;
	for (int i = 0; i < writer->object_count; ++i)
		plait_atomic_abort(&state->files[i]);
	free(state->files);
	free(state->buffer);
	free(state);
	writer->state = NULL;
}

static bool plait_pc2_open(plait_writer *writer, plait_tool_error *error)
{
	plait_pc2_state *state = calloc(1, sizeof *state);
	if (state == NULL)
		return plait_tool_error_set(error, "out of memory");
	writer->state = state;
	int most = 1;
	for (int i = 0; i < writer->object_count; ++i)
		most = writer->objects[i].vertex_count > most ? writer->objects[i].vertex_count : most;
	state->files =
	    calloc((size_t)(writer->object_count > 0 ? writer->object_count : 1), sizeof *state->files);
	state->buffer = malloc((size_t)most * 12);
	if (state->files == NULL || state->buffer == NULL) {
		plait_pc2_free(writer);
		return plait_tool_error_set(error, "out of memory");
	}
	for (int i = 0; i < writer->object_count; ++i) {
		const plait_output_object *object = &writer->objects[i];
		char name[96];
		snprintf(name, sizeof name, "%s.obj", object->name);
		if (!plait_writer_write_obj(writer, object, name, 0, error)) {
			plait_pc2_free(writer);
			return false;
		}
		snprintf(name, sizeof name, "%s.pc2", object->name);
		if (!plait_atomic_open(&state->files[i], writer->dir, name, error)) {
			plait_pc2_free(writer);
			return false;
		}
		unsigned char header[32] = "POINTCACHE2";
		plait_put_u32(header + 12, 1);
		plait_put_u32(header + 16, (uint32_t)object->vertex_count);
		plait_put_f32(header + 20, 0.0f); // first sample is frame 0
		plait_put_f32(header + 24, 1.0f); // one sample per frame
		plait_put_u32(header + PLAIT_PC2_SAMPLES_OFFSET, 0);
		if (fwrite(header, 1, sizeof header, state->files[i].file) != sizeof header) {
			plait_tool_error_set(error, "%s: cannot write", state->files[i].temp_path);
			plait_pc2_free(writer);
			return false;
		}
	}
	return true;
}

static bool plait_pc2_write_frame(plait_writer *writer, int frame, plait_tool_error *error)
{
	plait_pc2_state *state = writer->state;
	for (int i = 0; i < writer->object_count; ++i) {
		const plait_output_object *object = &writer->objects[i];
		if (!plait_writer_read_positions(writer, object, error))
			return false;
		for (int k = 0; k < object->vertex_count; ++k) {
			plait_put_f32(state->buffer + 12 * k + 0, writer->positions[k].x);
			plait_put_f32(state->buffer + 12 * k + 4, writer->positions[k].y);
			plait_put_f32(state->buffer + 12 * k + 8, writer->positions[k].z);
		}
		size_t size = (size_t)object->vertex_count * 12;
		if (fwrite(state->buffer, 1, size, state->files[i].file) != size)
			return plait_tool_error_set(error, "%s: cannot write frame %d", state->files[i].temp_path, frame);
	}
	return true;
}

static bool plait_pc2_close(plait_writer *writer, plait_tool_error *error)
{
	plait_pc2_state *state = writer->state;
	bool ok = true;
	for (int i = 0; ok && i < writer->object_count; ++i) {
		unsigned char count[4];
		plait_put_u32(count, (uint32_t)writer->frames_written);
		FILE *f = state->files[i].file;
		if (fseek(f, PLAIT_PC2_SAMPLES_OFFSET, SEEK_SET) != 0 || fwrite(count, 1, 4, f) != 4)
			ok = plait_tool_error_set(error, "%s: cannot write", state->files[i].temp_path);
		else
			ok = plait_atomic_commit(&state->files[i], error);
	}
	plait_pc2_free(writer);
	return ok;
}

const plait_writer_format plait_writer_pc2 = {"pc2", "PC2 point cache, DIR/NAME.pc2 per object",
                                              plait_pc2_open, plait_pc2_write_frame, plait_pc2_close};
