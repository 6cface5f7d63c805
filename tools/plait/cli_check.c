/* `plait check DIR`: counts, in every frame `plait run --out DIR` wrote, the triangles that cross
 * (between objects and within each cloth) and the vertices inside colliders, from the files
 * alone. Exit status as diff and cmp: 0 clean, 1 problems found, 2 could not check. */
#include "cli.h"

#include "files.h"
#include "frame_check.h"
#include "frame_reader.h"
#include "json_write.h"
#include "manifest.h"
#include "thread_pool.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define PLAIT_CHECK_DEFAULT_TOLERANCE 1e-4
#define PLAIT_CHECK_LOG_NAME "check.jsonl"
#define PLAIT_CHECK_FRAMES_SHOWN 10

static void plait_check_usage(FILE *f)
{
	fprintf(f, "usage: plait check DIR [--log FILE] [--tolerance METRES] [--threads N]\n");
}

static void plait_check_help(FILE *f)
{
	plait_check_usage(f);
	fprintf(f, "\nChecks every frame that `plait run --out DIR` wrote (obj or pc2), from the files and\n"
	           "DIR/manifest.json alone, and counts:\n"
	           "  - pairs of crossing triangles between objects (cloth against cloth, cloth against\n"
	           "    collider surfaces) and within each cloth (triangles that share no vertex);\n"
	           "  - vertices of cloth, curves and particles inside a collider (below a plane, inside a\n"
	           "    sphere, capsule, box or closed mesh) by more than the tolerance.\n"
	           "Objects with \"collide\": false are left out. One JSON line per frame goes to the log, a\n"
	           "summary to stdout.\n\n"
	           "  --log FILE            per-frame counts (default: DIR/check.jsonl; '-': stdout, and the\n"
	           "                        summary goes to stderr)\n"
	           "  --tolerance METRES    how deep a vertex must be inside a collider to count (default 1e-4)\n"
	           "  --threads N           frames checked at once (default: the number of online processors)\n"
	           "  -h, --help            this help\n\n"
	           "Exit status: 0 every frame is clean, 1 some frame has crossing triangles or vertices\n"
	           "inside colliders, 2 bad arguments or DIR cannot be read (not a finished run, a file cut\n"
	           "short); then nothing is written.\n");
}

typedef struct plait_check_options {
	const char *dir;
	const char *log; /* NULL: DIR/check.jsonl */
	double tolerance;
	int threads;
} plait_check_options;

typedef struct plait_check_totals {
	long long intersections, between_objects, inside_colliders;
	long long *pairs; /* summed over frames, as plait_frame_counts */
	long long *inside;
	long long *frame_pairs, *frame_inside; /* one frame's, widened for plait_check_describe */
	int frames, problem_frames, first_problem;
} plait_check_totals;

static void plait_check_line(FILE *f, const plait_manifest *m, int frame, const plait_frame_counts *counts)
{
	int n = m->object_count;
	fprintf(f, "{\"frame\":%d,\"intersections\":%d,\"between_objects\":%d,\"self\":{", frame,
	        counts->intersections, counts->between_objects);
	bool first = true;
	for (int o = 0; o < n; ++o) {
		if (m->objects[o].type != PLAIT_OBJECT_CLOTH)
			continue;
		fputs(first ? "" : ",", f);
		plait_json_put_string(f, m->objects[o].name);
		fprintf(f, ":%d", counts->pairs[o * n + o]);
		first = false;
	}
	fprintf(f, "},\"inside_colliders\":%d,\"pairs\":{", counts->inside_colliders);
	first = true;
	for (int a = 0; a < n; ++a) {
		for (int b = a + 1; b < n; ++b) {
			if (counts->pairs[a * n + b] == 0)
				continue;
			// Names have no '/': it cannot be mistaken for part of one.
			char key[2 * sizeof m->objects[0].name + 1];
			snprintf(key, sizeof key, "%s/%s", m->objects[a].name, m->objects[b].name);
			fputs(first ? "" : ",", f);
			plait_json_put_string(f, key);
			fprintf(f, ":%d", counts->pairs[a * n + b]);
			first = false;
		}
	}
	fputs("},\"inside\":{", f);
	first = true;
	for (int c = 0; c < n; ++c) {
		if (counts->inside[c] == 0)
			continue;
		fputs(first ? "" : ",", f);
		plait_json_put_string(f, m->objects[c].name);
		fprintf(f, ":%d", counts->inside[c]);
		first = false;
	}
	fputs("}}\n", f);
}

