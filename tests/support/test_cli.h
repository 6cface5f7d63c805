/* Running the plait tool in-process, and the file chores around it, for the tests that drive
 * the command line (they need the tool layer, plait_toollib). */
#ifndef PLAIT_TEST_CLI_H
#define PLAIT_TEST_CLI_H

#include <stddef.h>

typedef struct cli_result {
	int code;
	char *out;
	char *err;
} cli_result;

/* Runs `plait ARGS...` in-process with captured output; free with free_result. */
cli_result run_cli(int argc, const char **argv);
void free_result(cli_result *result);

/* rm -r of a test's temporary folder. */
void remove_tree(const char *path);

/* The whole file, NUL-terminated (malloc'ed), its length in *size when size is not NULL; NULL
 * when it cannot be opened. */
char *read_file(const char *path, size_t *size);

#endif
