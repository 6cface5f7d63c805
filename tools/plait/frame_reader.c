#include "frame_reader.h"

#include "grow_array.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PLAIT_PC2_HEADER_SIZE 32

static const char *plait_skip_blanks(const char *c, const char *end)
{
	while (c < end && (*c == ' ' || *c == '\t' || *c == '\r'))
		++c;
	return c;
}

// One face index: "i", "i/t", "i//n" or "i/t/n", 1-based or negative (counted back from the
// vertices read so far). Returns the 0-based index through *index, or false.
static bool plait_parse_index(const char **c, const char *end, int vertices_so_far, long *index)
{
	char *stop;
	long value = strtol(*c, &stop, 10);
	if (stop == *c || stop > end || value == 0)
		return false;
	*index = value > 0 ? value - 1 : vertices_so_far + value;
	const char *p = stop;
	while (p < end && *p != ' ' && *p != '\t' && *p != '\r')
		++p; // texture and normal indices are not needed
	*c = p;
	return true;
}

bool plait_obj_parse(const char *text, size_t size, const char *path, plait_frame_mesh *mesh,
                     plait_tool_error *error)
{
	mesh->vertex_count = 0;
	mesh->triangle_count = 0;
	const char *c = text, *text_end = text + size;
	int line = 0;
	long face[3];
	while (c < text_end) {
		++line;
		const char *end = memchr(c, '\n', (size_t)(text_end - c));
		if (end == NULL)
			end = text_end;
		c = plait_skip_blanks(c, end);
		if (end - c >= 2 && c[0] == 'v' && (c[1] == ' ' || c[1] == '\t')) {
			float xyz[3];
			c += 2;
			for (int k = 0; k < 3; ++k) {
				c = plait_skip_blanks(c, end);
				char *stop;
				xyz[k] = c < end ? strtof(c, &stop) : 0.0f;
				if (c >= end || stop == c || stop > end)
					return plait_tool_error_set(error, "%s:%d: a vertex needs x, y and z", path, line);
				if (!isfinite(xyz[k]))
					return plait_tool_error_set(error, "%s:%d: a vertex has a non-finite coordinate", path,
					                            line);
				c = stop;
			}
			if (mesh->vertex_count == INT_MAX ||
			    !plait_grow_array((void **)&mesh->positions, &mesh->vertex_capacity, mesh->vertex_count + 1,
			                      sizeof *mesh->positions))
				return plait_tool_error_set(error, "%s: out of memory", path);
			mesh->positions[mesh->vertex_count++] = (plait_vec3){xyz[0], xyz[1], xyz[2]};
		} else if (end - c >= 2 && c[0] == 'f' && (c[1] == ' ' || c[1] == '\t')) {
			// Fanned from the first vertex, as the library fans polygons.
			c += 2;
			int corners = 0;
			for (;;) {
				c = plait_skip_blanks(c, end);
				if (c >= end)
					break;
				long index;
				if (!plait_parse_index(&c, end, mesh->vertex_count, &index))
					return plait_tool_error_set(error, "%s:%d: a face index is not a vertex number", path,
					                            line);
				if (index < 0 || index > INT_MAX)
					return plait_tool_error_set(error, "%s:%d: face index %ld is out of range", path, line,
					                            index + 1);
				if (corners < 2) {
					face[corners] = index;
				} else {
					face[2] = index;
					if (!plait_grow_array((void **)&mesh->triangles, &mesh->triangle_capacity,
					                      mesh->triangle_count + 1, sizeof *mesh->triangles))
						return plait_tool_error_set(error, "%s: out of memory", path);
					int *t = mesh->triangles[mesh->triangle_count++];
					t[0] = (int)face[0];
					t[1] = (int)face[1];
					t[2] = (int)face[2];
					face[1] = face[2];
				}
				++corners;
			}
			if (corners < 3)
				return plait_tool_error_set(error, "%s:%d: a face needs at least 3 vertices, got %d", path,
				                            line, corners);
		}
		c = end + 1;
	}
	for (int t = 0; t < mesh->triangle_count; ++t)
		for (int k = 0; k < 3; ++k)
			if (mesh->triangles[t][k] >= mesh->vertex_count)
				return plait_tool_error_set(error, "%s: a face uses vertex %d of %d", path,
				                            mesh->triangles[t][k] + 1, mesh->vertex_count);
	return true;
}

static char *plait_path(const char *dir, const char *name)
{
	size_t size = strlen(dir) + strlen(name) + 2;
	char *path = malloc(size);
	if (path != NULL)
		snprintf(path, size, "%s/%s", dir, name);
	return path;
}