// "3 crossing triangle pairs (sheet/ball 2, within sheet 1), 2 vertices inside colliders (ball 2)"
static void plait_check_describe(FILE *f, const plait_manifest *m, long long intersections,
                                 long long inside_count, const long long *pairs, const long long *inside)
{
	int n = m->object_count;
	fprintf(f, "%lld crossing triangle pair%s", intersections, intersections == 1 ? "" : "s");
	const char *separator = " (";
	for (int a = 0; a < n; ++a) {
		for (int b = a; b < n; ++b) {
			long long count = pairs[a * n + b];
			if (count == 0)
				continue;
			if (a == b)
				fprintf(f, "%swithin %s %lld", separator, m->objects[a].name, count);
			else
				fprintf(f, "%s%s/%s %lld", separator, m->objects[a].name, m->objects[b].name, count);
			separator = ", ";
		}
	}
	fputs(separator[0] == ',' ? ")" : "", f);
	fprintf(f, ", %lld vert%s inside colliders", inside_count, inside_count == 1 ? "ex" : "ices");
	separator = " (";
	for (int c = 0; c < n; ++c) {
		if (inside[c] == 0)
			continue;
		fprintf(f, "%s%s %lld", separator, m->objects[c].name, inside[c]);
		separator = ", ";
	}
	fputs(separator[0] == ',' ? ")" : "", f);
}

// Logs a frame's line, adds it to the totals, and shows the first frames with problems.
static void plait_check_add_frame(FILE *lines, FILE *summary, const plait_manifest *manifest, int frame,
                                  const plait_frame_counts *counts, plait_check_totals *totals)
{
	int n = manifest->object_count;
	plait_check_line(lines, manifest, frame, counts);
	totals->frames += 1;
	totals->intersections += counts->intersections;
	totals->between_objects += counts->between_objects;
	totals->inside_colliders += counts->inside_colliders;
	for (int k = 0; k < n * n; ++k)
		totals->pairs[k] += counts->pairs[k];
	for (int c = 0; c < n; ++c)
		totals->inside[c] += counts->inside[c];
	if (counts->intersections == 0 && counts->inside_colliders == 0)
		return;
	if (totals->problem_frames < PLAIT_CHECK_FRAMES_SHOWN) {
		for (int k = 0; k < n * n; ++k)
			totals->frame_pairs[k] = counts->pairs[k];
		for (int c = 0; c < n; ++c)
			totals->frame_inside[c] = counts->inside[c];
		fprintf(summary, "frame %d: ", frame);
		plait_check_describe(summary, manifest, counts->intersections, counts->inside_colliders,
		                     totals->frame_pairs, totals->frame_inside);
		fputc('\n', summary);
	}
	if (totals->first_problem < 0)
		totals->first_problem = frame;
	totals->problem_frames += 1;
}

static int plait_check_summary(const plait_check_options *options, FILE *summary, bool to_stdout,
                               const plait_manifest *manifest, const plait_check_totals *totals)
{
	int n = manifest->object_count, status = PLAIT_EXIT_OK;
	if (totals->problem_frames > PLAIT_CHECK_FRAMES_SHOWN)
		fprintf(summary, "... and %d more frames with problems\n",
		        totals->problem_frames - PLAIT_CHECK_FRAMES_SHOWN);
	fprintf(summary, "plait check: %s: frames %d to %d, %d object%s: ", options->dir, manifest->first_frame,
	        manifest->last_frame, n, n == 1 ? "" : "s");
	if (totals->problem_frames == 0) {
		fputs("clean, no crossing triangles and no vertices inside colliders", summary);
	} else {
		fprintf(summary, "%d frame%s with problems, the first at frame %d; in all ", totals->problem_frames,
		        totals->problem_frames == 1 ? "" : "s", totals->first_problem);
		plait_check_describe(summary, manifest, totals->intersections, totals->inside_colliders,
		                     totals->pairs, totals->inside);
		status = PLAIT_EXIT_FAILURE;
	}
	if (to_stdout)
		fputc('\n', summary);
	else if (options->log != NULL)
		fprintf(summary, "\nper-frame counts in %s\n", options->log);
	else
		fprintf(summary, "\nper-frame counts in %s/%s\n", options->dir, PLAIT_CHECK_LOG_NAME);
	return status;
}

