/* Copies that bypass the caches, for data written once and read back only in an emergency
 * (the frame-start state a failed frame is restored from). An ordinary copy pulls the
 * destination into every cache level and evicts the data the solver is about to use; at
 * hang-512 that was 7 MB a frame, a fifth of the last-level cache (docs/performance.md,
 * session 15). */
#ifndef PLAIT_CORE_STREAM_COPY_H
#define PLAIT_CORE_STREAM_COPY_H

#include <stddef.h>

/* memcpy's result (the regions must not overlap), written around the caches where the
 * processor can (SSE2 non-temporal stores; a plain memcpy elsewhere). The stores are fenced
 * before it returns, so any thread that synchronises with the caller afterwards sees them. */
void plait_copy_streaming(void *destination, const void *source, size_t bytes);

#endif
