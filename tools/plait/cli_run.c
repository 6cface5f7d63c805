/* `plait run`: simulate a scene and write every frame. */
#include "cli.h"

#include "files.h"
#include "manifest.h"
#include "scene.h"
#include "stats_log.h"
#include "thread_pool.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static void plait_run_usage(FILE *f)
{
	fprintf(f, "usage: plait run [SCENE.json] [--out DIR] [--frames N] [--format obj|pc2] [--check]\n"
	           "                 [--threads N]\n");
}

static void plait_run_help(FILE *f)
{
	plait_run_usage(f);
	fprintf(f, "\nSimulates SCENE.json (without it, a built-in demo: cloth falling on a sphere) and writes\n"
	           "frame 0 and every simulated frame of every object, colliders included, to DIR, plus\n"
	           "DIR/stats.jsonl with one line per frame and, once done, DIR/manifest.json, which lets\n"
	           "`plait check DIR` read the frames back.\n\n"
	           "  --out DIR        output folder, created if missing (default: out)\n"
	           "  --frames N       frames to simulate (default: the scene's \"frames\")\n"
	           "  --format FORMAT  obj: DIR/NAME.FRAME.obj per object and frame (default)\n"
	           "                   pc2: DIR/NAME.pc2 point cache and DIR/NAME.obj mesh per object\n"
	           "  --check          count, every frame, crossing cloth triangles (between cloths and\n"
	           "                   within each) and vertices inside colliders, into stats.jsonl\n");
	fprintf(f,
	        "  --threads N      threads for the solver, this one included, 1 to %d (default: the\n"
	        "                   number of online processors, here %d); results do not depend on it\n",
	        PLAIT_THREAD_POOL_MAX_THREADS, plait_thread_pool_default_count());
	fprintf(f, "  -h, --help       this help\n\n"
	           "Exit status: 0 done, 1 scene error or failed simulation, 2 bad arguments.\n");
}

static double plait_now_seconds(void)
{
	struct timespec t;
	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int plait_cli_run(int argc, char **argv, FILE *out, FILE *err)
{
	plait_run_options options = {.out_dir = "out",
	                             .frames = -1,
	                             .format = &plait_writer_obj,
	                             .threads = plait_thread_pool_default_count()};
	for (int i = 1; i < argc; ++i) {
		const char *arg = argv[i];
		bool missing = false;
		const char *value;
		if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
			plait_run_help(out);
			return PLAIT_EXIT_OK;
		} else if (strcmp(arg, "--check") == 0) {
			options.check = true;
		} else if ((value = plait_cli_option_value(argc, argv, &i, "--out", &missing)) != NULL) {
			if (value[0] == '\0') {
				fprintf(err, "plait run: --out needs a folder name\n");
				plait_run_usage(err);
				return PLAIT_EXIT_USAGE;
			}
			options.out_dir = value;
		} else if ((value = plait_cli_option_value(argc, argv, &i, "--frames", &missing)) != NULL) {
			char *end;
			long frames = strtol(value, &end, 10);
			if (end == value || *end != '\0' || frames < 0 || frames > 1000000) {
				fprintf(err, "plait run: --frames expects a whole number from 0 to 1000000, got '%s'\n",
				        value);
				plait_run_usage(err);
				return PLAIT_EXIT_USAGE;
			}
			options.frames = (int)frames;
		} else if ((value = plait_cli_option_value(argc, argv, &i, "--threads", &missing)) != NULL) {
			char *end;
			long threads = strtol(value, &end, 10);
			if (end == value || *end != '\0' || threads < 1 || threads > PLAIT_THREAD_POOL_MAX_THREADS) {
				fprintf(err, "plait run: --threads expects a whole number from 1 to %d, got '%s'\n",
				        PLAIT_THREAD_POOL_MAX_THREADS, value);
				plait_run_usage(err);
				return PLAIT_EXIT_USAGE;
			}
			options.threads = (int)threads;
		} else if ((value = plait_cli_option_value(argc, argv, &i, "--format", &missing)) != NULL) {
			options.format = plait_writer_find_format(value);
			if (options.format == NULL) {
				fprintf(err, "plait run: unknown format '%s' (expected obj or pc2)\n", value);
				plait_run_usage(err);
				return PLAIT_EXIT_USAGE;
			}
		} else if (missing) {
			fprintf(err, "plait run: %s needs a value\n", arg);
			plait_run_usage(err);
			return PLAIT_EXIT_USAGE;
		} else if (arg[0] == '-' && arg[1] != '\0') {
			fprintf(err, "plait run: unknown option '%s'\n", arg);
			plait_run_usage(err);
			return PLAIT_EXIT_USAGE;
		} else if (options.scene_path != NULL) {
			fprintf(err, "plait run: one scene at a time (got '%s' and '%s')\n", options.scene_path, arg);
			plait_run_usage(err);
			return PLAIT_EXIT_USAGE;
		} else {
			options.scene_path = arg;
		}
	}
	int fd = fileno(err);
	options.progress = fd >= 0 && isatty(fd);
	return plait_run(&options, out, err);
}

