/* Errors of the tool layer: one readable message, already naming the file and key path. */
#ifndef PLAIT_TOOL_ERROR_H
#define PLAIT_TOOL_ERROR_H

#include <stdbool.h>

#define PLAIT_TOOL_ERROR_SIZE 512

typedef struct plait_tool_error {
	char message[PLAIT_TOOL_ERROR_SIZE];
} plait_tool_error;

/* printf-style; a NULL error is allowed. Always returns false so callers can `return set(...)`. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
bool plait_tool_error_set(plait_tool_error *error, const char *format, ...);

#endif
