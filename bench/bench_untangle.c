/* bench_untangle: how often, how soon and how cleanly cloths begun through one another come
 * apart (dynamics/mesh_contact_untangle.c).
 *
 *   bench_untangle [--starts N] [--frames F] [--only K] [--verbose]
 *
 * Each start drops two or three self-colliding sheets of random sizes (0.4-1 m), resolutions
 * (8-21 quads a side), tilts (slopes up to 0.4) and thicknesses (2-10 mm), placed through one
 * another about 0.3 m over the ground, for F frames (60) at 24 fps and 4 substeps. Per start it
 * prints the crossing triangle pairs at the start, the first frame free of crossings and of
 * tangles found (-1: never), the frames with crossings after it, the tangles found in all, the
 * failsafe's activations over the last ten frames and the largest strain at the end; then how
 * many starts came apart, and how many stayed tangled. Starts are numbered from 0 with fixed
 * seeds, so the same start is the same scene on every machine. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <plait/plait.h>

static float uniform(unsigned *state, float low, float high)
{
	*state = *state * 1664525u + 1013904223u;
	return low + (high - low) * (float)(*state >> 8) / 16777216.0f;
}

/* A sheet of n x n quads, `size` across, its height base + slope_x x + slope_z z, centred at
 * (cx, cz). */
static plait_object_id add_sheet(plait_world_id world, int n, float size, float base, float slope_x,
                                 float slope_z, float cx, float cz, float thickness)
{
	int vertices = (n + 1) * (n + 1);
	plait_vec3 *x = malloc(sizeof *x * (size_t)vertices);
	int *sizes = malloc(sizeof(int) * (size_t)(n * n));
	int *indices = malloc(sizeof(int) * 4 * (size_t)(n * n));
	if (x == NULL || sizes == NULL || indices == NULL) {
		fprintf(stderr, "bench_untangle: out of memory\n");
		exit(1);
	}
	for (int j = 0; j <= n; ++j) {
		for (int i = 0; i <= n; ++i) {
			float u = size * ((float)i / (float)n - 0.5f), w = size * ((float)j / (float)n - 0.5f);
			x[j * (n + 1) + i] = (plait_vec3){cx + u, base + slope_x * u + slope_z * w, cz + w};
		}
	}
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i) {
			int f = j * n + i, a = j * (n + 1) + i;
			sizes[f] = 4;
			int quad[4] = {a, a + n + 1, a + n + 2, a + 1};
			memcpy(indices + 4 * f, quad, sizeof quad);
		}
	}
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = (plait_mesh_def){x, vertices, sizes, n * n, indices};
	def.surface.thickness = thickness;
	def.self_collide = true;
	plait_error error;
	plait_object_id id = plait_create_cloth(world, &def, &error);
	if (plait_object_id_is_null(id)) {
		fprintf(stderr, "bench_untangle: %s\n", error.message);
		exit(1);
	}
	free(x);
	free(sizes);
	free(indices);
	return id;
}

static int crossings(plait_world_id world)
{
	plait_intersection_report report;
	plait_error error;
	if (plait_world_check_intersections(world, &report, &error) != PLAIT_OK) {
		fprintf(stderr, "bench_untangle: %s\n", error.message);
		exit(1);
	}
	return report.triangle_pairs;
}

int main(int argc, char **argv)
{
	int starts = 24, frames = 60, only = -1;
	bool verbose = false;
	for (int a = 1; a < argc; ++a) {
		if (strcmp(argv[a], "--starts") == 0 && a + 1 < argc) {
			starts = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--frames") == 0 && a + 1 < argc) {
			frames = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--only") == 0 && a + 1 < argc) {
			only = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--verbose") == 0) {
			verbose = true;
		} else {
			fprintf(stderr, "usage: bench_untangle [--starts N] [--frames F] [--only K] [--verbose]\n");
			return 2;
		}
	}
	if (starts < 1 || frames < 11) {
		fprintf(stderr, "bench_untangle: --starts takes 1 or more, --frames 11 or more\n");
		return 2;
	}
	int apart = 0, tangled = 0, run = 0;
	for (int s = 0; s < starts; ++s) {
		if (only >= 0 && s != only) {
			continue;
		}
		unsigned state = 1234u + 7919u * (unsigned)s;
		plait_world_def wdef = plait_default_world_def();
		wdef.air_density = 0.0f;
		wdef.substeps = 4;
		plait_world_id world = plait_create_world(&wdef, NULL);
		plait_collider_def ground = plait_default_collider_def();
		if (plait_world_id_is_null(world) ||
		    plait_object_id_is_null(plait_create_collider(world, &ground, NULL))) {
			fprintf(stderr, "bench_untangle: cannot make the world\n");
			return 1;
		}
		int sheets = 2 + s % 2;
		for (int k = 0; k < sheets; ++k) {
			int n = 8 + (int)uniform(&state, 0.0f, 14.0f);
			float size = uniform(&state, 0.4f, 1.0f);
			(void)uniform(&state, 0.05f, 0.6f); /* (a height once drawn: kept for the same starts) */
			float slope_x = uniform(&state, -0.4f, 0.4f), slope_z = uniform(&state, -0.4f, 0.4f);
			float cx = uniform(&state, -0.15f, 0.15f), cz = uniform(&state, -0.15f, 0.15f);
			float base = k == 0 ? 0.3f : 0.3f + uniform(&state, -0.05f, 0.05f);
			add_sheet(world, n, size, base, slope_x, slope_z, cx, cz, uniform(&state, 0.002f, 0.01f));
		}
		int start = crossings(world), clean_at = -1, late = 0, failsafe_end = 0;
		long tangles = 0;
		float strain = 0.0f;
		for (int f = 1; f <= frames; ++f) {
			plait_error error;
			if (plait_world_step(world, &error) != PLAIT_OK) {
				fprintf(stderr, "bench_untangle: start %d frame %d: %s\n", s, f, error.message);
				return 1;
			}
			plait_frame_stats stats = plait_world_get_stats(world);
			int now = crossings(world);
			tangles += stats.tangles;
			if (clean_at < 0 && now == 0 && stats.tangles == 0) {
				clean_at = f;
			} else if (clean_at > 0 && now > 0) {
				late += 1;
			}
			if (f > frames - 10) {
				failsafe_end += stats.failsafe;
			}
			strain = stats.max_strain;
			if (verbose) {
				printf("  start=%d frame=%d crossings=%d tangles=%d failsafe=%d max_strain=%.3f\n", s, f, now,
				       stats.tangles, stats.failsafe, (double)strain);
			}
		}
		run += 1;
		apart += clean_at > 0 && late == 0;
		tangled += clean_at < 0;
		printf("start=%d sheets=%d crossings=%d clean_at=%d late=%d tangles=%ld failsafe_last10=%d "
		       "max_strain=%.3f\n",
		       s, sheets, start, clean_at, late, tangles, failsafe_end, (double)strain);
		plait_destroy_world(world);
	}
	printf("starts=%d apart=%d tangled=%d\n", run, apart, tangled);
	return 0;
}
