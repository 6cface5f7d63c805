/* Turning a loaded scene into a world, and driving it frame by frame. */
#include "scene.h"

#include <stdio.h>

static const char *const plait_type_words[] = {"cloth", "curve", "particles", "collider"};

static plait_object_id plait_scene_create_object(plait_world_id world, const plait_scene_object *object,
                                                 plait_error *error)
{
	switch (object->type) {
	case PLAIT_OBJECT_CLOTH: {
		plait_cloth_def def = object->cloth;
		def.name = object->name;
		def.mesh = (plait_mesh_def){object->positions, object->vertex_count, object->face_sizes,
		                            object->face_count, object->face_indices};
		def.velocities = object->velocities;
		def.pins = object->pins;
		def.pin_count = object->pin_count;
		return plait_create_cloth(world, &def, error);
	}
	case PLAIT_OBJECT_CURVE: {
		plait_curve_def def = object->curve;
		def.name = object->name;
		def.positions = object->positions;
		def.vertex_count = object->vertex_count;
		def.velocities = object->velocities;
		def.pins = object->pins;
		def.pin_count = object->pin_count;
		return plait_create_curve(world, &def, error);
	}
	case PLAIT_OBJECT_PARTICLES: {
		plait_particles_def def = object->particles;
		def.name = object->name;
		def.positions = object->positions;
		def.count = object->vertex_count;
		def.velocities = object->velocities;
		return plait_create_particles(world, &def, error);
	}
	case PLAIT_OBJECT_COLLIDER: {
		plait_collider_def def = object->collider;
		def.name = object->name;
		if (def.shape == PLAIT_SHAPE_MESH) {
			def.mesh = (plait_mesh_def){object->positions, object->vertex_count, object->face_sizes,
			                            object->face_count, object->face_indices};
			def.deforming = object->sequence.frame_count > 0;
		}
		return plait_create_collider(world, &def, error);
	}
	}
	return (plait_object_id){0};
}

bool plait_scene_create_world(const plait_scene *scene, plait_world_id *world, plait_tool_error *error)
{
	*world = (plait_world_id){0};
	plait_error core_error = {0};
	plait_world_id id = plait_create_world(&scene->world, &core_error);
	if (plait_world_id_is_null(id))
		return plait_tool_error_set(error, "%s: world: the solver rejected the settings: %s", scene->file,
		                            core_error.message);
	for (int i = 0; i < scene->object_count; ++i) {
		const plait_scene_object *object = &scene->objects[i];
		core_error = (plait_error){0};
		plait_object_id object_id = plait_scene_create_object(id, object, &core_error);
		if (plait_object_id_is_null(object_id)) {
			plait_destroy_world(id);
			return plait_tool_error_set(error, "%s: objects[%d] (%s \"%s\"): the solver rejected it: %s",
			                            scene->file, i, plait_type_words[object->type], object->name,
			                            core_error.message);
		}
	}
	*world = id;
	return true;
}

static float plait_lerp(float a, float b, float t)
{
	return a + (b - a) * t;
}

static plait_vec3 plait_lerp3(plait_vec3 a, plait_vec3 b, float t)
{
	return (plait_vec3){plait_lerp(a.x, b.x, t), plait_lerp(a.y, b.y, t), plait_lerp(a.z, b.z, t)};
}

plait_transform plait_scene_collider_transform(const plait_scene_object *object, int frame)
{
	int n = object->keyframe_count;
	const plait_scene_keyframe *keys = object->keyframes;
	if (n == 0)
		return object->collider.transform;
	if (frame <= keys[0].frame)
		return keys[0].transform;
	if (frame >= keys[n - 1].frame)
		return keys[n - 1].transform;
	int k = 0;
	while (keys[k + 1].frame < frame)
		++k;
	// Rotations interpolate per angle like the solver does between frames (seed 000 §2.3).
	const plait_transform *a = &keys[k].transform, *b = &keys[k + 1].transform;
	float t = (float)(frame - keys[k].frame) / (float)(keys[k + 1].frame - keys[k].frame);
	plait_transform result = {plait_lerp3(a->translate, b->translate, t),
	                          plait_lerp3(a->rotate_deg, b->rotate_deg, t),
	                          plait_lerp(a->scale, b->scale, t)};
	return result;
}

bool plait_scene_apply_frame(const plait_scene *scene, plait_world_id world, int frame,
                             plait_tool_error *error)
{
	for (int i = 0; i < scene->object_count; ++i) {
		const plait_scene_object *object = &scene->objects[i];
		plait_object_id id = plait_world_get_object(world, i);
		plait_error core_error = {0};
		if (object->type == PLAIT_OBJECT_COLLIDER && object->keyframe_count > 0) {
			plait_transform transform = plait_scene_collider_transform(object, frame);
			if (plait_collider_set_transform(id, transform, &core_error) != PLAIT_OK)
				return plait_tool_error_set(error,
				                            "%s: objects[%d] (\"%s\"): cannot move collider at frame %d: %s",
				                            scene->file, i, object->name, frame, core_error.message);
		}
		if (object->type == PLAIT_OBJECT_COLLIDER && object->sequence.frame_count > 0) {
			const plait_vec3 *shape = plait_mesh_sequence_frame(&object->sequence, frame);
			if (plait_collider_set_mesh_positions(id, shape, object->sequence.vertex_count, &core_error) !=
			    PLAIT_OK)
				return plait_tool_error_set(
				    error, "%s: objects[%d] (\"%s\"): cannot deform collider at frame %d: %s", scene->file, i,
				    object->name, frame, core_error.message);
		}
		for (int p = 0; p < object->pin_count; ++p) {
			int vertex = object->pins[p];
			if (plait_object_set_pin_target(id, vertex, object->positions[vertex], &core_error) != PLAIT_OK)
				return plait_tool_error_set(error,
				                            "%s: objects[%d] (\"%s\"): cannot hold pin %d at frame %d: %s",
				                            scene->file, i, object->name, vertex, frame, core_error.message);
		}
	}
	return true;
}
