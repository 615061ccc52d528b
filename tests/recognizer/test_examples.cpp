// The trainer's example store: rows survive the 8-bit block-sparse storage (zero blocks exactly,
// the others within half a quantisation step), appends, in-place filtering and selection across
// chunk boundaries with their labels, groups and weights, and a growing set never holds more than
// one chunk of unused room (one doubling of a single buffer of rows ran a trainer out of memory),
// and a small set takes the memory its rows fill, not a whole chunk.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <memory>
#include <vector>

#include "procs/recognizer/example_set.h"
#include "procs/supervisor/proc_stats.h"

using namespace slamaware;
using namespace slamaware::recognizer;

namespace {

constexpr int64_t kBlock = 8;

// Row i: every third block zero, the others distinct per row and block.
std::vector<float> rowOf(int64_t i, int64_t dims) {
  std::vector<float> x(static_cast<size_t>(dims));
  for (int64_t d = 0; d < dims; ++d) {
    const int64_t b = d / kBlock;
    x[static_cast<size_t>(d)] =
        (b + i) % 3 == 0
            ? 0.f
            : static_cast<float>(std::sin(0.37 * static_cast<double>(i * 131 + d)) * (1 + b % 4));
  }
  return x;
}

void expectRow(const ExampleSet& s, int64_t at, int64_t i) {
  const std::vector<float> want = rowOf(i, s.dims());
  std::vector<float> got(static_cast<size_t>(s.dims()));
  s.get(at, got.data());
  for (int64_t b = 0; b < s.dims() / kBlock; ++b) {
    float m = 0;
    for (int64_t d = b * kBlock; d < (b + 1) * kBlock; ++d)
      m = std::max(m, std::fabs(want[static_cast<size_t>(d)]));
    for (int64_t d = b * kBlock; d < (b + 1) * kBlock; ++d) {
      if (m == 0) {
        ASSERT_EQ(got[static_cast<size_t>(d)], 0.f) << "row " << at << " value " << d;
      } else {
        ASSERT_NEAR(got[static_cast<size_t>(d)], want[static_cast<size_t>(d)], m / 254.f * 1.0001f)
            << "row " << at << " should hold example " << i << " (value " << d << ")";
      }
    }
  }
  EXPECT_EQ(s.label(at), static_cast<int>(i % 5));
  EXPECT_EQ(s.group(at), static_cast<int>(i));
  EXPECT_EQ(s.domain(at), static_cast<int>(i % 2));
  EXPECT_EQ(s.weight(at), static_cast<float>(1 + i % 3));
}

void addRow(ExampleSet* s, int64_t i) {
  s->add(rowOf(i, s->dims()).data(), static_cast<int>(i % 5), static_cast<int>(i),
         static_cast<int>(i % 2), static_cast<float>(1 + i % 3));
}

// Rows of 4,000 values fill a chunk with about 16 MB / 3 kB rows: n rows span several chunks.
ExampleSet filled(int64_t first, int64_t n, int64_t dims) {
  ExampleSet s(dims, kBlock);
  for (int64_t i = first; i < first + n; ++i) addRow(&s, i);
  return s;
}

}  // namespace

TEST(ExampleSet, RowsKeepTheirValuesLabelsGroupsAndWeights) {
  const int64_t dims = 4000, n = 12000;
  const ExampleSet s = filled(0, n, dims);
  ASSERT_EQ(s.size(), n);
  ASSERT_GT(s.allocatedBytes(), ExampleSet::kChunkBytes) << "the rows should span several chunks";
  for (int64_t i = 0; i < n; i += 7) expectRow(s, i, i);
  // Only the non-zero blocks are held: a third of them are zero here.
  std::vector<int32_t> index;
  std::vector<float> values;
  EXPECT_EQ(s.blocks(1, &index, &values), 334);  // blocks b with (b + 1) % 3 != 0, of 500
  EXPECT_EQ(values.size(), 334u * kBlock);
  EXPECT_EQ(index[0], 0);
  EXPECT_EQ(index[1], 1);
  EXPECT_EQ(index[2], 3);
  // Per non-zero block 8 one-byte values and 8 bytes of index and scale, 4 bytes per row.
  EXPECT_LE(s.bytes(), static_cast<size_t>(n) * (4 + 334 * (kBlock + 8)));
}

