/* Ordering constraints in batches of independent ones. Gauss-Seidel projects constraints one
 * after another; when consecutive constraints share a particle each waits for the previous
 * (a chain of sqrt and divide latencies). Grouping them into batches of `width` constraints that
 * share no particle, while keeping roughly the original sweep order (which carries corrections
 * from pins outward in one pass), lets the processor overlap a batch (and lets SIMD or threads
 * take it whole later). Pure and deterministic. */
#ifndef PLAIT_DYNAMICS_BATCHING_H
#define PLAIT_DYNAMICS_BATCHING_H

#include "core/alloc.h"

/* vertices holds count tuples of `arity` particle indices. Writes order[k] = the constraint to
 * put at position k, and batch_sizes[b] = the size of batch b (constraints of one batch share
 * no particle). Scans at most `window` pending constraints ahead of the oldest one. Returns the
 * number of batches, or -1 when out of memory. */
int plait_batch_order(const plait_allocator *allocator, const int *vertices, int arity, int count, int width,
                      int window, int *order, int *batch_sizes);

#endif
