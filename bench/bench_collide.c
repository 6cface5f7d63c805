/* collide: the collision scenes of issue #3 (tests/support/collide_scenes.h) at full size,
 * through the public API, with the intersection checker run on every frame.
 *
 * For each scene and run: ms/frame (median of the runs, checker time excluded), the share of
 * it spent in collisions (plait_frame_stats.collision_ms), and over all frames: the most
 * crossing triangle pairs in a frame, the frames with any, the most vertices inside colliders,
 * CCD hits and failsafe activations; at the end, stacked cloths out of order, and a hash of the
 * cloths' final positions (the same bits from two builds: the same results). first_ms is the
 * first frame alone: it builds the collision elements, trees and rest pairs. One line per run:
 *
 *   scene=pile n=64 threads=1 ms=12.3 collision=0.41 worst_crossings=0 crossing_frames=0 ...
 *
 * (worst_in_round: the most cloth triangles reaching into a sphere or capsule collider;
 * collider_features: kept/met, the corners and edges of mesh and box colliders that the last
 * listing of each frame met in element pairs with cloth and kept, of all it met there (the
 * others are smooth at the scale of the cloth's triangles; node pairs where none could be kept
 * are passed over unmet), mean over the frames.)
 *
 * usage: bench_collide [SCENE...] [--n N] [--frames F] [--runs R] [--threads T] [--no-check]
 *                      [--self-flag full|vertex_face|vertex] (of the self-colliding cloths)
 *                      [--thickness-per-edge R] (hang-self: thickness R times the edge, not 4 mm)
 *                      [--stiff] (hang-self: issue 4's stiff constraints and tethers, 6 substeps)
 *                      [--mesh-colliders] (arm, drape, twist: the capsules and spheres as meshes)
 *                      [--deforming-colliders] (twist: the sphere mesh turned vertex by vertex;
 *                       arm: one skinned mesh bent at the elbow; both deforming mesh colliders)
 *                      [--box-colliders] (arm: the capsules as square box bars)
 *                      [--coarse-floor] (pile: onto a coarse sheet of 3 x 3 vertices)
 *                      [--substeps S] (with --stiff: S substeps of one sweep each, not 6)
 *                      [--sphere-slices S] (hang-self: the sphere mesh's slices and stacks, 50)
 *                      [--sphere-radius R] (hang-self: the sphere's radius, 0.5 m; its top stays
 *                       where it was)
 *                      [--window FIRST LAST] (also the mean ms and collision ms a frame over
 *                       frames FIRST to LAST, e.g. hang-self --stiff falling free: 2 12)
 *                      [--verbose] (frames with crossings or vertices inside colliders)
 *                      [--per-frame] (a line per frame: its ms, collision ms and counters, and
 *                      the kinetic energy and largest strain at its end, measured untimed)
 *                      [--variants K] (each scene from K nearby starts, collide_scene_options
 *                      .variant 0..K-1: a line each, then their median, least and most ms; a
 *                      change judged on one start of a chaotic scene (folds, a pile) is judged
 *                      on where its cloth happened to fall)
 *                      [--contact-passes K] (the world's contact_pass_interval: a contact pass
 *                       at least every K stretch iterations; 0 none, the default)
 *   SCENE: drape thin-box pile twist arm hang-self (default: all)
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "collide_scenes.h"
#include "dynamics/mesh_contact.h"
#include "world/world.h"

#ifdef PLAIT_BENCH_HAVE_POOL
#include "thread_pool.h"
#endif

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

typedef struct run_result {
	double ms, first_ms, collision_ms;
	double window_ms, window_collision_ms; /* means over the frames of --window */
	int window_frames;
	uint64_t state; /* FNV-1a over the cloths' final positions' bits */
	int worst_crossings, crossing_frames, worst_inside, worst_in_round, ccd_hits, failsafe, order_violations;
	int frames;
	double features_kept, features_left_out; /* collider corners and edges met, summed over frames */
	long culled, unflattened;                /* flat patches passed over, and of those swept */
	bool failed;
} run_result;

