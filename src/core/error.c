#include "core/error.h"

#include <stdarg.h>
#include <stdio.h>

plait_result plait_error_set(plait_error *error, plait_result code, const char *format, ...)
{
	if (error != NULL) {
		va_list args;
		va_start(args, format);
		vsnprintf(error->message, sizeof error->message, format, args);
		va_end(args);
		error->code = code;
	}
	return code;
}

void plait_error_clear(plait_error *error)
{
	if (error != NULL) {
		error->code = PLAIT_OK;
		error->message[0] = '\0';
	}
}

const char *plait_result_name(plait_result result)
{
	switch (result) {
	case PLAIT_OK:
		return "ok";
	case PLAIT_ERROR_INVALID_ARGUMENT:
		return "invalid argument";
	case PLAIT_ERROR_INVALID_ID:
		return "invalid id";
	case PLAIT_ERROR_INVALID_MESH:
		return "invalid mesh";
	case PLAIT_ERROR_OUT_OF_MEMORY:
		return "out of memory";
	case PLAIT_ERROR_NONFINITE:
		return "non-finite value";
	}
	return "unknown error";
}
