/* The distance kernel alone, per instruction set: ns per constraint projection over the
 * stretch, shear and bend-distance blocks of an N x N cloth (the hang-N constraint set), and
 * a check that every level gives the same bits as the portable one.
 *
 * usage: bench_kernels [N] [--sweeps S] [--simd scalar|avx2|avx512]     (N = 128, S = 200)
 * prints one line per level: simd=... ns_per_projection=... identical=yes|no */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <plait/plait.h>

#include "dynamics/colouring.h"
#include "dynamics/constraints.h"
#include "world/world.h"

static double now_seconds(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static plait_world_id make_cloth_world(int n, plait_simd simd)
{
	plait_world_def wdef = plait_default_world_def();
	wdef.simd = simd;
	plait_world_id world = plait_create_world(&wdef, NULL);
	int vertex_count = n * n, quads = (n - 1) * (n - 1);
	plait_vec3 *x = malloc(sizeof *x * (size_t)vertex_count);
	int *sizes = malloc(sizeof(int) * (size_t)quads), *indices = malloc(sizeof(int) * 4 * (size_t)quads);
	for (int j = 0; j < n; ++j) {
		for (int i = 0; i < n; ++i) {
			x[j * n + i] = (plait_vec3){-1.0f + 2.0f * (float)i / (float)(n - 1), 0.0f,
			                            -1.0f + 2.0f * (float)j / (float)(n - 1)};
		}
	}
	for (int f = 0, j = 0; j + 1 < n; ++j) {
		for (int i = 0; i + 1 < n; ++i, ++f) {
			int a = j * n + i;
			sizes[f] = 4;
			int q[4] = {a, a + 1, a + n + 1, a + n};
			memcpy(indices + 4 * f, q, sizeof q);
		}
	}
	int pins[2] = {0, n - 1};
	plait_cloth_def def = plait_default_cloth_def();
	def.mesh = (plait_mesh_def){x, vertex_count, sizes, quads, indices};
	def.stretch_resistance = def.compression_resistance = def.shear_resistance = 10000.0f;
	def.bend_resistance = 10000.0f;
	def.bend_model = PLAIT_BEND_DISTANCE;
	def.pins = pins;
	def.pin_count = 2;
	plait_create_cloth(world, &def, NULL);
	free(x);
	free(sizes);
	free(indices);
	plait_sim_colour(&world.world->sim);
	return world;
}

int main(int argc, char **argv)
{
	int n = 128, sweeps = 200;
	const char *only = NULL;
	for (int k = 1; k < argc; ++k) {
		if (strcmp(argv[k], "--sweeps") == 0 && k + 1 < argc) {
			sweeps = atoi(argv[++k]);
		} else if (strcmp(argv[k], "--simd") == 0 && k + 1 < argc) {
			only = argv[++k];
		} else {
			n = atoi(argv[k]);
		}
	}
	/* "columns": the AVX-512 column kernel on the points as columns (copied there before the
	 * sweeps and back after them, outside the timing), where the cloth's segments allow it. */
	plait_simd levels[] = {PLAIT_SIMD_SCALAR, PLAIT_SIMD_AVX2, PLAIT_SIMD_AVX512, PLAIT_SIMD_AVX512};
	const char *names[] = {"scalar", "avx2", "avx512", "columns"};
	plait_point *reference = NULL;
	int particle_count = 0;
	for (int l = 0; l < 4; ++l) {
		if (only != NULL && strcmp(only, names[l]) != 0) {
			continue;
		}
		if (!plait_simd_is_supported(levels[l])) {
			printf("simd=%s supported=no\n", names[l]);
			continue;
		}
		plait_world_id world = make_cloth_world(n, levels[l]);
		plait_sim *sim = &world.world->sim;
		plait_particles *p = &sim->particles;
		/* Disturb the sheet so that every constraint has work to do. */
		for (int i = 0; i < p->count; ++i) {
			p->point[i].x.y += 0.01f * (float)((i * 7919) % 13) / 13.0f;
		}
		plait_distance_block *blocks[] = {&sim->stretch, &sim->shear, &sim->bend_distance};
		plait_columns columns = {sim->column_x, sim->column_y, sim->column_z, sim->column_w,
		                         sim->column_ops.project};
		bool on_columns = l >= 3;
		if (on_columns && !sim->use_columns) {
			printf("simd=%s n=%d used=no\n", names[l], n);
			plait_destroy_world(world);
			continue;
		}
		if (on_columns) {
			sim->column_ops.to_columns(p->point, &columns, 0, p->count);
		}
		long projections = 0;
		double start = now_seconds();
		for (int s = 0; s < sweeps; ++s) {
			for (int b = 0; b < 3; ++b) {
				plait_solve_distance(blocks[b], p, on_columns ? &columns : NULL, 3600.0f, PLAIT_SWEEP_FORWARD,
				                     sim->distance_kernel, &sim->parallel);
				projections += blocks[b]->count;
			}
		}
		double seconds = now_seconds() - start;
		if (on_columns) {
			sim->column_ops.from_columns(p->point, &columns, 0, p->count);
		}
		bool identical = true;
		if (reference == NULL) {
			particle_count = p->count;
			reference = malloc(sizeof *reference * (size_t)particle_count);
			memcpy(reference, p->point, sizeof *reference * (size_t)particle_count);
		} else {
			identical = memcmp(reference, p->point, sizeof *reference * (size_t)particle_count) == 0;
		}
		printf("simd=%s n=%d constraints=%d sweeps=%d ns_per_projection=%.3f identical=%s\n", names[l], n,
		       sim->stretch.count + sim->shear.count + sim->bend_distance.count, sweeps,
		       1e9 * seconds / (double)projections, identical ? "yes" : "no");
		plait_destroy_world(world);
	}
	free(reference);
	return 0;
}
