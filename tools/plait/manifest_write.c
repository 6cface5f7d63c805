/* Writing DIR/manifest.json during `plait run`. */
#include "manifest.h"

#include "files.h"
#include "json_write.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const plait_type_words[] = {"cloth", "curve", "particles", "collider"};
static const char *const plait_shape_words[] = {"plane", "sphere", "capsule", "box", "mesh"};

void plait_manifest_free(plait_manifest *manifest)
{
	for (int i = 0; i < manifest->object_count; ++i)
		free(manifest->objects[i].shapes);
	free(manifest->objects);
	*manifest = (plait_manifest){0};
}

static bool plait_scene_object_collides(const plait_scene_object *object)
{
	switch (object->type) {
	case PLAIT_OBJECT_CLOTH:
		return object->cloth.surface.collide;
	case PLAIT_OBJECT_CURVE:
		return object->curve.surface.collide;
	case PLAIT_OBJECT_PARTICLES:
		return object->particles.surface.collide;
	case PLAIT_OBJECT_COLLIDER:
		return object->collider.surface.collide;
	}
	return true;
}

bool plait_manifest_begin(plait_manifest *manifest, const plait_writer *writer, const plait_scene *scene,
                          plait_tool_error *error)
{
	*manifest = (plait_manifest){0};
	size_t size = strlen(writer->dir) + sizeof PLAIT_MANIFEST_NAME + 1;
	char *path = malloc(size);
	if (path == NULL)
		return plait_tool_error_set(error, "out of memory");
	snprintf(path, size, "%s/%s", writer->dir, PLAIT_MANIFEST_NAME);
	// The old manifest would describe frames this run is about to overwrite.
	if (remove(path) != 0 && errno != ENOENT) {
		int code = errno;
		plait_tool_error_set(error, "%s: cannot remove the previous run's manifest: %s", path,
		                     strerror(code));
		free(path);
		return false;
	}
	free(path);
	snprintf(manifest->format, sizeof manifest->format, "%s", writer->format->name);
	plait_world_def def = plait_world_get_def(writer->world);
	manifest->fps = def.fps;
	manifest->space_scale = def.space_scale;
	manifest->first_frame = 0;
	manifest->last_frame = -1;
	manifest->objects =
	    calloc((size_t)(writer->object_count > 0 ? writer->object_count : 1), sizeof *manifest->objects);
	if (manifest->objects == NULL)
		return plait_tool_error_set(error, "out of memory");
	manifest->object_count = writer->object_count;
	bool pc2 = strcmp(writer->format->name, "pc2") == 0;
	for (int i = 0; i < writer->object_count; ++i) {
		const plait_output_object *output = &writer->objects[i];
		plait_manifest_object *object = &manifest->objects[i];
		snprintf(object->name, sizeof object->name, "%s", output->name);
		object->type = output->type;
		object->vertex_count = output->vertex_count;
		object->collide = scene == NULL || output->world_index >= scene->object_count ||
		                  plait_scene_object_collides(&scene->objects[output->world_index]);
		snprintf(object->file, sizeof object->file, pc2 ? "%s.pc2" : "%s.%%04d.obj", output->name);
		if (pc2)
			snprintf(object->mesh, sizeof object->mesh, "%s.obj", output->name);
		if (object->type == PLAIT_OBJECT_COLLIDER) {
			plait_collider_shape shape;
			plait_error core_error = {0};
			if (plait_collider_get_shape(output->id, &shape, &core_error) != PLAIT_OK)
				return plait_tool_error_set(error, "\"%s\": %s", output->name, core_error.message);
			object->shape = shape.type;
			object->closed = plait_collider_is_closed(output->id);
		}
	}
	return true;
}

bool plait_manifest_record_frame(plait_manifest *manifest, const plait_writer *writer, int frame,
                                 plait_tool_error *error)
{
	int count =
	    manifest->last_frame < manifest->first_frame ? 0 : manifest->last_frame - manifest->first_frame + 1;
	if (count == 0)
		manifest->first_frame = frame;
	else if (frame != manifest->last_frame + 1)
		return plait_tool_error_set(error, "manifest: frame %d recorded after frame %d", frame,
		                            manifest->last_frame);
	for (int i = 0; i < manifest->object_count; ++i) {
		plait_manifest_object *object = &manifest->objects[i];
		if (object->type != PLAIT_OBJECT_COLLIDER || object->shape == PLAIT_SHAPE_MESH)
			continue;
		if (count >= object->shape_capacity) {
			int capacity = object->shape_capacity > 0 ? 2 * object->shape_capacity : 64;
			plait_collider_shape *grown = realloc(object->shapes, sizeof *grown * (size_t)capacity);
			if (grown == NULL)
				return plait_tool_error_set(error, "out of memory");
			object->shapes = grown;
			object->shape_capacity = capacity;
		}
		plait_error core_error = {0};
		if (plait_collider_get_shape(writer->objects[i].id, &object->shapes[count], &core_error) != PLAIT_OK)
			return plait_tool_error_set(error, "\"%s\": %s", object->name, core_error.message);
	}
	manifest->last_frame = frame;
	return true;
}

