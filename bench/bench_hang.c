/* hang-N: the standard cloth benchmark, through the public API.
 *
 * A 2 m x 2 m cloth of N x N vertices, flat in the XZ plane at y = 0 (x, z in [-1, 1]); the two
 * vertices at z = -1, x = +-1 pinned; 1 kg per free vertex; gravity (0, -9.81, 0); a static
 * sphere of radius 0.5 at (0, -0.75, 0); 60 frames per second; 300 frames. Structural, shear
 * (both quad diagonals) and bend constraints, the default substeps (3) and collision
 * iterations (4). The cloth meets the sphere with its vertices (PLAIT_COLLIDE_VERTEX), as the
 * particle-based solvers it is compared with do. Three materials:
 *   default  the default cloth resistances (stretch 20, compression 10, shear 10, bend 0.1),
 *            whose iteration counts follow from them (20 stretch, 10 shear, 3 bend per frame);
 *   rigid    stretch and compression at 10000 (zero compliance) with --iterations (20)
 *            stretch iterations per frame; shear and bend at their defaults (10 shear and 3
 *            bend iterations per frame);
 *   stiff    the constraint set of the cross-solver comparison (issue 4): structural edges,
 *            both quad diagonals and skip-one edges (bend as distances), all rigid, each kind
 *            --iterations times per frame (or once per substep when fewer): 97,026 constraints
 *            at N = 128.
 *
 * Prints one line per run: scene, material, threads, ms/frame (median of the runs), the strain
 * |length / rest - 1| of the structural edges at the last frame (max, p99, mean), and bytes of
 * library memory per vertex. --strain-window W adds a line with the worst max and the worst p99
 * of the strain over the last W frames (measured outside the timed steps): the strain at one
 * frame depends on where the cloth happens to be, a window shows whether a setting holds.
 *
 * --threads LIST (e.g. 1,2,4; default 1) runs every size with each thread count: K > 1 attaches
 * a pool of K workers (tools/plait/thread_pool.h, the calling thread included) to the world's
 * task hooks. It needs the tool layer (plait_toollib); without it only 1 is accepted.
 *
 * --alternate SWITCH (fold, close, columns or wave) times two of the solver's paths that give the same
 * bits side by side in each run, switching between them frame by frame: the host's drift then
 * falls on both alike (separate runs on a shared host swing by 15%; session 19 in
 * docs/performance.md). It reaches into the library's internals (world/world.h) for the switch:
 *   fold     the substeps' closing tethers and collisions folded into the last particle pass, or not;
 *   close    that close on the points as columns, or on the point array;
 *   columns  the distance kernel on the points as columns, or on the point array;
 *   wave     the frame as one wave down the regions (dynamics/wave.h), or pass after pass.
 * Run r takes the path "on" in frames of parity r, so an even number of runs evens out frames
 * that cost more than their neighbours. Adds a line per size and thread count: each path's ms a
 * frame over all runs, and on / off.
 *
 * usage: bench_hang [N ...] [--material default|rigid|stiff|both] [--tethers none|euclidean|geodesic]
 *                   [--runs R] [--frames F] [--iterations I] [--substeps S] [--threads LIST]
 *                   [--simd auto|scalar|avx2|avx512] [--strain-window W] [--alternate
 * fold|close|columns|wave]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <time.h>

#include <plait/plait.h>

#include "world/world.h" /* --alternate only: the solver's switches */

#ifdef PLAIT_BENCH_HAVE_POOL
#include "thread_pool.h"
#else
typedef struct plait_thread_pool plait_thread_pool;
#endif

#define HANG_MAX_THREADS 256
#define HANG_MAX_THREAD_COUNTS 16

typedef struct hang_options {
	int frames, runs, iterations, substeps;
	int strain_window; /* > 0: also the worst strain over the last this many frames */
	int material;      /* 0 default, 1 rigid, 2 stiff */
	plait_simd simd;
	plait_tether_mode tethers;
	plait_thread_pool *pool; /* NULL: one thread */
	int alternate;           /* 0: no; 1 fold, 2 close, 3 columns, 4 wave */
	int parity;              /* frames with frame % 2 == parity take the path "on" */
} hang_options;

