/* hang-N: the standard cloth benchmark, through the public API.
 *
 * A 2 m x 2 m cloth of N x N vertices, flat in the XZ plane at y = 0 (x, z in [-1, 1]); the two
 * vertices at z = -1, x = +-1 pinned; 1 kg per free vertex; gravity (0, -9.81, 0); a static
 * sphere of radius 0.5 at (0, -0.75, 0); 60 frames per second; 300 frames. Structural, shear
 * (both quad diagonals) and bend constraints, the default substeps (3) and collision
 * iterations (4). Two materials:
 *   default  the default cloth resistances (stretch 20, compression 10, shear 10, bend 0.1),
 *            whose iteration counts follow from them (20 stretch, 10 shear, 3 bend per frame);
 *   rigid    stretch and compression at 10000 (zero compliance) with --iterations (20)
 *            stretch iterations per frame; shear and bend at their defaults (10 shear and 3
 *            bend iterations per frame).
 *
 * Prints one line per run: scene, material, threads, ms/frame (median of the runs), the strain
 * |length / rest - 1| of the structural edges at the last frame (max, p99, mean), and bytes of
 * library memory per vertex.
 *
 * usage: bench_hang [N ...] [--material default|rigid|both] [--tethers none|euclidean|geodesic]
 *                   [--runs R] [--frames F] [--iterations I] [--substeps S]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdbool.h>
#include <time.h>

#include <plait/plait.h>

typedef struct hang_options {
	int frames, runs, iterations, substeps;
	bool rigid;
	plait_tether_mode tethers;
} hang_options;

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
	size_t bytes_per_vertex;
	int nonfinite;
} hang_result;

static size_t allocated_bytes;

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
	world_def.alloc = counting_alloc;
	world_def.free = counting_free;
	if (options->substeps > 0) {
		world_def.substeps = options->substeps;
	}
	plait_error error;
	allocated_bytes = 0;
	plait_world_id world = plait_create_world(&world_def, &error);
	plait_cloth_def cloth = plait_default_cloth_def();
	cloth.name = "hang";
	cloth.mesh = (plait_mesh_def){positions, vertex_count, face_sizes, faces, face_indices};
	cloth.vertex_masses = masses;
	if (options->rigid) {
		cloth.stretch_resistance = 10000.0f;
		cloth.compression_resistance = 10000.0f;
		cloth.iterations = options->iterations;
	}
	cloth.surface.thickness = 0.0f;
	cloth.tethers = options->tethers;
	cloth.pins = pins;
	cloth.pin_count = 2;
	plait_object_id cloth_id = plait_create_cloth(world, &cloth, &error);
	if (plait_object_id_is_null(cloth_id)) {
		fprintf(stderr, "bench_hang: %s\n", error.message);
		exit(1);
	}
	plait_collider_def sphere = plait_default_collider_def();
	sphere.shape = PLAIT_SHAPE_SPHERE;
	sphere.center = (plait_vec3){0.0f, -0.75f, 0.0f};
	sphere.radius = 0.5f;
	plait_create_collider(world, &sphere, &error);

	double start = now_seconds();
	for (int frame = 0; frame < options->frames; ++frame) {
		if (plait_world_step(world, &error) != PLAIT_OK) {
			fprintf(stderr, "bench_hang: frame %d: %s\n", frame, error.message);
			result.nonfinite = 1;
			break;
		}
	}
	result.ms_per_frame = 1000.0 * (now_seconds() - start) / options->frames;
	result.bytes_per_vertex = allocated_bytes / (size_t)vertex_count;

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
			result.nonfinite = 1;
		}
	}
	result.strain_max = strain[e - 1];
	result.strain_p99 = strain[(int)(0.99 * (e - 1))];
	result.strain_mean = sum / e;
	free(strain);
	free(x);
	plait_destroy_world(world);
	free(positions);
	free(masses);
	free(face_sizes);
	free(face_indices);
	return result;
}

int main(int argc, char **argv)
{
	hang_options options = {300, 3, 20, 0, false, PLAIT_TETHER_NONE};
	int materials = 2; /* bit 0: default, bit 1: rigid */
	int sizes[16], size_count = 0;
	for (int a = 1; a < argc; ++a) {
		if (strcmp(argv[a], "--runs") == 0 && a + 1 < argc) {
			options.runs = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--frames") == 0 && a + 1 < argc) {
			options.frames = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--iterations") == 0 && a + 1 < argc) {
			options.iterations = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--material") == 0 && a + 1 < argc) {
			++a;
			materials = strcmp(argv[a], "default") == 0 ? 1 : strcmp(argv[a], "both") == 0 ? 3 : 2;
		} else if (strcmp(argv[a], "--tethers") == 0 && a + 1 < argc) {
			++a;
			options.tethers = strcmp(argv[a], "geodesic") == 0    ? PLAIT_TETHER_GEODESIC
			                  : strcmp(argv[a], "euclidean") == 0 ? PLAIT_TETHER_EUCLIDEAN
			                                                      : PLAIT_TETHER_NONE;
		} else if (strcmp(argv[a], "--substeps") == 0 && a + 1 < argc) {
			options.substeps = atoi(argv[++a]);
		} else if (size_count < 16 && atoi(argv[a]) > 1) {
			sizes[size_count++] = atoi(argv[a]);
		} else {
			fprintf(stderr,
			        "usage: bench_hang [N ...] [--material default|rigid|both] [--tethers "
			        "none|euclidean|geodesic] [--runs R] [--frames F] [--iterations I] [--substeps S]\n");
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
	for (int m = 0; m < 2; ++m) {
		if (!(materials & (1 << m))) {
			continue;
		}
		options.rigid = m == 1;
		for (int s = 0; s < size_count; ++s) {
			double times[64];
			hang_result last = {0};
			int runs = options.runs > 64 ? 64 : options.runs;
			for (int r = 0; r < runs; ++r) {
				last = run_hang(sizes[s], &options);
				times[r] = last.ms_per_frame;
			}
			qsort(times, (size_t)runs, sizeof times[0], compare_doubles);
			const char *tether_names[3] = {"none", "euclidean", "geodesic"};
			printf(
			    "scene=hang-%d material=%s tethers=%s threads=1 frames=%d ms_per_frame=%.3f strain_max=%.4f "
			    "strain_p99=%.4f strain_mean=%.5f bytes_per_vertex=%zu nonfinite=%d\n",
			    sizes[s], options.rigid ? "rigid" : "default", tether_names[options.tethers], options.frames,
			    times[runs / 2], last.strain_max, last.strain_p99, last.strain_mean, last.bytes_per_vertex,
			    last.nonfinite);
			fflush(stdout);
		}
	}
	return 0;
}