static void plait_put_vec3(FILE *f, const char *key, plait_vec3 v)
{
	fprintf(f, "\"%s\": [%.9g, %.9g, %.9g]", key, v.x, v.y, v.z);
}

static void plait_put_shape(FILE *f, const plait_collider_shape *shape)
{
	fputc('{', f);
	switch (shape->type) {
	case PLAIT_SHAPE_PLANE:
		plait_put_vec3(f, "point", shape->point);
		fputs(", ", f);
		plait_put_vec3(f, "normal", shape->normal);
		break;
	case PLAIT_SHAPE_SPHERE:
		plait_put_vec3(f, "center", shape->center);
		fprintf(f, ", \"radius\": %.9g", shape->radius);
		break;
	case PLAIT_SHAPE_CAPSULE:
		plait_put_vec3(f, "a", shape->a);
		fputs(", ", f);
		plait_put_vec3(f, "b", shape->b);
		fprintf(f, ", \"radius\": %.9g", shape->radius);
		break;
	case PLAIT_SHAPE_BOX:
		plait_put_vec3(f, "center", shape->center);
		fputs(", ", f);
		plait_put_vec3(f, "half_extents", shape->half_extents);
		fprintf(f, ", \"axes\": [[%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g], [%.9g, %.9g, %.9g]]",
		        shape->axes[0].x, shape->axes[0].y, shape->axes[0].z, shape->axes[1].x, shape->axes[1].y,
		        shape->axes[1].z, shape->axes[2].x, shape->axes[2].y, shape->axes[2].z);
		break;
	case PLAIT_SHAPE_MESH:
		break;
	}
	fputc('}', f);
}

bool plait_manifest_commit(const plait_manifest *manifest, const char *dir, plait_tool_error *error)
{
	plait_atomic_file out;
	if (!plait_atomic_open(&out, dir, PLAIT_MANIFEST_NAME, error))
		return false;
	FILE *f = out.file;
	int frames = manifest->last_frame - manifest->first_frame + 1;
	fprintf(f, "{\"plait\": \"%d.%d.%d\", \"manifest\": %d, \"format\": ", PLAIT_VERSION_MAJOR,
	        PLAIT_VERSION_MINOR, PLAIT_VERSION_PATCH, PLAIT_MANIFEST_VERSION);
	plait_json_put_string(f, manifest->format);
	fprintf(
	    f,
	    ",\n \"first_frame\": %d, \"last_frame\": %d, \"fps\": %.9g, \"space_scale\": %.9g,\n \"objects\": [",
	    manifest->first_frame, manifest->last_frame, manifest->fps, manifest->space_scale);
	for (int i = 0; i < manifest->object_count; ++i) {
		const plait_manifest_object *object = &manifest->objects[i];
		fputs(i == 0 ? "\n  {\"name\": " : ",\n  {\"name\": ", f);
		plait_json_put_string(f, object->name);
		fprintf(f, ", \"type\": \"%s\", \"collide\": %s, \"vertices\": %d, \"file\": ",
		        plait_type_words[object->type], object->collide ? "true" : "false", object->vertex_count);
		plait_json_put_string(f, object->file);
		if (object->mesh[0] != '\0') {
			fputs(", \"mesh\": ", f);
			plait_json_put_string(f, object->mesh);
		}
		if (object->type == PLAIT_OBJECT_COLLIDER) {
			fprintf(f, ", \"shape\": \"%s\", \"closed\": %s", plait_shape_words[object->shape],
			        object->closed ? "true" : "false");
			if (object->shape != PLAIT_SHAPE_MESH) {
				fputs(",\n   \"shapes\": [", f);
				for (int k = 0; k < frames; ++k) {
					fputs(k == 0 ? "\n    " : ",\n    ", f);
					plait_put_shape(f, &object->shapes[k]);
				}
				fputs("]", f);
			}
		}
		fputc('}', f);
	}
	fputs("]}\n", f);
	if (ferror(f)) {
		plait_tool_error_set(error, "%s: cannot write", out.temp_path);
		plait_atomic_abort(&out);
		return false;
	}
	return plait_atomic_commit(&out, error);
}
