/* pile: 100,000 particles falling into a box, through the public API.
 *
 * Particles of radius 5 mm start on a jittered 50 x 40 x 50 lattice (spacing 12 mm) above a
 * 1 m x 1 m box made of five planes (a floor and four walls), and fall for 120 frames at 24 fps
 * with default settings (3 substeps, 4 collision iterations), colliding with each other through
 * the spatial hash and with the walls.
 *
 * Prints: scene, particles, ms/frame (median of the runs), contacts in the last frame, the
 * highest particle at the end, and penetrations into the walls.
 *
 * usage: bench_pile [--runs R] [--frames F] [--count N]
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <plait/plait.h>

static double now_seconds(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int compare_doubles(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return x < y ? -1 : x > y;
}

static void add_plane(plait_world_id world, plait_vec3 point, plait_vec3 normal)
{
	plait_collider_def def = plait_default_collider_def();
	def.shape = PLAIT_SHAPE_PLANE;
	def.point = point;
	def.normal = normal;
	def.surface.friction = 0.3f;
	plait_error error;
	if (plait_object_id_is_null(plait_create_collider(world, &def, &error))) {
		fprintf(stderr, "bench_pile: %s\n", error.message);
		exit(1);
	}
}

int main(int argc, char **argv)
{
	int runs = 3, frames = 120, count = 100000;
	for (int a = 1; a < argc; ++a) {
		if (strcmp(argv[a], "--runs") == 0 && a + 1 < argc) {
			runs = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--frames") == 0 && a + 1 < argc) {
			frames = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--count") == 0 && a + 1 < argc) {
			count = atoi(argv[++a]);
		} else {
			fprintf(stderr, "usage: bench_pile [--runs R] [--frames F] [--count N]\n");
			return 2;
		}
	}
	if (runs < 1 || runs > 64 || frames < 1 || count < 1 || count > 100000) {
		fprintf(stderr, "bench_pile: runs 1..64, frames >= 1, count 1..100000\n");
		return 2;
	}
	plait_vec3 *positions = malloc(sizeof *positions * (size_t)count);
	unsigned seed = 1u;
	for (int k = 0; k < count; ++k) {
		int i = k % 50, j = (k / 50) % 50, layer = k / 2500;
		seed = seed * 1664525u + 1013904223u;
		float jitter = 0.001f * (float)(seed >> 24) / 255.0f;
		positions[k] = (plait_vec3){-0.3f + 0.012f * (float)i + jitter, 0.05f + 0.012f * (float)layer,
		                            -0.3f + 0.012f * (float)j - jitter};
	}
	double times[64];
	int last_contacts = 0, penetrations = 0;
	float highest = 0.0f;
	for (int r = 0; r < runs; ++r) {
		plait_world_def def = plait_default_world_def();
		def.air_density = 0.0f;
		plait_error error;
		plait_world_id world = plait_create_world(&def, &error);
		add_plane(world, (plait_vec3){0, 0, 0}, (plait_vec3){0, 1, 0});
		add_plane(world, (plait_vec3){-0.5f, 0, 0}, (plait_vec3){1, 0, 0});
		add_plane(world, (plait_vec3){0.5f, 0, 0}, (plait_vec3){-1, 0, 0});
		add_plane(world, (plait_vec3){0, 0, -0.5f}, (plait_vec3){0, 0, 1});
		add_plane(world, (plait_vec3){0, 0, 0.5f}, (plait_vec3){0, 0, -1});
		plait_particles_def particles = plait_default_particles_def();
		particles.positions = positions;
		particles.count = count;
		particles.radius = 0.005f;
		particles.mass = 0.001f;
		particles.surface.friction = 0.3f;
		plait_object_id pile = plait_create_particles(world, &particles, &error);
		if (plait_object_id_is_null(pile)) {
			fprintf(stderr, "bench_pile: %s\n", error.message);
			return 1;
		}
		double start = now_seconds();
		for (int f = 0; f < frames; ++f) {
			if (plait_world_step(world, &error) != PLAIT_OK) {
				fprintf(stderr, "bench_pile: frame %d: %s\n", f, error.message);
				return 1;
			}
		}
		times[r] = 1000.0 * (now_seconds() - start) / frames;
		plait_frame_stats stats = plait_world_get_stats(world);
		last_contacts = stats.contacts;
		penetrations = stats.penetrations;
		plait_vec3 *x = malloc(sizeof *x * (size_t)count);
		plait_object_get_positions(pile, 0, count, x, NULL);
		highest = 0.0f;
		for (int k = 0; k < count; ++k) {
			highest = x[k].y > highest ? x[k].y : highest;
		}
		free(x);
		plait_destroy_world(world);
	}
	qsort(times, (size_t)runs, sizeof times[0], compare_doubles);
	printf("scene=pile particles=%d threads=1 frames=%d ms_per_frame=%.3f contacts=%d highest_m=%.3f "
	       "penetrations=%d\n",
	       count, frames, times[runs / 2], last_contacts, (double)highest, penetrations);
	free(positions);
	return 0;
}
