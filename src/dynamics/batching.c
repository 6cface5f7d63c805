#include "dynamics/batching.h"

#include <string.h>

#define MAX_ARITY 4
#define MAX_WIDTH 16

int plait_batch_order(const plait_allocator *allocator, const int *vertices, int arity, int count, int width,
                      int window, int *order, int *batch_sizes)
{
	for (int k = 0; k < count; ++k) {
		order[k] = k;
		batch_sizes[k] = 1;
	}
	if (count <= 1 || arity > MAX_ARITY || width > MAX_WIDTH || width < 2) {
		return count;
	}
	bool *used = plait_alloc_zero(allocator, (size_t)count, sizeof(bool));
	if (used == NULL) {
		return -1;
	}
	int written = 0, oldest = 0, batches = 0;
	while (written < count) {
		while (used[oldest]) {
			++oldest;
		}
		int batch_vertices[MAX_WIDTH * MAX_ARITY];
		int batch_vertex_count = 0, batch_size = 0;
		int scanned = 0;
		for (int c = oldest; c < count && scanned < window && batch_size < width; ++c) {
			if (used[c]) {
				continue;
			}
			++scanned;
			const int *tuple = vertices + (size_t)c * (size_t)arity;
			bool independent = true;
			for (int a = 0; a < arity && independent; ++a) {
				for (int b = 0; b < batch_vertex_count; ++b) {
					if (batch_vertices[b] == tuple[a]) {
						independent = false;
						break;
					}
				}
			}
			if (!independent) {
				continue;
			}
			memcpy(batch_vertices + batch_vertex_count, tuple, sizeof(int) * (size_t)arity);
			batch_vertex_count += arity;
			used[c] = true;
			order[written++] = c;
			++batch_size;
		}
		batch_sizes[batches++] = batch_size;
	}
	plait_free(allocator, used);
	return batches;
}
