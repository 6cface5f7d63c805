/* core/stream_copy: the cache-bypassing copy gives memcpy's bytes for every size and every
 * alignment of either end, and writes nothing outside its destination. */
#include <criterion/criterion.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/stream_copy.h"

Test(stream_copy, gives_memcpys_bytes_at_every_size_and_alignment)
{
	enum { LARGEST = 3 * 4096 + 200, GUARD = 64 };
	unsigned char *source = malloc(LARGEST + 64);
	unsigned char *destination = malloc(LARGEST + 64 + 2 * GUARD);
	cr_assert(source != NULL && destination != NULL);
	for (size_t k = 0; k < LARGEST + 64; ++k) {
		source[k] = (unsigned char)(k * 131u + 7u);
	}
	/* Sizes around the streaming threshold (4096) and around the 64-byte blocks and the head
	 * that aligns the destination. */
	const size_t sizes[] = {0,    1,    15,   16,        17,        63,    64,     65,
	                        4095, 4096, 4097, 4096 + 15, 4096 + 63, 10000, LARGEST};
	for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; ++s) {
		for (size_t from = 0; from < 16; from += 3) {
			for (size_t to = 0; to < 16; ++to) {
				memset(destination, 0xA5, LARGEST + 64 + 2 * GUARD);
				plait_copy_streaming(destination + GUARD + to, source + from, sizes[s]);
				cr_assert(memcmp(destination + GUARD + to, source + from, sizes[s]) == 0,
				          "size %zu, source offset %zu, destination offset %zu", sizes[s], from, to);
				for (size_t k = 0; k < GUARD + to; ++k) {
					cr_assert_eq(destination[k], 0xA5, "wrote before the destination (size %zu)", sizes[s]);
				}
				for (size_t k = GUARD + to + sizes[s]; k < LARGEST + 64 + 2 * GUARD; ++k) {
					cr_assert_eq(destination[k], 0xA5, "wrote past the destination (size %zu)", sizes[s]);
				}
			}
		}
	}
	free(source);
	free(destination);
}
