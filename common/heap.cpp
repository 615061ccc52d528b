#include "common/heap.h"

#include <malloc.h>

#include <algorithm>

namespace slamaware {

bool mapBlocksApartFrom(size_t bytes) {
  constexpr size_t kMax = size_t{32} << 20;  // glibc: HEAP_MAX_SIZE / 2 on 64-bit systems
  return mallopt(M_MMAP_THRESHOLD, static_cast<int>(std::min(bytes, kMax))) == 1;
}

}  // namespace slamaware
