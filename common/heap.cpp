#include "common/heap.h"

#include <malloc.h>

#include <algorithm>

namespace slamaware {

std::optional<HeapUse> heapUse() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  const struct mallinfo2 m = mallinfo2();
  return HeapUse{m.uordblks + m.hblkhd, m.fordblks, m.hblkhd};
#else
  return std::nullopt;
#endif
}

bool mapBlocksApartFrom(size_t bytes) {
  constexpr size_t kMax = size_t{32} << 20;  // glibc: HEAP_MAX_SIZE / 2 on 64-bit systems
  const size_t threshold = std::min(bytes, kMax);
  // glibc's sliding threshold keeps freed memory at a heap's top up to twice the mmap threshold;
  // a threshold set by hand leaves the trim threshold at its 128 kB default, and then the buffers
  // a frame frees were handed back and faulted in again, zeroed, on the next frame.
  return mallopt(M_MMAP_THRESHOLD, static_cast<int>(threshold)) == 1 &&
         mallopt(M_TRIM_THRESHOLD, static_cast<int>(2 * threshold)) == 1;
}

}  // namespace slamaware