static void plait_run_progress(FILE *err, int frame, int frames, double step_ms, double elapsed)
{
	double left = frame > 0 ? elapsed / frame * (frames - frame) : 0.0;
	fprintf(err, "\rframe %d/%d  %.1f ms/frame  ~%.0fs left   ", frame, frames, step_ms, left);
	fflush(err);
}

typedef struct plait_run_outputs {
	plait_writer *writer;
	plait_manifest manifest;
	plait_stats_log stats;
	bool check;
} plait_run_outputs;

static bool plait_run_write(plait_run_outputs *outputs, plait_world_id world, int frame, double ms,
                            plait_tool_error *error)
{
	plait_frame_stats stats = plait_world_get_stats(world);
	plait_intersection_report report;
	if (outputs->check) {
		plait_error core_error;
		if (plait_world_check_intersections(world, &report, &core_error) != PLAIT_OK)
			return plait_tool_error_set(error, "frame %d: intersection check: %s", frame, core_error.message);
	}
	return plait_writer_write_frame(outputs->writer, frame, error) &&
	       plait_manifest_record_frame(&outputs->manifest, outputs->writer, frame, error) &&
	       plait_stats_log_write(&outputs->stats, frame, ms, &stats, outputs->check ? &report : NULL, error);
}

int plait_run(const plait_run_options *options, FILE *out, FILE *err)
{
	plait_tool_error error = {{0}};
	plait_scene scene;
	if (!plait_cli_load_scene(options->scene_path, &scene, &error)) {
		fprintf(err, "%s\n", error.message);
		return PLAIT_EXIT_FAILURE;
	}
	for (int i = 0; i < scene.warning_count; ++i)
		fprintf(err, "warning: %s\n", scene.warnings[i]);
	int frames = options->frames >= 0 ? options->frames : scene.frames;
	if (options->scene_path == NULL)
		fprintf(out, "plait: no scene given, running the built-in demo (cloth falling on a sphere)\n");

	// The solver's threads: none beyond this one for 1. The pool outlives the world.
	plait_thread_pool *pool = NULL;
	if (options->threads > 1) {
		pool = plait_thread_pool_create(options->threads);
		if (pool == NULL) {
			fprintf(err, "plait: cannot start %d threads\n", options->threads - 1);
			plait_scene_free(&scene);
			return PLAIT_EXIT_FAILURE;
		}
	}
	plait_thread_pool_attach(pool, &scene.world);

	// Validate everything the solver checks before a single file exists.
	plait_world_id world;
	if (!plait_scene_create_world(&scene, &world, &error)) {
		fprintf(err, "%s\n", error.message);
		plait_scene_free(&scene);
		plait_thread_pool_destroy(pool);
		return PLAIT_EXIT_FAILURE;
	}
	plait_run_outputs outputs = {0};
	outputs.check = options->check;
	if (!plait_make_dirs(options->out_dir, &error) ||
	    !plait_stats_log_open(&outputs.stats, options->out_dir, &error)) {
		fprintf(err, "plait: %s\n", error.message);
		plait_destroy_world(world);
		plait_scene_free(&scene);
		plait_thread_pool_destroy(pool);
		return PLAIT_EXIT_FAILURE;
	}
	outputs.writer = plait_writer_open(options->format, options->out_dir, world, &error);
	if (outputs.writer == NULL || !plait_manifest_begin(&outputs.manifest, outputs.writer, &scene, &error)) {
		fprintf(err, "plait: %s\n", error.message);
		plait_writer_close(outputs.writer, NULL);
		plait_manifest_free(&outputs.manifest);
		plait_atomic_abort(&outputs.stats.file);
		plait_destroy_world(world);
		plait_scene_free(&scene);
		plait_thread_pool_destroy(pool);
		return PLAIT_EXIT_FAILURE;
	}

	int status = PLAIT_EXIT_OK;
	int done = 0;
	double start = plait_now_seconds(), step_total_ms = 0.0;
	if (!plait_run_write(&outputs, world, 0, 0.0, &error)) {
		fprintf(err, "plait: %s\n", error.message);
		status = PLAIT_EXIT_FAILURE;
	}
	for (int frame = 1; status == PLAIT_EXIT_OK && frame <= frames; ++frame) {
		// Keyframes and pins for the frame being stepped to.
		if (!plait_scene_apply_frame(&scene, world, frame, &error)) {
			fprintf(err, "%s%s\n", options->progress ? "\n" : "", error.message);
			status = PLAIT_EXIT_FAILURE;
			break;
		}
		plait_error core_error = {0};
		double t0 = plait_now_seconds();
		plait_result result = plait_world_step(world, &core_error);
		double ms = 1000.0 * (plait_now_seconds() - t0);
		if (result != PLAIT_OK) {
			fprintf(err, "%s%s: frame %d: the simulation failed (%s): %s\n", options->progress ? "\n" : "",
			        scene.file, frame, plait_result_name(result), core_error.message);
			fprintf(err, "frames 0 to %d are in %s\n", frame - 1, options->out_dir);
			status = PLAIT_EXIT_FAILURE;
			break;
		}
		step_total_ms += ms;
		if (!plait_run_write(&outputs, world, frame, ms, &error)) {
			fprintf(err, "%splait: %s\n", options->progress ? "\n" : "", error.message);
			status = PLAIT_EXIT_FAILURE;
			break;
		}
		done = frame;
		if (options->progress)
			plait_run_progress(err, frame, frames, step_total_ms / frame, plait_now_seconds() - start);
	}
	if (options->progress && done > 0)
		fprintf(err, "\r%60s\r", "");
	// Finish the files even after a failure: the frames written so far stay usable.
	// The manifest goes last: it vouches for the frames before it.
	int objects_written = outputs.writer->object_count;
	if (!plait_writer_close(outputs.writer, &error) || !plait_stats_log_close(&outputs.stats, &error) ||
	    !plait_manifest_commit(&outputs.manifest, options->out_dir, &error)) {
		fprintf(err, "plait: %s\n", error.message);
		plait_atomic_abort(&outputs.stats.file);
		status = PLAIT_EXIT_FAILURE;
	}
	plait_manifest_free(&outputs.manifest);
	if (status == PLAIT_EXIT_OK) {
		double seconds = plait_now_seconds() - start;
		fprintf(out, "plait: simulated %d frame%s of %s in %.2f s (%.1f ms/frame in the solver)\n", done,
		        done == 1 ? "" : "s", scene.file, seconds, done > 0 ? step_total_ms / done : 0.0);
		fprintf(
		    out, "plait: wrote frames 0 to %d of %d object%s as %s, stats.jsonl and manifest.json, to %s/\n",
		    done, objects_written, objects_written == 1 ? "" : "s", options->format->name, options->out_dir);
	}
	plait_destroy_world(world);
	plait_scene_free(&scene);
	plait_thread_pool_destroy(pool);
	return status;
}