static bool plait_check_is_folder(const char *dir, plait_tool_error *error)
{
	struct stat info;
	if (stat(dir, &info) != 0) {
		int code = errno;
		return plait_tool_error_set(error, "%s: %s", dir, code == ENOENT ? "no such folder" : strerror(code));
	}
	if (!S_ISDIR(info.st_mode))
		return plait_tool_error_set(error, "%s: not a folder (expected the DIR of `plait run --out DIR`)",
		                            dir);
	return true;
}

// The log is written under a temporary name beside its final place and renamed at the end, so
// a check that fails leaves nothing behind.
static bool plait_check_open_log(const plait_check_options *options, plait_atomic_file *log, FILE *out,
                                 FILE **lines, plait_tool_error *error)
{
	*log = (plait_atomic_file){0};
	if (options->log != NULL && strcmp(options->log, "-") == 0) {
		*lines = out;
		return true;
	}
	const char *dir = options->dir, *name = PLAIT_CHECK_LOG_NAME;
	char *folder = NULL;
	if (options->log != NULL) {
		const char *slash = strrchr(options->log, '/');
		name = slash != NULL ? slash + 1 : options->log;
		folder = slash == NULL
		             ? strdup(".")
		             : strndup(options->log, slash == options->log ? 1 : (size_t)(slash - options->log));
		if (folder == NULL)
			return plait_tool_error_set(error, "out of memory");
		dir = folder;
		if (name[0] == '\0') {
			free(folder);
			return plait_tool_error_set(error, "--log %s: expected a file name", options->log);
		}
	}
	bool ok = plait_atomic_open(log, dir, name, error);
	free(folder);
	*lines = ok ? log->file : NULL;
	return ok;
}

/* One frame's outcome, computed by whichever worker took it. */
typedef struct plait_check_result {
	bool ok;
	plait_tool_error error;
	int intersections, between_objects, inside_colliders;
	int *pairs, *inside; /* as plait_frame_counts */
} plait_check_result;

/* A worker reads and checks every stride-th frame of a batch with its own reader and scratch. */
typedef struct plait_check_worker {
	plait_frame_reader reader;
	plait_frame_checker checker;
	bool ready;
	const plait_manifest *manifest;
	plait_check_result *results; /* the batch's */
	int batch_first, batch_count, index, stride;
	pthread_t thread;
} plait_check_worker;

static void *plait_check_worker_run(void *context)
{
	plait_check_worker *w = context;
	int n = w->manifest->object_count;
	for (int k = w->index; k < w->batch_count; k += w->stride) {
		plait_check_result *result = &w->results[k];
		int frame = w->batch_first + k;
		result->ok = plait_frame_reader_read(&w->reader, frame, &result->error) &&
		             plait_frame_check(&w->checker, w->reader.meshes, frame, &result->error);
		if (!result->ok)
			break; // later frames of the batch are not reported after an error
		const plait_frame_counts *counts = &w->checker.counts;
		result->intersections = counts->intersections;
		result->between_objects = counts->between_objects;
		result->inside_colliders = counts->inside_colliders;
		memcpy(result->pairs, counts->pairs, sizeof *result->pairs * (size_t)n * (size_t)n);
		memcpy(result->inside, counts->inside, sizeof *result->inside * (size_t)n);
	}
	return NULL;
}

