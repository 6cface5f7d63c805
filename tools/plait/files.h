/* Output files that appear whole or not at all: written under a temporary name in the same
 * folder, then renamed into place (rename is atomic within a file system). */
#ifndef PLAIT_FILES_H
#define PLAIT_FILES_H

#include "tool_error.h"

#include <stdbool.h>
#include <stdio.h>

/* mkdir -p: creates path and its missing parents; an existing folder is fine. */
bool plait_make_dirs(const char *path, plait_tool_error *error);

typedef struct plait_atomic_file {
	FILE *file;
	char *temp_path;  /* DIR/.NAME.tmp */
	char *final_path; /* DIR/NAME */
} plait_atomic_file;

/* Opens DIR/.NAME.tmp for binary writing. */
bool plait_atomic_open(plait_atomic_file *atomic, const char *dir, const char *name, plait_tool_error *error);
/* Flushes, closes and renames to DIR/NAME; on any failure removes the temporary file. */
bool plait_atomic_commit(plait_atomic_file *atomic, plait_tool_error *error);
/* Closes and removes the temporary file. */
void plait_atomic_abort(plait_atomic_file *atomic);

#endif
