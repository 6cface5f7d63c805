/* The mesh collider's queries alone (collision/mesh_shape.h): ns per signed distance and per
 * box query (plait_mesh_shape_any) against a sphere mesh of radius 0.5 m, for points within a
 * shell about its surface, as the collider pass asks them: in the order of a cloth lying over
 * the sphere (neighbours one after another) or in a random order.
 *
 * With --reaches, the set-up of a rigid mesh collider instead: ms for the smooth reaches of
 * the sphere's corners and edges (collision/smooth_reach.h) on one thread, as bench_collide
 * hang-self asks them at its first step (budget 3.46 mm, range 48 mm), a hash of them, and the
 * share of edges whose reach runs the whole range. --bumps A ripples the sphere's radius by
 * A m; --radius R (0.5 m) makes it smaller: a mesh curved at the cloth's scale, as a body's
 * limbs are.
 *
 * usage: bench_mesh_queries [--bands B] [--shell S] [--random] [--rounds R]
 *                           [--reaches [--bumps A] [--radius R]]
 *        (B = 50 latitude bands and as many longitudes, about 4,900 triangles; S = 0.01 m;
 *         R = 5 passes over 40,000 points)
 * prints: triangles=... distance_ns=... any_ns=... (and checksums, to compare builds), or
 *         triangles=... reaches_ms=... full_edges=... reaches=HASH */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <plait/plait.h>

#include "collision/mesh_shape.h"
#include "collision/smooth_reach.h"

