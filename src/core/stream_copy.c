#include "core/stream_copy.h"

#include <stdint.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* Below this a copy is left to memcpy: the fence and the unaligned ends would cost more than
 * the cache lines they spare. */
#define STREAM_MIN_BYTES 4096

void plait_copy_streaming(void *destination, const void *source, size_t bytes)
{
#if defined(__SSE2__)
	if (bytes >= STREAM_MIN_BYTES) {
		unsigned char *to = destination;
		const unsigned char *from = source;
		/* Non-temporal stores need 16-byte aligned destinations: the head goes by memcpy. */
		size_t head = (16u - ((uintptr_t)to & 15u)) & 15u;
		memcpy(to, from, head);
		to += head;
		from += head;
		bytes -= head;
		size_t blocks = bytes / 64;
		for (size_t b = 0; b < blocks; ++b) {
			__m128i v0 = _mm_loadu_si128((const __m128i *)(const void *)(from + 0));
			__m128i v1 = _mm_loadu_si128((const __m128i *)(const void *)(from + 16));
			__m128i v2 = _mm_loadu_si128((const __m128i *)(const void *)(from + 32));
			__m128i v3 = _mm_loadu_si128((const __m128i *)(const void *)(from + 48));
			_mm_stream_si128((__m128i *)(void *)(to + 0), v0);
			_mm_stream_si128((__m128i *)(void *)(to + 16), v1);
			_mm_stream_si128((__m128i *)(void *)(to + 32), v2);
			_mm_stream_si128((__m128i *)(void *)(to + 48), v3);
			to += 64;
			from += 64;
		}
		memcpy(to, from, bytes - blocks * 64);
		/* Non-temporal stores are weakly ordered: without the fence another thread could read
		 * the destination before they land. */
		_mm_sfence();
		return;
	}
#endif
	memcpy(destination, source, bytes);
}
