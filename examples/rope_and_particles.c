/* rope_and_particles: a rope hanging from a pin that is dragged along a keyframed path, a handful
 * of particles raining onto it, and a capsule that sweeps through the scene. Shows the calls that
 * drive a simulation from outside between frames: plait_object_set_pin_target and
 * plait_collider_set_transform. Prints a few statistics every half second. */
#include <math.h>
#include <stdio.h>

#include <plait/plait.h>

#define ROPE_VERTICES 30
#define PARTICLES 40
#define FRAMES 96

typedef struct key {
	int frame;
	plait_vec3 value;
} key;

/* The pin's path: along +x, then toward +z, then back, reached at these frames. */
static const key pin_path[] = {{0, {0.0f, 2.0f, 0.0f}},
                               {24, {0.6f, 2.0f, 0.0f}},
                               {60, {0.6f, 2.2f, 0.6f}},
                               {FRAMES, {0.0f, 2.0f, 0.0f}}};

/* Piecewise-linear interpolation of the path at a frame; held before the first and after the last key. */
static plait_vec3 path_at(const key *keys, int count, int frame)
{
	if (frame <= keys[0].frame) {
		return keys[0].value;
	}
	for (int k = 1; k < count; ++k) {
		if (frame <= keys[k].frame) {
			float t = (float)(frame - keys[k - 1].frame) / (float)(keys[k].frame - keys[k - 1].frame);
			plait_vec3 a = keys[k - 1].value, b = keys[k].value;
			return (plait_vec3){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)};
		}
	}
	return keys[count - 1].value;
}

static int fail(const char *what, const plait_error *error)
{
	fprintf(stderr, "rope_and_particles: %s: %s: %s\n", what, plait_result_name(error->code), error->message);
	return 1;
}