static double now_seconds(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A uniform number in [0, 1) from a 32-bit state (the same points in every build). */
static float next_unit(unsigned *state)
{
	*state = *state * 1664525u + 1013904223u;
	return (float)(*state >> 8) / 16777216.0f;
}

/* The sphere of bench_collide hang-self: `bands` latitude bands and as many longitudes, fans
 * at the poles. */
static plait_mesh_shape make_sphere(int bands, float r, float bumps, const plait_allocator *heap)
{
	const float pi = 3.14159265f;
	int vertex_count = 2 + bands * (bands - 1);
	plait_vec3 *x = malloc(sizeof *x * (size_t)vertex_count);
	int *sizes = malloc(sizeof(int) * (size_t)(bands * bands));
	int *indices = malloc(sizeof(int) * 4 * (size_t)(bands * bands));
	x[0] = (plait_vec3){0.0f, r, 0.0f};
	x[1] = (plait_vec3){0.0f, -r, 0.0f};
	for (int j = 1; j < bands; ++j) {
		float polar = pi * (float)j / (float)bands;
		for (int i = 0; i < bands; ++i) {
			float a = 2.0f * pi * (float)i / (float)bands;
			float radius = r + bumps * sinf(7.0f * a) * sinf(5.0f * polar);
			x[2 + (j - 1) * bands + i] = (plait_vec3){radius * sinf(polar) * cosf(a), radius * cosf(polar),
			                                          radius * sinf(polar) * sinf(a)};
		}
	}
	int faces = 0, at = 0;
	for (int i = 0; i < bands; ++i) {
		int next = (i + 1) % bands, last = 2 + (bands - 2) * bands;
		int top[3] = {0, 2 + next, 2 + i}, bottom[3] = {1, last + i, last + next};
		sizes[faces++] = 3;
		memcpy(indices + at, top, sizeof top);
		at += 3;
		for (int j = 1; j + 1 < bands; ++j) {
			int a = 2 + (j - 1) * bands;
			int quad[4] = {a + i, a + next, a + bands + next, a + bands + i};
			sizes[faces++] = 4;
			memcpy(indices + at, quad, sizeof quad);
			at += 4;
		}
		sizes[faces++] = 3;
		memcpy(indices + at, bottom, sizeof bottom);
		at += 3;
	}
	plait_mesh_def def = {x, vertex_count, sizes, faces, indices};
	plait_mesh_shape shape;
	plait_error error;
	if (plait_mesh_shape_build(&shape, heap, &def, &error) != PLAIT_OK) {
		fprintf(stderr, "bench_mesh_queries: %s\n", error.message);
		exit(1);
	}
	free(x);
	free(sizes);
	free(indices);
	return shape;
}

/* The smooth reaches of the shape's features, timed: ms, a hash of their bits (the same
 * reaches from two builds: the same hash) and the share of edges reaching the whole range. */
static int bench_reaches(const plait_mesh_shape *shape, const plait_allocator *heap)
{
	const float budget = 0.0034641f, range = 0.0480073f; /* hang-self 128's first step */
	int nv = shape->vertex_count, ne = 3 * shape->triangle_count;
	float *vertex = malloc(sizeof(float) * (size_t)nv), *edge = malloc(sizeof(float) * (size_t)ne);
	double start = now_seconds();
	if (!plait_mesh_smooth_reaches(shape, heap, NULL, budget, range, vertex, edge)) {
		fprintf(stderr, "bench_mesh_queries: out of memory\n");
		return 1;
	}
	double ms = 1e3 * (now_seconds() - start);
	uint64_t hash = 1469598103934665603ull;
	int full = 0;
	double sum = 0.0;
	for (int e = 0; e < ne; ++e) {
		sum += edge[e] > 0.0f ? edge[e] : 0.0f;
	}
	for (int k = 0; k < nv + ne; ++k) {
		float r = k < nv ? vertex[k] : edge[k - nv];
		uint32_t bits;
		memcpy(&bits, &r, sizeof bits);
		hash = (hash ^ bits) * 1099511628211ull;
		full += k >= nv && r >= 0.999f * (range - budget);
	}
	printf("triangles=%d reaches_ms=%.1f full_edges=%.3f mean_edge_mm=%.2f reaches=%016llx\n",
	       shape->triangle_count, ms, (double)full / (double)ne, 1e3 * sum / (double)ne,
	       (unsigned long long)hash);
	free(vertex);
	free(edge);
	return 0;
}

int main(int argc, char **argv)
{
	int bands = 50, rounds = 5;
	float shell = 0.01f, bumps = 0.0f, radius = 0.5f;
	bool random_order = false, reaches = false;
	for (int a = 1; a < argc; ++a) {
		if (strcmp(argv[a], "--bands") == 0 && a + 1 < argc) {
			bands = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--shell") == 0 && a + 1 < argc) {
			shell = (float)atof(argv[++a]);
		} else if (strcmp(argv[a], "--rounds") == 0 && a + 1 < argc) {
			rounds = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--random") == 0) {
			random_order = true;
		} else if (strcmp(argv[a], "--reaches") == 0) {
			reaches = true;
		} else if (strcmp(argv[a], "--bumps") == 0 && a + 1 < argc) {
			bumps = (float)atof(argv[++a]);
		} else if (strcmp(argv[a], "--radius") == 0 && a + 1 < argc) {
			radius = (float)atof(argv[++a]);
		} else {
			fprintf(stderr, "usage: bench_mesh_queries [--bands B] [--shell S] [--random] [--rounds R] "
			                "[--reaches [--bumps A] [--radius R]]\n");
			return 2;
		}
	}
	if (bands < 3 || rounds < 1 || !(shell >= 0.0f && shell < 0.5f) || !(radius > 0.0f && radius < 100.0f) ||
	    !(fabsf(bumps) < 0.5f * radius)) {
		fprintf(stderr, "bench_mesh_queries: bands >= 3, rounds >= 1, 0 <= shell < 0.5 m, 0 < radius < 100 m "
		                "and |bumps| < radius / 2\n");
		return 2;
	}
	const plait_allocator heap = {NULL, NULL, NULL};
	plait_mesh_shape shape = make_sphere(bands, radius, bumps, &heap);
	if (reaches) {
		int status = bench_reaches(&shape, &heap);
		plait_mesh_shape_destroy(&shape, &heap);
		return status;
	}
	/* 200 x 200 points over a patch of the sphere, row by row (a cloth's order), each within
	 * the shell; or as many anywhere round it, in no order. */
	enum { SIDE = 200, COUNT = SIDE * SIDE };
	vec3 *points = malloc(sizeof *points * COUNT);
	unsigned state = 7u;
	for (int j = 0; j < SIDE; ++j) {
		for (int i = 0; i < SIDE; ++i) {
			float polar, around;
			if (random_order) {
				polar = acosf(2.0f * next_unit(&state) - 1.0f);
				around = 6.2831853f * next_unit(&state);
			} else {
				polar = 0.3f + 1.5f * (float)j / (float)SIDE;
				around = 2.5f * (float)i / (float)SIDE;
			}
			float r = radius + shell * (2.0f * next_unit(&state) - 1.0f);
			points[j * SIDE + i] =
			    v3(r * sinf(polar) * cosf(around), r * cosf(polar), r * sinf(polar) * sinf(around));
		}
	}
	double distance_sum = 0.0, start = now_seconds();
	for (int round = 0; round < rounds; ++round) {
		for (int k = 0; k < COUNT; ++k) {
			vec3 normal;
			distance_sum += plait_mesh_shape_distance(&shape, points[k], &normal);
		}
	}
	double distance_ns = 1e9 * (now_seconds() - start) / ((double)rounds * COUNT);
	long hits = 0;
	start = now_seconds();
	for (int round = 0; round < rounds; ++round) {
		for (int k = 0; k < COUNT; ++k) {
			vec3 grow = v3(0.006f, 0.006f, 0.006f);
			hits += plait_mesh_shape_any(&shape, v3_sub(points[k], grow), v3_add(points[k], grow));
		}
	}
	double any_ns = 1e9 * (now_seconds() - start) / ((double)rounds * COUNT);
	printf("triangles=%d order=%s shell=%g distance_ns=%.1f any_ns=%.1f distance_sum=%.6g any_hits=%ld\n",
	       shape.triangle_count, random_order ? "random" : "cloth", (double)shell, distance_ns, any_ns,
	       distance_sum, hits);
	free(points);
	plait_mesh_shape_destroy(&shape, &heap);
	return 0;
}