// The whole file into reader->text, NUL-terminated.
static bool plait_read_text(plait_frame_reader *reader, const char *path, size_t *size,
                            plait_tool_error *error)
{
	FILE *f = fopen(path, "rb");
	if (f == NULL) {
		int code = errno;
		return plait_tool_error_set(error, "%s: cannot read: %s", path, strerror(code));
	}
	size_t used = 0;
	for (;;) {
		if (used + 65536 + 1 > reader->text_capacity) {
			size_t capacity = reader->text_capacity > 0 ? 2 * reader->text_capacity : 1 << 20;
			char *grown = realloc(reader->text, capacity);
			if (grown == NULL) {
				fclose(f);
				return plait_tool_error_set(error, "%s: out of memory", path);
			}
			reader->text = grown;
			reader->text_capacity = capacity;
		}
		size_t got = fread(reader->text + used, 1, reader->text_capacity - used - 1, f);
		used += got;
		if (got == 0)
			break;
	}
	bool failed = ferror(f) != 0;
	fclose(f);
	if (failed)
		return plait_tool_error_set(error, "%s: cannot read", path);
	reader->text[used] = '\0';
	*size = used;
	return true;
}

// Reads an OBJ and checks it has the vertices the manifest says (a cut file has fewer).
static bool plait_read_obj(plait_frame_reader *reader, const plait_manifest_object *object, const char *name,
                           plait_frame_mesh *mesh, plait_tool_error *error)
{
	char *path = plait_path(reader->dir, name);
	if (path == NULL)
		return plait_tool_error_set(error, "out of memory");
	size_t size = 0;
	bool ok =
	    plait_read_text(reader, path, &size, error) && plait_obj_parse(reader->text, size, path, mesh, error);
	if (ok && mesh->vertex_count != object->vertex_count)
		ok = plait_tool_error_set(error,
		                          "%s: %d vertices, but the manifest says \"%s\" has %d (a file cut short?)",
		                          path, mesh->vertex_count, object->name, object->vertex_count);
	bool needs_faces = object->type == PLAIT_OBJECT_CLOTH || object->type == PLAIT_OBJECT_COLLIDER;
	if (ok && needs_faces && mesh->triangle_count == 0 && object->vertex_count > 0)
		ok = plait_tool_error_set(error, "%s: no faces (a file cut short?)", path);
	free(path);
	return ok;
}