/* Frames [first, last] (from 1) whose means run_result gives apart (first 0: none). */
typedef struct frame_window {
	int first, last;
} frame_window;

static run_result run(collide_scene_kind kind, int n, int frames, int threads, bool check, bool verbose,
                      bool per_frame, frame_window window, const collide_scene_options *options)
{
	run_result r = {0};
	plait_world_def def = plait_default_world_def();
#ifdef PLAIT_BENCH_HAVE_POOL
	plait_thread_pool *pool = threads > 1 ? plait_thread_pool_create(threads) : NULL;
	if (pool != NULL) {
		plait_thread_pool_attach(pool, &def);
	}
#else
	(void)threads;
#endif
	collide_scene scene;
	plait_error error;
	if (!collide_scene_create_with(&scene, kind, n, &def, options, &error)) {
		fprintf(stderr, "bench_collide: %s: %s\n", collide_scene_names[kind], error.message);
		exit(1);
	}
	r.frames = frames > 0 ? frames : scene.frames;
	double stepping = 0.0;
	for (int f = 0; f < r.frames; ++f) {
		double start = now_seconds();
		if (collide_scene_step(&scene, &error) != PLAIT_OK) {
			fprintf(stderr, "bench_collide: %s frame %d: %s\n", collide_scene_names[kind], f + 1,
			        error.message);
			r.failed = true;
			break;
		}
		double frame_seconds = now_seconds() - start;
		stepping += frame_seconds;
		if (f == 0) {
			r.first_ms = 1e3 * (now_seconds() - start);
		}
		plait_frame_stats stats = plait_world_get_stats(scene.world);
		if (per_frame) {
			printf("  frame=%d ms=%.2f collision_ms=%.2f contacts=%d ccd_hits=%d failsafe=%d kinetic_j=%.1f "
			       "max_strain=%.2f\n",
			       f + 1, 1e3 * frame_seconds, stats.collision_ms, stats.contacts, stats.ccd_hits,
			       stats.failsafe, stats.kinetic_energy, stats.max_strain);
		}
		r.collision_ms += stats.collision_ms;
		if (window.first > 0 && f + 1 >= window.first && f + 1 <= window.last) {
			r.window_ms += 1e3 * frame_seconds;
			r.window_collision_ms += stats.collision_ms;
			r.window_frames += 1;
		}
		r.ccd_hits += stats.ccd_hits;
		r.failsafe += stats.failsafe;
		int kept, left_out;
		plait_mesh_contacts_collider_features(&scene.world.world->sim, &kept, &left_out);
		r.features_kept += kept;
		r.features_left_out += left_out;
		if (check) {
			plait_intersection_report report;
			plait_world_check_intersections(scene.world, &report, NULL);
			r.crossing_frames += report.triangle_pairs > 0;
			if (verbose && (report.triangle_pairs > 0 || report.inside_colliders > 0 ||
			                report.triangles_in_colliders > 0)) {
				printf("  frame %d: crossings %d inside %d triangles in round colliders %d\n", f + 1,
				       report.triangle_pairs, report.inside_colliders, report.triangles_in_colliders);
			}
			if (report.triangle_pairs > r.worst_crossings) {
				r.worst_crossings = report.triangle_pairs;
			}
			if (report.inside_colliders > r.worst_inside) {
				r.worst_inside = report.inside_colliders;
			}
			if (report.triangles_in_colliders > r.worst_in_round) {
				r.worst_in_round = report.triangles_in_colliders;
			}
		}
	}
	r.ms = 1e3 * stepping / r.frames;
	r.collision_ms /= r.frames;
	if (r.window_frames > 0) {
		r.window_ms /= r.window_frames;
		r.window_collision_ms /= r.window_frames;
	}
	r.order_violations = collide_scene_order_violations(&scene);
	plait_mesh_contacts_flat_counts(&scene.world.world->sim, &r.culled, &r.unflattened);
	r.state = 1469598103934665603ull;
	for (int c = 0; c < scene.cloth_count; ++c) {
		int count = plait_object_get_vertex_count(scene.cloths[c]);
		plait_vec3 *x = malloc(sizeof *x * (size_t)(count > 0 ? count : 1));
		if (x != NULL && plait_object_get_positions(scene.cloths[c], 0, count, x, &error) == PLAIT_OK) {
			const unsigned char *bytes = (const unsigned char *)x;
			for (size_t k = 0; k < sizeof *x * (size_t)count; ++k) {
				r.state = (r.state ^ bytes[k]) * 1099511628211ull;
			}
		}
		free(x);
	}
	collide_scene_destroy(&scene);
#ifdef PLAIT_BENCH_HAVE_POOL
	if (pool != NULL) {
		plait_thread_pool_destroy(pool);
	}
#endif
	return r;
}

