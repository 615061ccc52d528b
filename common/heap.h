#pragma once
// Which blocks glibc maps on their own. A block at or over the mmap threshold gets its own
// mapping and goes back to the system when freed; a smaller one comes from the heap, whose freed
// pages stay with the process until a trim. By default the threshold slides up to the largest
// mapped block freed so far: after a process's first large buffer (a map's cloud, a
// re-clustering's arrays) every later one of that size comes from the heap and leaves touched
// pages behind, and the RSS a run settles at depends on the order of its frees
// (docs/experiments/slam.md and proposals.md, 2026-12-05).
#include <cstddef>
#include <optional>

namespace slamaware {

/// The heap as glibc sees it, in bytes.
struct HeapUse {
  size_t used = 0;    ///< held by the process: in the heap and in blocks mapped apart
  size_t free = 0;    ///< freed but kept by the allocator (RSS growing with it is glibc's)
  size_t mapped = 0;  ///< of `used`, in blocks mapped apart
};

/// glibc's `mallinfo2`; none on a C library without it (before glibc 2.33).
std::optional<HeapUse> heapUse();

/// Fixes the threshold at `bytes` (glibc's limits: at most 32 MiB, larger values are clamped):
/// blocks of `bytes` or more are mapped apart from then on, whatever was freed before; and, as
/// glibc's sliding threshold does, a heap keeps up to twice that freed at its top before handing
/// it back. Returns false if glibc refused.
bool mapBlocksApartFrom(size_t bytes);

}  // namespace slamaware
