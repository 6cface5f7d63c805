#include "scene_keys.h"

#include "grid.h"
#include "scene.h"

#include <math.h>
#include <stddef.h>

// CHOICE keys store the index of the name into a C enum as an int.
_Static_assert(sizeof(plait_bend_model) == sizeof(int), "plait_bend_model is not an int");
_Static_assert(sizeof(plait_tether_mode) == sizeof(int), "plait_tether_mode is not an int");
_Static_assert(sizeof(plait_self_collision_flag) == sizeof(int), "plait_self_collision_flag is not an int");
_Static_assert(sizeof(plait_collision_flag) == sizeof(int), "plait_collision_flag is not an int");

// The names of enum values as scene files write them, indexed by value.
static const char *const plait_bend_models[] = {
    [PLAIT_BEND_DIHEDRAL] = "dihedral",
    [PLAIT_BEND_DISTANCE] = "distance",
};
static const char *const plait_tether_modes[] = {
    [PLAIT_TETHER_NONE] = "none",
    [PLAIT_TETHER_EUCLIDEAN] = "euclidean",
    [PLAIT_TETHER_GEODESIC] = "geodesic",
};
static const char *const plait_self_collision_flags[] = {
    [PLAIT_SELF_COLLIDE_FULL_SURFACE] = "full_surface",
    [PLAIT_SELF_COLLIDE_VERTEX_FACE] = "vertex_face",
    [PLAIT_SELF_COLLIDE_VERTEX] = "vertex",
};
static const char *const plait_collision_flags[] = {
    [PLAIT_COLLIDE_FULL_SURFACE] = "full_surface",
    [PLAIT_COLLIDE_VERTEX] = "vertex",
};

// Ranges as (min, max, min_excluded).
#define PLAIT_ANY -INFINITY, INFINITY, false
#define PLAIT_AT_LEAST(x) (x), INFINITY, false
#define PLAIT_ABOVE(x) (x), INFINITY, true
#define PLAIT_ABOVE_UP_TO(a, b) (a), (b), true
#define PLAIT_BETWEEN(a, b) (a), (b), false
#define PLAIT_NO_RANGE 0, 0, false

#define PLAIT_SPECIAL(name, required)                                                                        \
	{                                                                                                        \
		name, PLAIT_KEY_SPECIAL, PLAIT_NO_RANGE, 0, required, NULL, 0                                        \
	}
#define PLAIT_FLOAT(name, range, T, member)                                                                  \
	{                                                                                                        \
		name, PLAIT_KEY_FLOAT, range, offsetof(T, member), false, NULL, 0                                    \
	}
#define PLAIT_INT(name, range, T, member)                                                                    \
	{                                                                                                        \
		name, PLAIT_KEY_INT, range, offsetof(T, member), false, NULL, 0                                      \
	}
#define PLAIT_BOOL(name, T, member)                                                                          \
	{                                                                                                        \
		name, PLAIT_KEY_BOOL, PLAIT_NO_RANGE, offsetof(T, member), false, NULL, 0                            \
	}
#define PLAIT_VEC3(name, T, member)                                                                          \
	{                                                                                                        \
		name, PLAIT_KEY_VEC3, PLAIT_ANY, offsetof(T, member), false, NULL, 0                                 \
	}
// A string naming a value of an enum member; names is an array of the value names.
#define PLAIT_CHOICE(name, names, T, member)                                                                 \
	{                                                                                                        \
		name, PLAIT_KEY_CHOICE, PLAIT_NO_RANGE, offsetof(T, member), false, names,                           \
		    (int)(sizeof names / sizeof names[0])                                                            \
	}

// Keys every object has; T is the def type of the object. The range of collision_layer is
// checked by the library when the object is created (the message names the object).
#define PLAIT_OBJECT_KEYS(T)                                                                                 \
	PLAIT_SPECIAL("name", false), PLAIT_SPECIAL("type", true),                                               \
	    PLAIT_FLOAT("thickness", PLAIT_BETWEEN(0, 1e6), T, surface.thickness),                               \
	    PLAIT_FLOAT("friction", PLAIT_BETWEEN(0, 10), T, surface.friction),                                  \
	    PLAIT_FLOAT("stickiness", PLAIT_BETWEEN(0, 1), T, surface.stickiness),                               \
	    PLAIT_FLOAT("bounce", PLAIT_BETWEEN(0, 1), T, surface.bounce),                                       \
	    PLAIT_BOOL("collide", T, surface.collide),                                                           \
	    PLAIT_INT("collision_layer", PLAIT_ANY, T, surface.collision_layer)

static const plait_scene_key plait_top_keys[] = {
    PLAIT_SPECIAL("world", false),
    PLAIT_INT("frames", PLAIT_BETWEEN(0, 1000000), plait_scene, frames),
    PLAIT_SPECIAL("objects", true),
};

