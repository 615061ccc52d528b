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
  return mallopt(M_MMAP_THRESHOLD, static_cast<int>(std::min(bytes, kMax))) == 1;
}

}  // namespace slamaware
