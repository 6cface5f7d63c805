/* A monotonic-enough wall clock for the library's own profile figures (C11 timespec_get: no
 * POSIX needed). Only measures; nothing in the solver depends on it. */
#ifndef PLAIT_CORE_CLOCK_H
#define PLAIT_CORE_CLOCK_H

#include <time.h>

static inline double plait_seconds(void)
{
	struct timespec t;
	if (timespec_get(&t, TIME_UTC) != TIME_UTC) {
		return 0.0;
	}
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#endif