static const plait_scene_key plait_world_keys[] = {
    PLAIT_FLOAT("fps", PLAIT_ABOVE(0), plait_world_def, fps),
    PLAIT_INT("substeps", PLAIT_BETWEEN(1, 1000), plait_world_def, substeps),
    PLAIT_INT("max_collision_iterations", PLAIT_BETWEEN(0, 1000), plait_world_def, max_collision_iterations),
    PLAIT_INT("contact_pass_interval", PLAIT_BETWEEN(0, 1000), plait_world_def, contact_pass_interval),
    PLAIT_VEC3("gravity", plait_world_def, gravity),
    PLAIT_FLOAT("air_density", PLAIT_AT_LEAST(0), plait_world_def, air_density),
    PLAIT_SPECIAL("wind", false),
    PLAIT_FLOAT("space_scale", PLAIT_ABOVE(0), plait_world_def, space_scale),
    PLAIT_FLOAT("time_scale", PLAIT_ABOVE(0), plait_world_def, time_scale),
    {"seed", PLAIT_KEY_UINT32, PLAIT_BETWEEN(0, 4294967295.0), offsetof(plait_world_def, seed), false, NULL,
     0},
    PLAIT_BOOL("cloth_contacts", plait_world_def, cloth_contacts),
    PLAIT_BOOL("untangle", plait_world_def, untangle),
};

static const plait_scene_key plait_wind_keys[] = {
    PLAIT_FLOAT("speed", PLAIT_AT_LEAST(0), plait_world_def, wind.speed),
    PLAIT_VEC3("direction", plait_world_def, wind.direction),
    PLAIT_FLOAT("noise", PLAIT_BETWEEN(0, 10), plait_world_def, wind.noise),
};

static const plait_scene_key plait_cloth_keys[] = {
    PLAIT_OBJECT_KEYS(plait_cloth_def),
    PLAIT_SPECIAL("mesh", false),
    PLAIT_SPECIAL("grid", false),
    PLAIT_SPECIAL("velocities", false),
    PLAIT_SPECIAL("pins", false),
    PLAIT_FLOAT("density", PLAIT_ABOVE_UP_TO(0, 1e6), plait_cloth_def, density),
    PLAIT_FLOAT("stretch_resistance", PLAIT_BETWEEN(0, 10000), plait_cloth_def, stretch_resistance),
    PLAIT_FLOAT("compression_resistance", PLAIT_BETWEEN(0, 10000), plait_cloth_def, compression_resistance),
    PLAIT_FLOAT("shear_resistance", PLAIT_BETWEEN(0, 10000), plait_cloth_def, shear_resistance),
    PLAIT_FLOAT("bend_resistance", PLAIT_BETWEEN(0, 10000), plait_cloth_def, bend_resistance),
    PLAIT_CHOICE("bend_model", plait_bend_models, plait_cloth_def, bend_model),
    PLAIT_FLOAT("rest_length_scale", PLAIT_BETWEEN(0.01, 10), plait_cloth_def, rest_length_scale),
    PLAIT_FLOAT("drag", PLAIT_BETWEEN(0, 1e6), plait_cloth_def, drag),
    PLAIT_FLOAT("tangential_drag", PLAIT_BETWEEN(0, 1e6), plait_cloth_def, tangential_drag),
    PLAIT_FLOAT("lift", PLAIT_BETWEEN(0, 1e6), plait_cloth_def, lift),
    PLAIT_FLOAT("damp", PLAIT_BETWEEN(0, 100), plait_cloth_def, damp),
    PLAIT_INT("iterations", PLAIT_BETWEEN(0, 1000), plait_cloth_def, iterations),
    PLAIT_INT("shear_iterations", PLAIT_BETWEEN(0, 1000), plait_cloth_def, shear_iterations),
    PLAIT_INT("bend_iterations", PLAIT_BETWEEN(0, 1000), plait_cloth_def, bend_iterations),
    PLAIT_CHOICE("tethers", plait_tether_modes, plait_cloth_def, tethers),
    PLAIT_FLOAT("tether_scale", PLAIT_BETWEEN(1, 10), plait_cloth_def, tether_scale),
    PLAIT_FLOAT("tether_stiffness", PLAIT_BETWEEN(0, 1), plait_cloth_def, tether_stiffness),
    PLAIT_BOOL("self_collide", plait_cloth_def, self_collide),
    PLAIT_CHOICE("self_collision_flag", plait_self_collision_flags, plait_cloth_def, self_collision_flag),
    PLAIT_CHOICE("collision_flag", plait_collision_flags, plait_cloth_def, collision_flag),
    // Range checked by the library when the cloth is created.
    PLAIT_FLOAT("self_collide_width_scale", PLAIT_ANY, plait_cloth_def, self_collide_width_scale),
};

static const plait_scene_key plait_grid_keys[] = {
    PLAIT_SPECIAL("size", true),
    PLAIT_SPECIAL("resolution", true),
    PLAIT_VEC3("center", plait_grid_def, center),
    PLAIT_VEC3("normal", plait_grid_def, normal),
};