static const char *const alternate_names[5] = {"", "fold", "close", "columns", "wave"};

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

typedef struct hang_result {
	double ms_per_frame;
	double strain_max, strain_p99, strain_mean;
	double window_max, window_p99; /* worst max and worst p99 over the strain window */
	size_t bytes_per_vertex;
	int nonfinite;
	double seconds_on, seconds_off; /* --alternate: stepping time of each path */
	int frames_on, frames_off;
} hang_result;

/* Sets the --alternate switch of the world's solver; false when that path cannot be taken
 * (columns without the AVX-512 kernels). */
static bool set_switch(plait_world_id world, int alternate, bool on)
{
	plait_sim *sim = &world.world->sim;
	switch (alternate) {
	case 1:
		sim->fold_closing_passes = on;
		return true;
	case 2:
		sim->close_on_columns = on;
		return true;
	case 3:
		/* The columns are allocated when the blocks are coloured (the first step) and only where
		 * they pay; then they can be left unused for a frame. */
		if (on && sim->columns_capacity < sim->particles.count) {
			return sim->frame == 0;
		}
		sim->use_columns = on;
		return true;
	case 4:
		/* (Whether frames took it is known after them: run_hang.) */
		sim->wave_frames = on;
		return true;
	default:
		return true;
	}
}

/* Atomic in case the library allocates from its worker threads. */
static atomic_size_t allocated_bytes;

static void *counting_alloc(size_t size, size_t alignment, void *context)
{
	(void)context;
	size_t rounded = (size + alignment - 1) / alignment * alignment;
	size_t *block = aligned_alloc(64, rounded + 64);
	if (block == NULL) {
		return NULL;
	}
	block[0] = rounded;
	allocated_bytes += rounded;
	return (char *)block + 64;
}

static void counting_free(void *memory, void *context)
{
	(void)context;
	size_t *block = (size_t *)((char *)memory - 64);
	allocated_bytes -= block[0];
	free(block);
}

/* Strain |length / rest - 1| of the structural edges now: max, p99 and mean into result. */
static void measure_strain(plait_object_id cloth_id, int n, hang_result *result)
{
	int vertex_count = n * n;
	plait_vec3 *x = malloc(sizeof *x * (size_t)vertex_count);
	plait_object_get_positions(cloth_id, 0, vertex_count, x, NULL);
	int edge_count = 2 * n * (n - 1);
	double *strain = malloc(sizeof *strain * (size_t)edge_count);
	int e = 0;
	double rest = 2.0 / (n - 1);
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i) {
			int a = j * n + i;
			if (i + 1 < n) {
				plait_vec3 d = {x[a + 1].x - x[a].x, x[a + 1].y - x[a].y, x[a + 1].z - x[a].z};
				strain[e++] = fabs(sqrt(d.x * d.x + d.y * d.y + d.z * d.z) / rest - 1.0);
			}
			if (j + 1 < n) {
				plait_vec3 d = {x[a + n].x - x[a].x, x[a + n].y - x[a].y, x[a + n].z - x[a].z};
				strain[e++] = fabs(sqrt(d.x * d.x + d.y * d.y + d.z * d.z) / rest - 1.0);
			}
		}
	}
	qsort(strain, (size_t)e, sizeof *strain, compare_doubles);
	double sum = 0.0;
	for (int k = 0; k < e; ++k) {
		sum += strain[k];
		if (!isfinite(strain[k])) {
			result->nonfinite = 1;
		}
	}
	result->strain_max = strain[e - 1];
	result->strain_p99 = strain[(int)(0.99 * (e - 1))];
	result->strain_mean = sum / e;
	free(strain);
	free(x);
}

