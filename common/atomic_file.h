#pragma once
// Files that must never be seen half-written (maps, models; docs/architecture.md §6), and the
// checksum that tells a damaged file from a good one.
#include <cstddef>
#include <cstdint>
#include <string>

namespace slamaware {

/// Writes `size` bytes to `path` atomically: a temporary file beside it (path + ".tmp.<pid>"),
/// write, fsync, rename over `path`, fsync of the folder. A reader (or a process killed at any
/// moment) sees the old file or the new one, never a mix; a crash may leave the temporary file
/// behind. Creates the parent folders. Throws std::runtime_error naming `path` on failure.
void writeFileAtomic(const std::string& path, const void* data, size_t size);

/// CRC-32 (IEEE 802.3 polynomial, as zlib and PNG) of a byte range, continuing from `crc` (0 to
/// start): crc32(b, n2, crc32(a, n1)) == crc32 of a followed by b.
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

}  // namespace slamaware