// Frames are independent: a batch of them is shared out among the workers, then reported in
// order. Results do not depend on the number of threads.
static bool plait_check_frames(plait_check_worker *workers, int thread_count, const plait_manifest *manifest,
                               FILE *lines, FILE *summary, plait_check_totals *totals,
                               plait_tool_error *error)
{
	int n = manifest->object_count, batch = 8 * thread_count;
	plait_check_result *results = calloc((size_t)batch, sizeof *results);
	int *pairs = calloc((size_t)batch * (size_t)(n * n + 1), sizeof *pairs);
	int *inside = calloc((size_t)batch * (size_t)(n + 1), sizeof *inside);
	bool ok = results != NULL && pairs != NULL && inside != NULL;
	if (!ok)
		plait_tool_error_set(error, "out of memory");
	for (int k = 0; ok && k < batch; ++k) {
		results[k].pairs = pairs + (size_t)k * (size_t)(n * n + 1);
		results[k].inside = inside + (size_t)k * (size_t)(n + 1);
	}
	for (int first = manifest->first_frame; ok && first <= manifest->last_frame; first += batch) {
		int count = manifest->last_frame - first + 1 < batch ? manifest->last_frame - first + 1 : batch;
		for (int k = 0; k < count; ++k)
			results[k].ok = false;
		int started = 1;
		for (int t = 0; t < thread_count; ++t) {
			plait_check_worker *w = &workers[t];
			w->results = results;
			w->batch_first = first;
			w->batch_count = count;
			w->index = t;
			w->stride = thread_count;
			if (t > 0 && pthread_create(&w->thread, NULL, plait_check_worker_run, w) == 0)
				++started;
			else if (t > 0)
				break; // fewer threads: the frames left over are taken below
		}
		plait_check_worker_run(&workers[0]);
		for (int t = 1; t < started; ++t)
			pthread_join(workers[t].thread, NULL);
		// Frames of threads that could not start.
		for (int t = started; t < thread_count; ++t) {
			workers[0].index = t;
			plait_check_worker_run(&workers[0]);
		}
		for (int k = 0; ok && k < count; ++k) {
			const plait_check_result *r = &results[k];
			if (!r->ok) {
				*error = r->error;
				ok = false;
				break;
			}
			plait_frame_counts counts = {r->intersections, r->between_objects, r->inside_colliders, r->pairs,
			                             r->inside};
			plait_check_add_frame(lines, summary, manifest, first + k, &counts, totals);
		}
	}
	free(results);
	free(pairs);
	free(inside);
	return ok;
}

static int plait_check(const plait_check_options *options, FILE *out, FILE *err)
{
	plait_tool_error error = {{0}};
	plait_manifest manifest;
	if (!plait_check_is_folder(options->dir, &error) ||
	    !plait_manifest_load(options->dir, &manifest, &error)) {
		fprintf(err, "plait check: %s\n", error.message);
		return PLAIT_EXIT_USAGE;
	}
	int frames = manifest.last_frame - manifest.first_frame + 1;
	int thread_count = options->threads < frames ? options->threads : frames;
	thread_count = thread_count > 1 ? thread_count : 1;
	plait_check_worker *workers = calloc((size_t)thread_count, sizeof *workers);
	bool ok = workers != NULL;
	if (!ok)
		plait_tool_error_set(&error, "out of memory");
	for (int t = 0; ok && t < thread_count; ++t) {
		plait_check_worker *w = &workers[t];
		w->manifest = &manifest;
		ok = plait_frame_reader_open(&w->reader, options->dir, &manifest, &error);
		if (ok && !plait_frame_checker_init(&w->checker, &manifest, options->tolerance, &error)) {
			plait_frame_reader_close(&w->reader);
			ok = false;
		}
		w->ready = ok;
	}
	bool to_stdout = options->log != NULL && strcmp(options->log, "-") == 0;
	FILE *summary = to_stdout ? err : out;
	int n = manifest.object_count;
	plait_check_totals totals = {.first_problem = -1};
	totals.pairs = calloc((size_t)(n > 0 ? n * n : 1), sizeof *totals.pairs);
	totals.inside = calloc((size_t)(n > 0 ? n : 1), sizeof *totals.inside);
	totals.frame_pairs = calloc((size_t)(n > 0 ? n * n : 1), sizeof *totals.frame_pairs);
	totals.frame_inside = calloc((size_t)(n > 0 ? n : 1), sizeof *totals.frame_inside);
	if (ok && (totals.pairs == NULL || totals.inside == NULL || totals.frame_pairs == NULL ||
	           totals.frame_inside == NULL))
		ok = plait_tool_error_set(&error, "out of memory");
	plait_atomic_file log = {0};
	FILE *lines = NULL;
	ok = ok && plait_check_open_log(options, &log, out, &lines, &error);
	ok = ok && plait_check_frames(workers, thread_count, &manifest, lines, summary, &totals, &error);
	if (ok && log.file != NULL)
		ok = plait_atomic_commit(&log, &error);
	else if (ok && ferror(lines))
		ok = plait_tool_error_set(&error, "cannot write the per-frame counts");
	int status = PLAIT_EXIT_USAGE;
	if (!ok) {
		plait_atomic_abort(&log);
		fprintf(err, "plait check: %s\n", error.message);
	} else {
		status = plait_check_summary(options, summary, to_stdout, &manifest, &totals);
	}
	for (int t = 0; workers != NULL && t < thread_count; ++t) {
		if (workers[t].ready) {
			plait_frame_checker_free(&workers[t].checker);
			plait_frame_reader_close(&workers[t].reader);
		}
	}
	free(workers);
	free(totals.pairs);
	free(totals.inside);
	free(totals.frame_pairs);
	free(totals.frame_inside);
	plait_manifest_free(&manifest);
	return status;
}

