/* The floating-point mode of a step. Constraint corrections of a settled cloth shrink into
 * subnormal numbers, and arithmetic on those is microcoded on x86: one hang-128 frame ran 25%
 * slower for it. Like PhysX's solver, a step therefore runs with subnormals flushed to zero
 * (FTZ and DAZ), on the calling thread and on every worker, and restores the caller's mode
 * after. Every thread and every instruction set then computes in the same mode, so results
 * stay identical across them. Elsewhere than x86 the mode is left as it is. */
#ifndef PLAIT_CORE_FLOAT_MODE_H
#define PLAIT_CORE_FLOAT_MODE_H

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

typedef unsigned int plait_float_mode;

static inline plait_float_mode plait_float_mode_enter(void)
{
#if defined(__SSE2__)
	unsigned int saved = _mm_getcsr();
	_mm_setcsr(saved | 0x8040u); /* FTZ (bit 15) and DAZ (bit 6) */
	return saved;
#else
	return 0;
#endif
}

static inline void plait_float_mode_leave(plait_float_mode saved)
{
#if defined(__SSE2__)
	_mm_setcsr(saved);
#else
	(void)saved;
#endif
}

#endif