int main(void)
{
	plait_error error;
	plait_world_def world_def = plait_default_world_def();
	world_def.substeps = 6; /* a light rope hit by heavier particles: more substeps keep it taut */
	plait_world_id world = plait_create_world(&world_def, &error);
	if (plait_world_id_is_null(world)) {
		return fail("world", &error);
	}

	/* A 1.5 m rope along +x at height 2, pinned at vertex 0. */
	plait_vec3 rope_points[ROPE_VERTICES];
	for (int i = 0; i < ROPE_VERTICES; ++i) {
		rope_points[i] = (plait_vec3){1.5f * (float)i / (ROPE_VERTICES - 1), 2.0f, 0.0f};
	}
	const int pins[] = {0};
	plait_curve_def rope_def = plait_default_curve_def();
	rope_def.name = "rope";
	rope_def.positions = rope_points;
	rope_def.vertex_count = ROPE_VERTICES;
	rope_def.mass = 0.02f;
	rope_def.stretch_resistance = 200.0f;
	rope_def.bend_resistance = 0.5f;
	rope_def.surface.thickness = 0.02f;
	rope_def.pins = pins;
	rope_def.pin_count = 1;
	plait_object_id rope = plait_create_curve(world, &rope_def, &error);
	if (plait_object_id_is_null(rope)) {
		return fail("rope", &error);
	}

	/* Light particles in a loose grid just above the rope, thrown down so they catch it as it swings. */
	plait_vec3 drops[PARTICLES], down[PARTICLES];
	for (int i = 0; i < PARTICLES; ++i) {
		drops[i] = (plait_vec3){0.1f + 0.12f * (float)(i % 10), 2.3f + 0.15f * (float)(i / 10),
		                        0.05f * (float)(i % 3) - 0.05f};
		down[i] = (plait_vec3){0.0f, -2.0f, 0.0f};
	}
	plait_particles_def drops_def = plait_default_particles_def();
	drops_def.name = "drops";
	drops_def.positions = drops;
	drops_def.count = PARTICLES;
	drops_def.velocities = down;
	drops_def.mass = 0.005f;
	drops_def.radius = 0.03f;
	plait_object_id particles = plait_create_particles(world, &drops_def, &error);
	if (plait_object_id_is_null(particles)) {
		return fail("particles", &error);
	}

	/* A horizontal capsule across the scene and the ground plane. */
	plait_collider_def bar_def = plait_default_collider_def();
	bar_def.name = "bar";
	bar_def.shape = PLAIT_SHAPE_CAPSULE;
	bar_def.a = (plait_vec3){0.8f, 1.0f, -0.5f};
	bar_def.b = (plait_vec3){0.8f, 1.0f, 0.5f};
	bar_def.radius = 0.15f;
	bar_def.surface.friction = 0.4f;
	plait_object_id bar = plait_create_collider(world, &bar_def, &error);
	plait_collider_def ground_def = plait_default_collider_def();
	ground_def.name = "ground";
	if (plait_object_id_is_null(bar) ||
	    plait_object_id_is_null(plait_create_collider(world, &ground_def, &error))) {
		return fail("colliders", &error);
	}

	int most_contacts = 0;
	for (int frame = 1; frame <= FRAMES; ++frame) {
		/* Targets are those reached at the end of the coming frame; the solver interpolates. */
		plait_vec3 pin = path_at(pin_path, (int)(sizeof pin_path / sizeof pin_path[0]), frame);
		if (plait_object_set_pin_target(rope, 0, pin, &error) != PLAIT_OK) {
			return fail("pin target", &error);
		}
		plait_transform swing = plait_identity_transform();
		swing.translate.x = -0.6f * sinf(6.2831853f * (float)frame / FRAMES); /* once back and forth */
		swing.rotate_deg.y = 30.0f * (float)frame / FRAMES;
		if (plait_collider_set_transform(bar, swing, &error) != PLAIT_OK) {
			return fail("bar transform", &error);
		}
		if (plait_world_step(world, &error) != PLAIT_OK) {
			return fail("step", &error);
		}

		plait_frame_stats stats = plait_world_get_stats(world);
		most_contacts = stats.contacts > most_contacts ? stats.contacts : most_contacts;
		if (frame % 12 == 0) {
			plait_vec3 tip;
			if (plait_object_get_positions(rope, ROPE_VERTICES - 1, 1, &tip, &error) != PLAIT_OK) {
				return fail("rope positions", &error);
			}
			printf(
			    "frame %3d  pin (%5.2f %5.2f %5.2f)  rope tip (%5.2f %5.2f %5.2f)  kinetic energy %7.4f J  "
			    "max strain %.4f  contacts %3d\n",
			    frame, pin.x, pin.y, pin.z, tip.x, tip.y, tip.z, stats.kinetic_energy, stats.max_strain,
			    stats.contacts);
		}
	}

	/* Where things ended up: the pinned vertex should sit exactly on its last target. */
	plait_vec3 pinned, p[PARTICLES];
	if (plait_object_get_positions(rope, 0, 1, &pinned, &error) != PLAIT_OK ||
	    plait_object_get_positions(particles, 0, PARTICLES, p, &error) != PLAIT_OK) {
		return fail("positions", &error);
	}
	plait_vec3 target = pin_path[sizeof pin_path / sizeof pin_path[0] - 1].value;
	float highest = p[0].y, lowest = p[0].y;
	for (int i = 1; i < PARTICLES; ++i) {
		highest = p[i].y > highest ? p[i].y : highest;
		lowest = p[i].y < lowest ? p[i].y : lowest;
	}
	printf(
	    "pinned vertex %.2g m from its target; drops between %.3f and %.3f m high; at most %d contacts in a "
	    "frame\n",
	    sqrtf((pinned.x - target.x) * (pinned.x - target.x) + (pinned.y - target.y) * (pinned.y - target.y) +
	          (pinned.z - target.z) * (pinned.z - target.z)),
	    lowest, highest, most_contacts);
	plait_destroy_world(world);
	return 0;
}