static hang_result run_hang(int n, const hang_options *options)
{
	hang_result result = {0};
	int vertex_count = n * n;
	plait_vec3 *positions = malloc(sizeof *positions * (size_t)vertex_count);
	float *masses = malloc(sizeof *masses * (size_t)vertex_count);
	int *face_sizes = malloc(sizeof(int) * (size_t)(n - 1) * (size_t)(n - 1));
	int *face_indices = malloc(sizeof(int) * 4 * (size_t)(n - 1) * (size_t)(n - 1));
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i) {
			positions[j * n + i] = (plait_vec3){-1.0f + 2.0f * (float)i / (float)(n - 1), 0.0f,
			                                    -1.0f + 2.0f * (float)j / (float)(n - 1)};
			masses[j * n + i] = 1.0f;
		}
	}
	int faces = 0;
	for (int j = 0; j + 1 < n; ++j) {
		for (int i = 0; i + 1 < n; ++i) {
			int a = j * n + i;
			face_sizes[faces] = 4;
			int *f = face_indices + 4 * faces;
			f[0] = a;
			f[1] = a + n;
			f[2] = a + n + 1;
			f[3] = a + 1;
			++faces;
		}
	}
	int pins[2] = {0, n - 1};

	plait_world_def world_def = plait_default_world_def();
	world_def.fps = 60.0f;
	world_def.air_density = 0.0f;
	world_def.simd = options->simd;
	world_def.alloc = counting_alloc;
	world_def.free = counting_free;
	if (options->substeps > 0) {
		world_def.substeps = options->substeps;
	}
#ifdef PLAIT_BENCH_HAVE_POOL
	plait_thread_pool_attach(options->pool, &world_def);
#endif
	plait_error error;
	allocated_bytes = 0;
	plait_world_id world = plait_create_world(&world_def, &error);
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.name = "hang";
	cloth.mesh = (plait_mesh_def){positions, vertex_count, face_sizes, faces, face_indices};
	cloth.vertex_masses = masses;
	if (options->material == 1) {
		cloth.stretch_resistance = 10000.0f;
		cloth.compression_resistance = 10000.0f;
		cloth.iterations = options->iterations;
	} else if (options->material == 2) {
		cloth.stretch_resistance = cloth.compression_resistance = 10000.0f;
		cloth.shear_resistance = cloth.bend_resistance = 10000.0f;
		cloth.bend_model = PLAIT_BEND_DISTANCE;
		cloth.iterations = cloth.shear_iterations = cloth.bend_iterations = options->iterations;
	}
	cloth.surface.thickness = 0.0f;
	/* Vertices against the sphere, as the other solvers compared collide. */
	cloth.collision_flag = PLAIT_COLLIDE_VERTEX;
	cloth.tethers = options->tethers;
	cloth.pins = pins;
	cloth.pin_count = 2;
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
	if (plait_object_id_is_null(cloth_id) || plait_world_id_is_null(world)) {
		fprintf(stderr, "bench_hang: %s\n", error.message);
		exit(1);
	}
	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.0f, -0.75f, 0.0f};
	sphere.radius = 0.5f;
	plait_create_collider(world, &sphere, &error);

	double stepping_seconds = 0.0;
	for (int frame = 0; frame < options->frames; ++frame) {
		bool on = frame % 2 == options->parity;
		if (options->alternate != 0 && !set_switch(world, options->alternate, on)) {
			fprintf(stderr, "bench_hang: --alternate %s: this run cannot take that path\n",
			        alternate_names[options->alternate]);
			exit(1);
		}
		double start = now_seconds();
		plait_result stepped = plait_world_step(world, &error);
		double seconds = now_seconds() - start;
		stepping_seconds += seconds;
		/* The first frame colours the blocks and builds the tethers' lanes: left out. */
		if (frame > 0 && on) {
			result.seconds_on += seconds;
			result.frames_on += 1;
		} else if (frame > 0) {
			result.seconds_off += seconds;
			result.frames_off += 1;
		}
		if (stepped != PLAIT_OK) {
			fprintf(stderr, "bench_hang: frame %d: %s\n", frame, error.message);
			result.nonfinite = 1;
			break;
		}
		/* Outside the timed part: the strain of each frame of the window. */
		if (frame >= options->frames - options->strain_window) {
			hang_result now = {0};
			measure_strain(cloth_id, n, &now);
			result.window_max = now.strain_max > result.window_max ? now.strain_max : result.window_max;
			result.window_p99 = now.strain_p99 > result.window_p99 ? now.strain_p99 : result.window_p99;
		}
	}
	if (options->alternate == 4 && world.world->sim.waved_frames == 0) {
		fprintf(stderr, "bench_hang: --alternate wave: this run cannot take that path\n");
		exit(1);
	}
	result.ms_per_frame = 1000.0 * stepping_seconds / options->frames;
	result.bytes_per_vertex = allocated_bytes / (size_t)vertex_count;

	measure_strain(cloth_id, n, &result);
	plait_destroy_world(world);
	free(positions);
	free(masses);
	free(face_sizes);
	free(face_indices);
	return result;
}

