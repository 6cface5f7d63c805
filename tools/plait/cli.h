/* The plait command line, callable in-process (tests) as well as from main(). */
#ifndef PLAIT_CLI_H
#define PLAIT_CLI_H

#include "scene.h"
#include "writers.h"

#include <stdbool.h>
#include <stdio.h>

/* Exit codes. */
#define PLAIT_EXIT_OK 0
#define PLAIT_EXIT_FAILURE 1 /* bad scene, failed simulation, cannot write; check: problems found */
#define PLAIT_EXIT_USAGE 2   /* bad command-line arguments; check: cannot read what it should check */

/* `plait ARGS...`: argv[0] is the program name. Normal output goes to out, messages to err. */
int plait_cli_main(int argc, char **argv, FILE *out, FILE *err);

typedef struct plait_run_options {
	const char *scene_path; /* NULL runs the built-in demo */
	const char *out_dir;
	int frames; /* < 0: as many as the scene says */
	const plait_writer_format *format;
	bool progress; /* a progress line on err, rewritten in place */
	bool check;    /* count intersections every frame into stats.jsonl */
	int threads;   /* workers for the solver, the calling thread included; <= 1: no thread pool */
} plait_run_options;

/* `plait run` once its arguments are parsed; returns an exit code. */
int plait_run(const plait_run_options *options, FILE *out, FILE *err);

/* `plait run ARGS...`, `plait check ARGS...` and `plait explain ARGS...` with argv[0] the
 * subcommand. */
int plait_cli_run(int argc, char **argv, FILE *out, FILE *err);
int plait_cli_check(int argc, char **argv, FILE *out, FILE *err);
int plait_cli_explain(int argc, char **argv, FILE *out, FILE *err);

/* Value of "--name VALUE" or "--name=VALUE" at argv[*i] (advancing *i past VALUE); NULL if
 * argv[*i] is not that option, with *missing set when it is but VALUE is not there. */
const char *plait_cli_option_value(int argc, char **argv, int *i, const char *name, bool *missing);

/* Loads the scene at path, or the demo when path is NULL. */
bool plait_cli_load_scene(const char *path, plait_scene *scene, plait_tool_error *error);

#endif
