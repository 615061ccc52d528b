#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "common/heap.h"

namespace slamaware {
namespace {

size_t mappedBytes() { return heapUse().value().mapped; }

// A buffer that is allocated, written and freed, as a process's large buffers are.
void useAndFree(size_t bytes) {
  auto* p = static_cast<char*>(std::malloc(bytes));
  ASSERT_NE(p, nullptr);
  std::memset(p, 1, bytes);
  std::free(p);
}

TEST(Heap, ABlockOverTheThresholdIsMappedApartEvenAfterALargerOneWasFreed) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator replaces glibc's, and its mmap threshold with it";
#else
  // What a process does first: a large buffer (a full map's cloud) freed. glibc's own threshold
  // then slides up to its size, and a later block of 8 MB would come from the heap.
  useAndFree(size_t{24} << 20);
  ASSERT_TRUE(mapBlocksApartFrom(size_t{1} << 20));
  const size_t before = mappedBytes();
  auto* block = static_cast<char*>(std::malloc(size_t{8} << 20));
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, size_t{8} << 20);
  EXPECT_GE(mappedBytes(), before + (size_t{8} << 20)) << "the 8 MB block came from the heap";
  std::free(block);
  EXPECT_EQ(mappedBytes(), before) << "the 8 MB block was not handed back when freed";
  // Below the threshold a block still comes from the heap (a frame's buffers are reused there).
  auto* small = static_cast<char*>(std::malloc(size_t{512} << 10));
  ASSERT_NE(small, nullptr);
  EXPECT_EQ(mappedBytes(), before);
  std::free(small);
#endif
}

TEST(Heap, AThresholdOverGlibcsLimitIsClampedNotRefused) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "AddressSanitizer's allocator replaces glibc's, and its mmap threshold with it";
#else
  EXPECT_TRUE(mapBlocksApartFrom(size_t{1} << 30));
  EXPECT_TRUE(mapBlocksApartFrom(size_t{128} << 10));
#endif
}

}  // namespace
}  // namespace slamaware
