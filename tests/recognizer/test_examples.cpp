// The trainer's example store: rows survive half precision, appends, filtering and selection
// across block boundaries with their labels and groups, and a growing set never holds more than
// one block of unused room (one doubling of a single buffer of rows ran a trainer out of memory).
#include <gtest/gtest.h>

#include <vector>

#include "procs/recognizer/classifier.h"

using namespace slamaware;

namespace {

// Row i: values that half precision holds exactly (multiples of 1/8 under 256), distinct per row.
std::vector<float> rowOf(int64_t i, int64_t dims) {
  std::vector<float> x(static_cast<size_t>(dims));
  for (int64_t d = 0; d < dims; ++d) x[static_cast<size_t>(d)] = static_cast<float>((i * 7 + d) % 2000) / 8.f;
  return x;
}

void expectRow(const ExampleSet& s, int64_t at, int64_t i) {
  std::vector<float> got(static_cast<size_t>(s.dims()));
  s.get(at, got.data());
  EXPECT_EQ(got, rowOf(i, s.dims())) << "row " << at << " should hold example " << i;
  EXPECT_EQ(s.label(at), static_cast<int>(i % 5));
  EXPECT_EQ(s.group(at), static_cast<int>(i));
}

ExampleSet filled(int64_t n, int64_t dims) {
  ExampleSet s(dims);
  for (int64_t i = 0; i < n; ++i) s.add(rowOf(i, dims).data(), static_cast<int>(i % 5), static_cast<int>(i));
  return s;
}

}  // namespace

TEST(ExampleSet, RowsLabelsAndGroupsSurviveAcrossBlocks) {
  const int64_t dims = 37, n = 3 * ExampleSet::kRowsPerBlock + 5;
  const ExampleSet s = filled(n, dims);
  ASSERT_EQ(s.size(), n);
  for (int64_t i = 0; i < n; ++i) expectRow(s, i, i);
}

TEST(ExampleSet, AppendFilterAndSelectKeepTheRightRows) {
  const int64_t dims = 19, n = 2 * ExampleSet::kRowsPerBlock + 17;
  ExampleSet a = filled(n, dims);
  ExampleSet tail(dims);
  for (int64_t i = n; i < 2 * n; ++i) tail.add(rowOf(i, dims).data(), static_cast<int>(i % 5), static_cast<int>(i));
  a.append(tail);
  ASSERT_EQ(a.size(), 2 * n);
  for (int64_t i = 0; i < 2 * n; ++i) expectRow(a, i, i);

  const ExampleSet thirds = a.select([](int64_t i) { return i % 3 == 0; });
  ASSERT_EQ(thirds.size(), (2 * n + 2) / 3);
  for (int64_t k = 0; k < thirds.size(); ++k) expectRow(thirds, k, 3 * k);

  a.filter([](int64_t i) { return i % 3 != 0; });
  ASSERT_EQ(a.size(), 2 * n - thirds.size());
  int64_t k = 0;
  for (int64_t i = 0; i < 2 * n; ++i)
    if (i % 3 != 0) expectRow(a, k++, i);
  // Filtering releases the blocks it emptied.
  EXPECT_LE(a.allocatedBytes(), a.bytes() + ExampleSet::kRowsPerBlock * dims * sizeof(uint16_t));

  ExampleSet other(dims + 1);
  EXPECT_THROW(a.append(other), std::invalid_argument);
}

TEST(ExampleSet, AGrowingSetHoldsAtMostOneBlockOfUnusedRoom) {
  const int64_t dims = 1000;
  const size_t block = ExampleSet::kRowsPerBlock * dims * sizeof(uint16_t);
  ExampleSet s(dims);
  std::vector<float> x(static_cast<size_t>(dims), 0.5f);
  for (int64_t i = 0; i < 10 * ExampleSet::kRowsPerBlock + 1; ++i) {
    s.add(x.data(), 0);
    ASSERT_LE(s.allocatedBytes(), s.bytes() + block) << "after " << i + 1 << " rows";
  }
  EXPECT_EQ(s.bytes(), static_cast<size_t>(s.size() * dims) * sizeof(uint16_t));
}