int plait_cli_check(int argc, char **argv, FILE *out, FILE *err)
{
	plait_check_options options = {.tolerance = PLAIT_CHECK_DEFAULT_TOLERANCE,
	                               .threads = plait_thread_pool_default_count()};
	for (int i = 1; i < argc; ++i) {
		const char *arg = argv[i];
		bool missing = false;
		const char *value;
		if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
			plait_check_help(out);
			return PLAIT_EXIT_OK;
		} else if ((value = plait_cli_option_value(argc, argv, &i, "--log", &missing)) != NULL) {
			if (value[0] == '\0') {
				fprintf(err, "plait check: --log needs a file name (or '-' for stdout)\n");
				plait_check_usage(err);
				return PLAIT_EXIT_USAGE;
			}
			options.log = value;
		} else if ((value = plait_cli_option_value(argc, argv, &i, "--tolerance", &missing)) != NULL) {
			char *end;
			double tolerance = strtod(value, &end);
			if (end == value || *end != '\0' || !isfinite(tolerance) || tolerance < 0.0) {
				fprintf(err, "plait check: --tolerance expects a length in metres >= 0, got '%s'\n", value);
				plait_check_usage(err);
				return PLAIT_EXIT_USAGE;
			}
			options.tolerance = tolerance;
		} else if ((value = plait_cli_option_value(argc, argv, &i, "--threads", &missing)) != NULL) {
			char *end;
			long threads = strtol(value, &end, 10);
			if (end == value || *end != '\0' || threads < 1 || threads > PLAIT_THREAD_POOL_MAX_THREADS) {
				fprintf(err, "plait check: --threads expects a whole number from 1 to %d, got '%s'\n",
				        PLAIT_THREAD_POOL_MAX_THREADS, value);
				plait_check_usage(err);
				return PLAIT_EXIT_USAGE;
			}
			options.threads = (int)threads;
		} else if (missing) {
			fprintf(err, "plait check: %s needs a value\n", arg);
			plait_check_usage(err);
			return PLAIT_EXIT_USAGE;
		} else if (arg[0] == '-' && arg[1] != '\0') {
			fprintf(err, "plait check: unknown option '%s'\n", arg);
			plait_check_usage(err);
			return PLAIT_EXIT_USAGE;
		} else if (options.dir != NULL) {
			fprintf(err, "plait check: one folder at a time (got '%s' and '%s')\n", options.dir, arg);
			plait_check_usage(err);
			return PLAIT_EXIT_USAGE;
		} else {
			options.dir = arg;
		}
	}
	if (options.dir == NULL) {
		fprintf(err, "plait check: which folder? (the DIR of `plait run --out DIR`)\n");
		plait_check_usage(err);
		return PLAIT_EXIT_USAGE;
	}
	return plait_check(&options, out, err);
}