int main(int argc, char **argv)
{
	bool chosen[SCENE_COUNT] = {false}, any = false, check = true, verbose = false, per_frame = false;
	int n = 0, frames = 0, runs = 1, threads = 1, variants = 1;
	frame_window window = {0, 0};
	collide_scene_options options = collide_scene_default_options();
	for (int a = 1; a < argc; ++a) {
		if (strcmp(argv[a], "--n") == 0 && a + 1 < argc) {
			n = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--frames") == 0 && a + 1 < argc) {
			frames = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--runs") == 0 && a + 1 < argc) {
			runs = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--threads") == 0 && a + 1 < argc) {
			threads = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--no-check") == 0) {
			check = false;
		} else if (strcmp(argv[a], "--self-flag") == 0 && a + 1 < argc) {
			++a;
			options.self_flag = strcmp(argv[a], "vertex") == 0        ? PLAIT_SELF_COLLIDE_VERTEX
			                    : strcmp(argv[a], "vertex_face") == 0 ? PLAIT_SELF_COLLIDE_VERTEX_FACE
			                                                          : PLAIT_SELF_COLLIDE_FULL_SURFACE;
		} else if (strcmp(argv[a], "--thickness-per-edge") == 0 && a + 1 < argc) {
			options.thickness_per_edge = (float)atof(argv[++a]);
		} else if (strcmp(argv[a], "--mesh-colliders") == 0) {
			options.mesh_colliders = true;
		} else if (strcmp(argv[a], "--deforming-colliders") == 0) {
			options.mesh_colliders = options.deforming_colliders = true;
		} else if (strcmp(argv[a], "--box-colliders") == 0) {
			options.box_colliders = true;
		} else if (strcmp(argv[a], "--coarse-floor") == 0) {
			options.coarse_floor = true;
		} else if (strcmp(argv[a], "--stiff") == 0) {
			options.stiff = true;
		} else if (strcmp(argv[a], "--substeps") == 0 && a + 1 < argc) {
			options.stiff_substeps = atoi(argv[++a]);
			options.stiff_substeps = options.stiff_substeps > 0 ? options.stiff_substeps : -1;
		} else if (strcmp(argv[a], "--sphere-slices") == 0 && a + 1 < argc) {
			options.sphere_slices = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--sphere-radius") == 0 && a + 1 < argc) {
			options.sphere_radius = (float)atof(argv[++a]);
		} else if (strcmp(argv[a], "--verbose") == 0) {
			verbose = true;
		} else if (strcmp(argv[a], "--per-frame") == 0) {
			per_frame = true;
		} else if (strcmp(argv[a], "--window") == 0 && a + 2 < argc) {
			window.first = atoi(argv[++a]);
			window.last = atoi(argv[++a]);
			if (window.first < 1 || window.last < window.first) {
				fprintf(stderr, "bench_collide: --window takes two frames, 1 <= first <= last\n");
				return 2;
			}
		} else if (strcmp(argv[a], "--variants") == 0 && a + 1 < argc) {
			variants = atoi(argv[++a]);
		} else if (strcmp(argv[a], "--contact-passes") == 0 && a + 1 < argc) {
			options.contact_pass_interval = atoi(argv[++a]);
			if (options.contact_pass_interval < 0) {
				fprintf(stderr, "bench_collide: --contact-passes takes an interval >= 0\n");
				return 2;
			}
		} else {
			int k = 0;
			while (k < SCENE_COUNT && strcmp(argv[a], collide_scene_names[k]) != 0) {
				++k;
			}
			if (k == SCENE_COUNT) {
				fprintf(stderr,
				        "usage: bench_collide [SCENE...] [--n N] [--frames F] [--runs R] [--threads T] "
				        "[--no-check] [--self-flag full|vertex_face|vertex] [--thickness-per-edge R] "
				        "[--stiff] [--mesh-colliders] [--deforming-colliders] [--box-colliders] "
				        "[--coarse-floor] [--substeps S] "
				        "[--sphere-slices S] "
				        "[--verbose] "
				        "[--per-frame] [--window FIRST LAST] [--variants K] [--contact-passes K]\n"
				        "  SCENE: drape thin-box pile twist arm hang-self\n");
				return 2;
			}
			chosen[k] = any = true;
		}
	}
	if (runs < 1 || variants < 1) {
		fprintf(stderr, "bench_collide: --runs and --variants take a positive count\n");
		return 2;
	}
	if (options.stiff_substeps < 0 || (options.stiff_substeps != 0 && !options.stiff)) {
		fprintf(stderr, "bench_collide: --substeps takes a positive count and sets the stiff hang-self's "
		                "substeps; give --stiff too\n");
		return 2;
	}
	int failures = 0;
	for (int k = 0; k < SCENE_COUNT; ++k) {
		if (any && !chosen[k]) {
			continue;
		}
		double *ms = malloc(sizeof(double) * (size_t)runs);
		double *variant_ms = malloc(sizeof(double) * (size_t)variants);
		for (int v = 0; v < variants; ++v) {
			options.variant = v;
			run_result last = {0};
			for (int r = 0; r < runs; ++r) {
				last = run((collide_scene_kind)k, n, frames, threads, check, verbose, per_frame, window,
				           &options);
				ms[r] = last.ms;
			}
			qsort(ms, (size_t)runs, sizeof(double), compare_doubles);
			variant_ms[v] = ms[runs / 2];
			printf("scene=%s n=%d threads=%d frames=%d ms=%.3f collision=%.2f worst_crossings=%d "
			       "crossing_frames=%d worst_inside=%d worst_in_round=%d order_violations=%d ccd_hits=%d "
			       "failsafe=%d collider_features=%.0f/%.0f flat=%ld/%ld first_ms=%.1f state=%016llx",
			       collide_scene_names[k], n, threads, last.frames, ms[runs / 2], last.collision_ms / last.ms,
			       last.worst_crossings, last.crossing_frames, last.worst_inside, last.worst_in_round,
			       last.order_violations, last.ccd_hits, last.failsafe, last.features_kept / last.frames,
			       (last.features_kept + last.features_left_out) / last.frames, last.unflattened, last.culled,
			       last.first_ms, (unsigned long long)last.state);
			if (last.window_frames > 0) {
				printf(" window=%d-%d window_ms=%.2f window_collision_ms=%.2f", window.first,
				       window.first + last.window_frames - 1, last.window_ms, last.window_collision_ms);
			}
			if (variants > 1) {
				printf(" variant=%d", v);
			}
			printf("%s\n", last.failed ? " FAILED" : "");
			fflush(stdout);
			failures += last.failed;
		}
		if (variants > 1) {
			qsort(variant_ms, (size_t)variants, sizeof(double), compare_doubles);
			printf("scene=%s variants=%d median_ms=%.3f least_ms=%.3f most_ms=%.3f\n", collide_scene_names[k],
			       variants, variant_ms[variants / 2], variant_ms[0], variant_ms[variants - 1]);
			fflush(stdout);
		}
		free(variant_ms);
		free(ms);
	}
	return failures > 0;
}