TEST(ExampleSet, AppendFilterAndSelectKeepTheRightRows) {
  const int64_t dims = 4000, n = 7000;
  ExampleSet a = filled(0, n, dims);
  a.append(filled(n, n, dims));
  ASSERT_EQ(a.size(), 2 * n);
  for (int64_t i = 0; i < 2 * n; i += 11) expectRow(a, i, i);

  const ExampleSet thirds = a.select([](int64_t i) { return i % 3 == 0; });
  ASSERT_EQ(thirds.size(), (2 * n + 2) / 3);
  for (int64_t k = 0; k < thirds.size(); k += 5) expectRow(thirds, k, 3 * k);

  const size_t before = a.allocatedBytes();
  a.filter([](int64_t i) { return i % 3 != 0; });
  ASSERT_EQ(a.size(), 2 * n - thirds.size());
  int64_t k = 0;
  for (int64_t i = 0; i < 2 * n; ++i)
    if (i % 3 != 0) {
      if (k % 5 == 0) expectRow(a, k, i);
      ++k;
    }
  // Filtering releases the chunks it emptied.
  EXPECT_LT(a.allocatedBytes(), before);
  EXPECT_LE(a.allocatedBytes(),
            a.bytes() + ExampleSet::kChunkBytes +
                (a.allocatedBytes() / ExampleSet::kChunkBytes) * a.maxRowBytes());

  a.append(a);  // appending a set to itself doubles it
  ASSERT_EQ(a.size(), 2 * k);
  expectRow(a, k + 1, 2);

  EXPECT_THROW(a.append(ExampleSet(dims + kBlock, kBlock)), std::invalid_argument);
  EXPECT_THROW(ExampleSet(10, 3), std::invalid_argument);
}

TEST(ExampleSet, AGrowingSetHoldsAtMostOneChunkOfUnusedRoom) {
  const int64_t dims = 100000;
  ExampleSet s(dims, 80);
  std::vector<float> x(static_cast<size_t>(dims), 0.5f);
  for (int64_t i = 0; i < 500; ++i) {
    s.add(x.data(), 0);
    const size_t chunks = s.allocatedBytes() / ExampleSet::kChunkBytes;
    ASSERT_LE(s.allocatedBytes(), s.bytes() + ExampleSet::kChunkBytes + chunks * s.maxRowBytes())
        << "after " << i + 1 << " rows";
  }
  EXPECT_EQ(s.bytes(), 500 * s.maxRowBytes());
}

namespace {

// Resident bytes of this process, as the supervisor samples every process.
int64_t residentBytes() { return 1024 * supervisor::sampleProcess(getpid()).value().rss_kb; }

}  // namespace

// A model's few exemplars live in one chunk: zeroing the chunk when it was allocated made every
// model load touch 16 MB (the fuzzer's model loads ran at 170-360 a second instead of thousands).
TEST(ExampleSet, ASmallSetTakesThePagesItsRowsFillNotAWholeChunk) {
  const int64_t dims = 4096;
  const std::vector<float> x = rowOf(1, dims);
  // Without clearing, the sets take a few pages each (under AddressSanitizer also the shadow of
  // what they write). With it they take 16 MB each, of which glibc may have kept at most 64 MB
  // resident from earlier frees (twice its largest mmap threshold): 192 MB or more for 16 sets.
  constexpr int kSets = 16;
  std::vector<std::unique_ptr<ExampleSet>> sets;
  const int64_t before = residentBytes();
  for (int i = 0; i < kSets; ++i) {
    sets.push_back(std::make_unique<ExampleSet>(dims, kBlock));
    sets.back()->add(x.data(), 0);
    ASSERT_EQ(sets.back()->allocatedBytes(), ExampleSet::kChunkBytes);
  }
  const int64_t grown = residentBytes() - before;
  EXPECT_LT(grown, 4 * static_cast<int64_t>(ExampleSet::kChunkBytes))
      << "RSS grew by " << grown / 1024 << " kB for " << kSets << " sets of one row of "
      << sets[0]->bytes() << " B";
}