static uint32_t plait_get_u32(const unsigned char *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float plait_get_f32(const unsigned char *p)
{
	uint32_t bits = plait_get_u32(p);
	float f;
	memcpy(&f, &bits, sizeof f);
	return f;
}

static bool plait_open_cache(plait_frame_reader *reader, int i, plait_tool_error *error)
{
	const plait_manifest *m = reader->manifest;
	const plait_manifest_object *object = &m->objects[i];
	char *path = plait_path(reader->dir, object->file);
	if (path == NULL)
		return plait_tool_error_set(error, "out of memory");
	FILE *f = fopen(path, "rb");
	if (f == NULL) {
		int code = errno;
		plait_tool_error_set(error, "%s: cannot read: %s", path, strerror(code));
		free(path);
		return false;
	}
	reader->caches[i] = f;
	unsigned char header[PLAIT_PC2_HEADER_SIZE];
	bool ok = true;
	long long frames = (long long)m->last_frame - m->first_frame + 1;
	long long needed = PLAIT_PC2_HEADER_SIZE + frames * object->vertex_count * 12;
	if (fread(header, 1, sizeof header, f) != sizeof header || memcmp(header, "POINTCACHE2", 12) != 0)
		ok = plait_tool_error_set(error, "%s: not a PC2 point cache (no POINTCACHE2 header)", path);
	else if (plait_get_u32(header + 16) != (uint32_t)object->vertex_count)
		ok = plait_tool_error_set(error, "%s: %u points, but the manifest says \"%s\" has %d", path,
		                          plait_get_u32(header + 16), object->name, object->vertex_count);
	else if (plait_get_f32(header + 20) != (float)m->first_frame || plait_get_f32(header + 24) != 1.0f)
		ok = plait_tool_error_set(
		    error, "%s: starts at frame %g with %g samples per frame; expected frame %d, 1", path,
		    (double)plait_get_f32(header + 20), (double)plait_get_f32(header + 24), m->first_frame);
	else if ((long long)plait_get_u32(header + 28) < frames)
		ok = plait_tool_error_set(error, "%s: %u samples, but the manifest lists %lld frames", path,
		                          plait_get_u32(header + 28), frames);
	else if (fseek(f, 0, SEEK_END) != 0 || ftell(f) < needed)
		ok = plait_tool_error_set(error,
		                          "%s: %ld bytes, %lld needed for %lld frames of %d points (cut short?)",
		                          path, ftell(f), needed, frames, object->vertex_count);
	free(path);
	return ok;
}

bool plait_frame_reader_open(plait_frame_reader *reader, const char *dir, const plait_manifest *manifest,
                             plait_tool_error *error)
{
	*reader = (plait_frame_reader){0};
	reader->manifest = manifest;
	reader->dir = strdup(dir);
	size_t count = (size_t)(manifest->object_count > 0 ? manifest->object_count : 1);
	reader->meshes = calloc(count, sizeof *reader->meshes);
	reader->caches = calloc(count, sizeof *reader->caches);
	int most = 1;
	for (int i = 0; i < manifest->object_count; ++i)
		most = manifest->objects[i].vertex_count > most ? manifest->objects[i].vertex_count : most;
	reader->sample = malloc((size_t)most * 12);
	if (reader->dir == NULL || reader->meshes == NULL || reader->caches == NULL || reader->sample == NULL) {
		plait_frame_reader_close(reader);
		return plait_tool_error_set(error, "out of memory");
	}
	if (strcmp(manifest->format, "pc2") != 0)
		return true;
	for (int i = 0; i < manifest->object_count; ++i) {
		const plait_manifest_object *object = &manifest->objects[i];
		if (!plait_open_cache(reader, i, error) ||
		    !plait_read_obj(reader, object, object->mesh, &reader->meshes[i], error)) {
			plait_frame_reader_close(reader);
			return false;
		}
	}
	return true;
}

static bool plait_read_sample(plait_frame_reader *reader, int i, int frame, plait_tool_error *error)
{
	const plait_manifest_object *object = &reader->manifest->objects[i];
	plait_frame_mesh *mesh = &reader->meshes[i];
	FILE *f = reader->caches[i];
	long long sample = frame - reader->manifest->first_frame;
	long long offset = PLAIT_PC2_HEADER_SIZE + sample * object->vertex_count * 12;
	size_t size = (size_t)object->vertex_count * 12;
	if (offset > LONG_MAX || fseek(f, (long)offset, SEEK_SET) != 0 ||
	    fread(reader->sample, 1, size, f) != size)
		return plait_tool_error_set(error, "%s/%s: cannot read frame %d", reader->dir, object->file, frame);
	for (int k = 0; k < object->vertex_count; ++k) {
		const unsigned char *p = reader->sample + 12 * (size_t)k;
		plait_vec3 v = {plait_get_f32(p), plait_get_f32(p + 4), plait_get_f32(p + 8)};
		if (!isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z))
			return plait_tool_error_set(error, "%s/%s: frame %d: vertex %d is not finite", reader->dir,
			                            object->file, frame, k);
		mesh->positions[k] = v;
	}
	return true;
}

bool plait_frame_reader_read(plait_frame_reader *reader, int frame, plait_tool_error *error)
{
	const plait_manifest *m = reader->manifest;
	bool pc2 = reader->caches != NULL && strcmp(m->format, "pc2") == 0;
	for (int i = 0; i < m->object_count; ++i) {
		const plait_manifest_object *object = &m->objects[i];
		if (pc2) {
			if (!plait_read_sample(reader, i, frame, error))
				return false;
			continue;
		}
		char name[PLAIT_MANIFEST_FILE_SIZE + 16];
		if (!plait_manifest_frame_file(object, frame, name, sizeof name))
			return plait_tool_error_set(error, "%s: frame file name too long", object->name);
		if (!plait_read_obj(reader, object, name, &reader->meshes[i], error))
			return false;
	}
	return true;
}

void plait_frame_reader_close(plait_frame_reader *reader)
{
	const plait_manifest *m = reader->manifest;
	for (int i = 0; m != NULL && i < m->object_count; ++i) {
		if (reader->meshes != NULL) {
			free(reader->meshes[i].positions);
			free(reader->meshes[i].triangles);
		}
		if (reader->caches != NULL && reader->caches[i] != NULL)
			fclose(reader->caches[i]);
	}
	free(reader->meshes);
	free(reader->caches);
	free(reader->text);
	free(reader->sample);
	free(reader->dir);
	*reader = (plait_frame_reader){0};
}
