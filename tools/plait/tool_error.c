#include "tool_error.h"

#include <stdarg.h>
#include <stdio.h>

bool plait_tool_error_set(plait_tool_error *error, const char *format, ...)
{
	if (error == NULL)
		return false;
	va_list args;
	va_start(args, format);
	vsnprintf(error->message, sizeof error->message, format, args);
	va_end(args);
	return false;
}
