// VLAD of a toy descriptor set, computed by hand, against both encoders; the normalisations
// (signed square root, then L2 over the whole vector) and the pyramid geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "procs/recognizer/vlad.h"

using namespace slamaware;
using namespace slamaware::recognizer;

namespace {

// 4 x 4 pooling cells with one descriptor each, D = 2, K = 2 with codewords c0 = (0, 0) and
// c1 = (10, 0). All descriptors sit on c0 except four.
struct Toy {
  Vocabulary vocabulary;
  FrameCodes codes;
  MatrixRM y = MatrixRM::Zero(16, 2);  // descriptor of cell (i, j) in row 4 j + i
  std::vector<int16_t> words;
  Toy() {
    vocabulary.centers.resize(2, 2);
    vocabulary.centers << 0, 0, 10, 0;
    set(0, 0, 1, 2);   // -> c0, residual (1, 2)
    set(1, 0, 11, 0);  // -> c1, residual (1, 0)
    set(2, 1, -1, 1);  // -> c0, residual (-1, 1)
    set(3, 3, 9, 3);   // -> c1, residual (-1, 3)
    vocabulary.assign(y, &words);
    codes.reset(CellRect{0, 0, 4, 4}, 2);
    for (int r = 0; r < 16; ++r) {
      float* e = codes.addEntry(words[r], 1.f);
      for (int d = 0; d < 2; ++d) e[d] = y(r, d) - vocabulary.centers(words[r], d);
      codes.endCell();
    }
  }
  void set(int i, int j, float a, float b) { y.row(4 * j + i) << a, b; }
};

// Raw residual sums by hand: 21 cells x K = 2 x D = 2 (layout of vlad.h).
std::vector<float> handRawVlad() {
  std::vector<float> v(21 * 4, 0.f);
  auto put = [&](int cell, std::vector<float> x) {
    for (int i = 0; i < 4; ++i) v[cell * 4 + i] = x[i];
  };
  put(0, {0, 3, 0, 3});            // whole box: c0 (1,2)+(-1,1); c1 (1,0)+(-1,3)
  put(1, {1, 2, 1, 0});            // 2x2 cell (0,0)
  put(2, {-1, 1, 0, 0});           // 2x2 cell (1,0)
  put(3, {0, 0, 0, 0});            // 2x2 cell (0,1)
  put(4, {0, 0, -1, 3});           // 2x2 cell (1,1)
  put(5 + 0, {1, 2, 0, 0});        // 4x4 cell (0,0)
  put(5 + 1, {0, 0, 1, 0});        // 4x4 cell (1,0)
  put(5 + 4 + 2, {-1, 1, 0, 0});   // 4x4 cell (2,1)
  put(5 + 12 + 3, {0, 0, -1, 3});  // 4x4 cell (3,3)
  return v;
}

std::vector<float> signedSqrtL2(std::vector<float> v) {
  double sum = 0;
  for (float& x : v) {
    x = x < 0 ? -std::sqrt(-x) : std::sqrt(x);
    sum += static_cast<double>(x) * x;
  }
  for (float& x : v) x = static_cast<float>(x / std::sqrt(sum));
  return v;
}

}  // namespace

TEST(Vlad, ToyDescriptorsGiveTheHandComputedVector) {
  Toy toy;
  ASSERT_EQ(toy.words[1], 1);
  ASSERT_EQ(toy.words[4 * 3 + 3], 1);
  ASSERT_EQ(toy.words[4 * 1 + 2], 0);
  const std::vector<float> expected = signedSqrtL2(handRawVlad());
  // sum |raw| = 26, so e.g. the whole-box c0 y-component is sqrt(3) / sqrt(26).
  EXPECT_NEAR(expected[1], std::sqrt(3.0) / std::sqrt(26.0), 1e-7);
  const PyramidBox box = pyramidFromCells(CellRect{0, 0, 4, 4});
  std::vector<float> direct(expected.size()), flair(expected.size());
  DirectEncoder(toy.codes, toy.vocabulary).encode(box, direct.data());
  FlairEncoder f;
  f.build(toy.codes, toy.vocabulary, toy.codes.region);
  f.encode(box, flair.data());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(direct[i], expected[i], 1e-6) << "element " << i;
    EXPECT_NEAR(flair[i], expected[i], 1e-6) << "element " << i;
  }
}

