/* Filling a caller's plait_error: the only way the library reports what went wrong. */
#ifndef PLAIT_CORE_ERROR_H
#define PLAIT_CORE_ERROR_H

#include <plait/plait.h>

/* Writes code and a printf-style message into error (if not NULL); returns code. */
plait_result plait_error_set(plait_error *error, plait_result code, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
void plait_error_clear(plait_error *error);

#endif