static const plait_scene_key plait_curve_keys[] = {
    PLAIT_OBJECT_KEYS(plait_curve_def),
    PLAIT_SPECIAL("positions", true),
    PLAIT_SPECIAL("velocities", false),
    PLAIT_SPECIAL("pins", false),
    PLAIT_FLOAT("mass", PLAIT_ABOVE_UP_TO(0, 1e9), plait_curve_def, mass),
    PLAIT_FLOAT("stretch_resistance", PLAIT_BETWEEN(0, 10000), plait_curve_def, stretch_resistance),
    PLAIT_FLOAT("compression_resistance", PLAIT_BETWEEN(0, 10000), plait_curve_def, compression_resistance),
    PLAIT_FLOAT("bend_resistance", PLAIT_BETWEEN(0, 10000), plait_curve_def, bend_resistance),
    PLAIT_FLOAT("rest_length_scale", PLAIT_BETWEEN(0.01, 10), plait_curve_def, rest_length_scale),
    PLAIT_FLOAT("drag", PLAIT_BETWEEN(0, 1e6), plait_curve_def, drag),
    PLAIT_FLOAT("damp", PLAIT_BETWEEN(0, 100), plait_curve_def, damp),
    PLAIT_INT("iterations", PLAIT_BETWEEN(0, 1000), plait_curve_def, iterations),
    PLAIT_BOOL("self_collide", plait_curve_def, self_collide),
};

static const plait_scene_key plait_particles_keys[] = {
    PLAIT_OBJECT_KEYS(plait_particles_def),
    PLAIT_SPECIAL("positions", true),
    PLAIT_SPECIAL("velocities", false),
    PLAIT_FLOAT("mass", PLAIT_ABOVE_UP_TO(0, 1e9), plait_particles_def, mass),
    PLAIT_FLOAT("radius", PLAIT_ABOVE_UP_TO(0, 1e6), plait_particles_def, radius),
    PLAIT_FLOAT("drag", PLAIT_BETWEEN(0, 1e6), plait_particles_def, drag),
    PLAIT_FLOAT("damp", PLAIT_BETWEEN(0, 100), plait_particles_def, damp),
    PLAIT_BOOL("self_collide", plait_particles_def, self_collide),
};

static const plait_scene_key plait_collider_keys[] = {
    PLAIT_OBJECT_KEYS(plait_collider_def),
    PLAIT_SPECIAL("shape", true),
    PLAIT_VEC3("point", plait_collider_def, point),
    PLAIT_VEC3("normal", plait_collider_def, normal),
    PLAIT_VEC3("center", plait_collider_def, center),
    PLAIT_FLOAT("radius", PLAIT_ABOVE(0), plait_collider_def, radius),
    PLAIT_VEC3("a", plait_collider_def, a),
    PLAIT_VEC3("b", plait_collider_def, b),
    PLAIT_VEC3("size", plait_collider_def, size),
    PLAIT_VEC3("rotation", plait_collider_def, rotation_deg),
    PLAIT_SPECIAL("mesh", false),
    PLAIT_SPECIAL("sequence", false),
    PLAIT_SPECIAL("keyframes", false),
    // Colliders do not move by dynamics: damp is accepted (shared presets) and ignored.
    {"damp", PLAIT_KEY_FLOAT, PLAIT_BETWEEN(0, 100), PLAIT_KEY_IGNORED, false, NULL, 0},
};

static const plait_scene_key plait_keyframe_keys[] = {
    {"frame", PLAIT_KEY_INT, PLAIT_BETWEEN(0, 1000000), offsetof(plait_scene_keyframe, frame), true, NULL, 0},
    PLAIT_VEC3("translate", plait_scene_keyframe, transform.translate),
    PLAIT_VEC3("rotate", plait_scene_keyframe, transform.rotate_deg),
    PLAIT_FLOAT("scale", PLAIT_ABOVE(0), plait_scene_keyframe, transform.scale),
};

#define PLAIT_TABLE(t) t, (int)(sizeof t / sizeof t[0])

static const struct {
	const char *name;
	const plait_scene_key *keys;
	int count;
} plait_contexts[PLAIT_CONTEXT_COUNT] = {
    [PLAIT_CONTEXT_TOP] = {"top level", PLAIT_TABLE(plait_top_keys)},
    [PLAIT_CONTEXT_WORLD] = {"world", PLAIT_TABLE(plait_world_keys)},
    [PLAIT_CONTEXT_WIND] = {"wind", PLAIT_TABLE(plait_wind_keys)},
    [PLAIT_CONTEXT_CLOTH] = {"cloth", PLAIT_TABLE(plait_cloth_keys)},
    [PLAIT_CONTEXT_GRID] = {"grid", PLAIT_TABLE(plait_grid_keys)},
    [PLAIT_CONTEXT_CURVE] = {"curve", PLAIT_TABLE(plait_curve_keys)},
    [PLAIT_CONTEXT_PARTICLES] = {"particles", PLAIT_TABLE(plait_particles_keys)},
    [PLAIT_CONTEXT_COLLIDER] = {"collider", PLAIT_TABLE(plait_collider_keys)},
    [PLAIT_CONTEXT_KEYFRAME] = {"keyframe", PLAIT_TABLE(plait_keyframe_keys)},
};

const plait_scene_key *plait_scene_keys(plait_scene_context context, int *count)
{
	*count = plait_contexts[context].count;
	return plait_contexts[context].keys;
}

const char *plait_scene_context_name(plait_scene_context context)
{
	return plait_contexts[context].name;
}