TEST(Vlad, BoxSmallerThanThePyramidLeavesEmptyCellsZero) {
  Toy toy;
  // 2 x 2 pooling cells: the 4x4 boundaries are 1, 1, 2, 2, 3, so 4x4 columns/rows 0 and 2 are
  // empty and columns/rows 1 and 3 hold one pooling cell each.
  const PyramidBox box = pyramidFromCells(CellRect{1, 1, 3, 3});
  EXPECT_EQ(box.u[0], 1);
  EXPECT_EQ(box.u[1], 1);
  EXPECT_EQ(box.u[2], 2);
  EXPECT_EQ(box.u[3], 2);
  EXPECT_EQ(box.u[4], 3);
  std::vector<float> direct(21 * 4), flair(21 * 4);
  DirectEncoder(toy.codes, toy.vocabulary).encode(box, direct.data());
  FlairEncoder f;
  f.build(toy.codes, toy.vocabulary, toy.codes.region);
  f.encode(box, flair.data());
  // The only non-zero residual inside is (-1, 1) at pooling cell (2, 1) -> 4x4 cell (3, 1).
  std::vector<float> raw(21 * 4, 0.f);
  for (int cell : {0, 2, 5 + 4 * 1 + 3}) {
    raw[cell * 4 + 0] = -1;
    raw[cell * 4 + 1] = 1;
  }
  const std::vector<float> expected = signedSqrtL2(raw);
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(direct[i], expected[i], 1e-6) << i;
    EXPECT_NEAR(flair[i], expected[i], 1e-6) << i;
  }
}

TEST(Vlad, FinishZeroesEmptyBlocksThenSignedSqrtThenL2) {
  const int K = 2, D = 3;
  std::vector<float> v(21 * K * D, 0.f), counts(21 * K, 0.f);
  v[0] = 4;
  v[1] = -9;
  counts[0] = 2;  // block (cell 0, codeword 0) has descriptors
  v[3] = 1e-4f;   // block (cell 0, codeword 1): rounding noise, no descriptors
  finishVlad(v.data(), counts.data(), K, D);
  EXPECT_NEAR(v[0], 2 / std::sqrt(13.0), 1e-7);
  EXPECT_NEAR(v[1], -3 / std::sqrt(13.0), 1e-7);
  EXPECT_EQ(v[2], 0.f);
  EXPECT_EQ(v[3], 0.f);
  double norm = 0;
  for (float x : v) norm += static_cast<double>(x) * x;
  EXPECT_NEAR(norm, 1.0, 1e-6);
  // An all-zero vector stays zero (no division by zero).
  std::vector<float> z(21 * K * D, 0.f);
  finishVlad(z.data(), counts.data(), K, D);
  for (float x : z) EXPECT_EQ(x, 0.f);
}

TEST(Vlad, AssignmentPicksTheNearestCodewordAndTheLowerIndexOnTies) {
  Vocabulary voc;
  voc.centers.resize(3, 2);
  voc.centers << 0, 0, 2, 0, 0, 5;
  MatrixRM y(4, 2);
  y << 0.9, 0, 1.1, 0, 1.0, 0, 0, 2.6;
  std::vector<int16_t> w;
  voc.assign(y, &w);
  EXPECT_EQ(w, (std::vector<int16_t>{0, 1, 0, 2}));
}

TEST(Vlad, SnapBoxClipsRoundsAndKeepsTinyBoxes) {
  PyramidBox b;
  // 640 x 480 image, 8 px cells: 80 x 60 cells.
  ASSERT_TRUE(snapBox(13, 21, 100, 50, 640, 480, 8, &b));
  EXPECT_EQ(b.u[0], 2);   // 13 / 8 = 1.6 -> 2
  EXPECT_EQ(b.u[4], 14);  // 113 / 8 = 14.1 -> 14
  EXPECT_EQ(b.v[0], 3);   // 21 / 8 = 2.6 -> 3
  EXPECT_EQ(b.v[4], 9);   // 71 / 8 = 8.9 -> 9
  EXPECT_EQ(b.u[2], 2 + (2 * 12) / 4);
  // Partly outside: clipped to the image.
  ASSERT_TRUE(snapBox(-50, 400, 100, 200, 640, 480, 8, &b));
  EXPECT_EQ(b.u[0], 0);
  EXPECT_EQ(b.u[4], 6);
  EXPECT_EQ(b.v[4], 60);
  // Narrower than a cell: the cell under its centre.
  ASSERT_TRUE(snapBox(101, 101, 2, 3, 640, 480, 8, &b));
  EXPECT_EQ(b.u[0], 12);
  EXPECT_EQ(b.u[4], 13);
  // Refused: zero size, outside, not finite.
  EXPECT_FALSE(snapBox(10, 10, 0, 5, 640, 480, 8, &b));
  EXPECT_FALSE(snapBox(700, 10, 20, 20, 640, 480, 8, &b));
  EXPECT_FALSE(snapBox(-30, 10, 20, 20, 640, 480, 8, &b));
  EXPECT_FALSE(snapBox(std::nan(""), 10, 20, 20, 640, 480, 8, &b));
}