// Parses a comma list of thread counts ("1,2,4") into counts; returns how many, 0 if malformed.
static int parse_thread_list(const char *text, int *counts, int capacity)
{
	int n = 0;
	const char *p = text;
	for (;;) {
		char *end;
		long k = strtol(p, &end, 10);
		if (end == p || k < 1 || k > HANG_MAX_THREADS || n == capacity || (*end != ',' && *end != '\0')) {
			return 0;
		}
		counts[n++] = (int)k;
		if (*end == '\0') {
			return n;
		}
		p = end + 1;
	}
}

int main(int argc, char **argv)
{
	hang_options options = {
	    .frames = 300, .runs = 3, .iterations = 20, .simd = PLAIT_SIMD_AUTO, .tethers = PLAIT_TETHER_NONE};
	int materials = 2; /* bit 0: default, bit 1: rigid, bit 2: stiff */
	int sizes[16], size_count = 0;
	int thread_counts[HANG_MAX_THREAD_COUNTS] = {1}, thread_count_count = 1;
	for (int a = 1; a < argc; ++a) {
		if (strcmp(argv[a], "--runs") == 0 && a + 1 < argc) {
			options.runs = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--frames") == 0 && a + 1 < argc) {
			options.frames = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--strain-window") == 0 && a + 1 < argc) {
			options.strain_window = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--iterations") == 0 && a + 1 < argc) {
			options.iterations = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--material") == 0 && a + 1 < argc) {
			++a;
			materials = strcmp(argv[a], "default") == 0 ? 1
			            : strcmp(argv[a], "both") == 0  ? 3
			            : strcmp(argv[a], "stiff") == 0 ? 4
			                                            : 2;
		} else if (strcmp(argv[a], "--simd") == 0 && a + 1 < argc) {
			++a;
			options.simd = strcmp(argv[a], "scalar") == 0   ? PLAIT_SIMD_SCALAR
			               : strcmp(argv[a], "avx2") == 0   ? PLAIT_SIMD_AVX2
			               : strcmp(argv[a], "avx512") == 0 ? PLAIT_SIMD_AVX512
			                                                : PLAIT_SIMD_AUTO;
		} else if (strcmp(argv[a], "--tethers") == 0 && a + 1 < argc) {
			++a;
			options.tethers = strcmp(argv[a], "geodesic") == 0    ? PLAIT_TETHER_GEODESIC
			                  : strcmp(argv[a], "euclidean") == 0 ? PLAIT_TETHER_EUCLIDEAN
			                                                      : PLAIT_TETHER_NONE;
		} else if (strcmp(argv[a], "--alternate") == 0 && a + 1 < argc) {
			++a;
			options.alternate = 0;
			for (int k = 1; k < 5; ++k) {
				options.alternate = strcmp(argv[a], alternate_names[k]) == 0 ? k : options.alternate;
			}
			if (options.alternate == 0) {
				fprintf(stderr, "bench_hang: --alternate expects fold, close, columns or wave, got '%s'\n",
				        argv[a]);
				return 2;
			}
		} else if (strcmp(argv[a], "--substeps") == 0 && a + 1 < argc) {
			options.substeps = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--threads") == 0 && a + 1 < argc) {
			++a;
			thread_count_count = parse_thread_list(argv[a], thread_counts, HANG_MAX_THREAD_COUNTS);
			if (thread_count_count == 0) {
				fprintf(stderr,
				        "bench_hang: --threads expects a comma list of up to %d counts from 1 to %d, got "
				        "'%s'\n",
				        HANG_MAX_THREAD_COUNTS, HANG_MAX_THREADS, argv[a]);
				return 2;
			}
		} else if (size_count < 16 && atoi(argv[a]) > 1) {
			sizes[size_count++] = atoi(argv[a]);
		} else {
			fprintf(stderr,
			        "usage: bench_hang [N ...] [--material default|rigid|stiff|both] [--tethers "
			        "none|euclidean|geodesic] [--runs R] [--frames F] [--iterations I] [--substeps S] "
			        "[--threads LIST] [--simd auto|scalar|avx2|avx512] [--strain-window W] [--alternate "
			        "fold|close|columns]\n");
			return 2;
		}
	}
	if (size_count == 0) {
		sizes[size_count++] = 64;
		sizes[size_count++] = 128;
	}
	if (options.runs < 1 || options.frames < 1) {
		fprintf(stderr, "bench_hang: runs and frames must be >= 1\n");
		return 2;
	}
#ifndef PLAIT_BENCH_HAVE_POOL
	for (int t = 0; t < thread_count_count; ++t) {
		if (thread_counts[t] > 1) {
			fprintf(stderr,
			        "bench_hang: built without the tool layer (plait_toollib): --threads can only be 1\n");
			return 2;
		}
	}
#endif
	for (int m = 0; m < 3; ++m) {
		if (!(materials & (1 << m))) {
			continue;
		}
		options.material = m;
		for (int s = 0; s < size_count; ++s) {
			for (int t = 0; t < thread_count_count; ++t) {
				int threads = thread_counts[t];
				options.pool = NULL;
#ifdef PLAIT_BENCH_HAVE_POOL
				if (threads > 1) {
					options.pool = plait_thread_pool_create(threads);
					if (options.pool == NULL) {
						fprintf(stderr, "bench_hang: cannot start %d threads\n", threads - 1);
						return 1;
					}
				}
#endif
				double times[64];
				hang_result last = {0};
				double seconds_on = 0.0, seconds_off = 0.0;
				int frames_on = 0, frames_off = 0;
				int runs = options.runs > 64 ? 64 : options.runs;
				for (int r = 0; r < runs; ++r) {
					options.parity = r % 2;
					last = run_hang(sizes[s], &options);
					times[r] = last.ms_per_frame;
					seconds_on += last.seconds_on;
					seconds_off += last.seconds_off;
					frames_on += last.frames_on;
					frames_off += last.frames_off;
				}
#ifdef PLAIT_BENCH_HAVE_POOL
				plait_thread_pool_destroy(options.pool);
				options.pool = NULL;
#endif
				qsort(times, (size_t)runs, sizeof times[0], compare_doubles);
				const char *tether_names[3] = {"none", "euclidean", "geodesic"};
				const char *material_names[3] = {"default", "rigid", "stiff"};
				printf(
				    "scene=hang-%d material=%s tethers=%s substeps=%d threads=%d frames=%d "
				    "ms_per_frame=%.3f strain_max=%.4f strain_p99=%.4f strain_mean=%.5f bytes_per_vertex=%zu "
				    "nonfinite=%d\n",
				    sizes[s], material_names[options.material], tether_names[options.tethers],
				    options.substeps > 0 ? options.substeps : plait_default_world_def().substeps, threads,
				    options.frames, times[runs / 2], last.strain_max, last.strain_p99, last.strain_mean,
				    last.bytes_per_vertex, last.nonfinite);
				if (options.alternate != 0 && frames_on > 0 && frames_off > 0) {
					double on = 1000.0 * seconds_on / frames_on, off = 1000.0 * seconds_off / frames_off;
					printf("scene=hang-%d threads=%d alternate=%s ms_on=%.3f ms_off=%.3f on_over_off=%.4f\n",
					       sizes[s], threads, alternate_names[options.alternate], on, off, on / off);
				}
				if (options.strain_window > 0) {
					printf("scene=hang-%d strain_window=%d window_max=%.4f window_p99=%.4f\n", sizes[s],
					       options.strain_window, last.window_max, last.window_p99);
				}
				fflush(stdout);
			}
		}
	}
	return 0;
}
