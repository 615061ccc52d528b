// The codeword assignment of raw descriptors (WordScores): every kernel gives the same words bit
// for bit, they are the nearest codewords (a double-precision reference), ties go to the lower
// codeword, and a row without gradient is assigned from its R, G, B alone as from the whole row.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "procs/recognizer/word_scores.h"

using namespace slamaware::recognizer;

namespace {

struct Problem {
  Eigen::MatrixXf w;
  Eigen::RowVectorXf bias;
  std::vector<std::vector<float>> rows;
  std::vector<const float*> pointers;
};

// K codewords; rows like real features: SIFT parts in [0, 0.3] (every third row without gradient,
// all zero), R, G, B in [0, 1].
Problem randomProblem(int k, int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> normal(0.0F, 1.0F);
  std::uniform_real_distribution<float> uniform(0.0F, 1.0F);
  Problem p;
  p.w.resize(kFeatureDims, k);
  for (int d = 0; d < kFeatureDims; ++d)
    for (int c = 0; c < k; ++c) p.w(d, c) = normal(rng);
  p.bias.resize(k);
  for (int c = 0; c < k; ++c) p.bias[c] = normal(rng);
  for (int i = 0; i < n; ++i) {
    std::vector<float> row(kFeatureDims, 0.0F);
    if (i % 3 != 0)
      for (int d = 0; d < kSiftDims; ++d) row[static_cast<size_t>(d)] = 0.3F * uniform(rng);
    for (int d = kSiftDims; d < kFeatureDims; ++d) row[static_cast<size_t>(d)] = uniform(rng);
    p.rows.push_back(std::move(row));
  }
  for (const auto& r : p.rows) p.pointers.push_back(r.data());
  return p;
}

std::vector<int16_t> assignWith(const Problem& p, WordScores::Kernel kernel, int first = 0) {
  std::vector<int16_t> words(p.rows.size(), -1);
  WordScores(p.w, p.bias)
      .assign(p.pointers.data(), static_cast<int64_t>(p.rows.size()), words.data(), first, kernel);
  return words;
}

}  // namespace

TEST(WordScores, KernelsAgreeBitForBit) {
  if (!WordScores::available(WordScores::Kernel::kAvx512))
    GTEST_SKIP() << "this CPU has no AVX-512F: only the portable kernel runs here";
  // 64 codewords (the shipped vocabulary), fewer than a register block, and several blocks; row
  // counts not a multiple of the four rows the AVX-512 kernel takes at a time.
  for (int k : {64, 7, 37, 150}) {
    const Problem p = randomProblem(k, 1003, static_cast<uint32_t>(k));
    EXPECT_EQ(assignWith(p, WordScores::Kernel::kPortable),
              assignWith(p, WordScores::Kernel::kAvx512))
        << k << " codewords";
  }
}

TEST(WordScores, WordsAreTheNearestCodewords) {
  for (int k : {64, 37, 150}) {
    const Problem p = randomProblem(k, 2000, 100 + static_cast<uint32_t>(k));
    const std::vector<int16_t> words = assignWith(p, WordScores::Kernel::kAuto);
    int checked = 0;
    for (size_t i = 0; i < p.rows.size(); ++i) {
      // Reference in double; rows whose two best scores are within float rounding are skipped.
      std::vector<double> s(static_cast<size_t>(k));
      for (int c = 0; c < k; ++c) {
        double acc = 0;
        for (int d = 0; d < kFeatureDims; ++d)
          acc += double{p.rows[i][static_cast<size_t>(d)]} * p.w(d, c);
        s[static_cast<size_t>(c)] = acc - p.bias[c];
      }
      int best = 0;
      for (int c = 1; c < k; ++c)
        if (s[static_cast<size_t>(c)] > s[static_cast<size_t>(best)]) best = c;
      double second = -1e300;
      for (int c = 0; c < k; ++c)
        if (c != best) second = std::max(second, s[static_cast<size_t>(c)]);
      if (s[static_cast<size_t>(best)] - second < 1e-4) continue;
      ++checked;
      ASSERT_EQ(words[i], best) << "row " << i << ", " << k << " codewords";
    }
    EXPECT_GT(checked, 1900) << k << " codewords";
  }
}

TEST(WordScores, TiesGoToTheLowerCodewordAndFlatRowsNeedOnlyTheirColour) {
  Problem p = randomProblem(40, 401, 7);
  // Codewords 5 and 30 identical, and the best for every row: 5 wins everywhere.
  p.w.col(30) = p.w.col(5);
  p.bias[30] = p.bias[5] = -1e3F;
  for (auto kernel : {WordScores::Kernel::kPortable, WordScores::Kernel::kAvx512}) {
    if (!WordScores::available(kernel)) continue;
    for (int16_t w : assignWith(p, kernel)) EXPECT_EQ(w, 5);
  }
  // Rows without gradient: starting the sums at their R, G, B changes no word.
  Problem flat = randomProblem(64, 300, 8);
  Problem only_flat;
  only_flat.w = flat.w;
  only_flat.bias = flat.bias;
  for (size_t i = 0; i < flat.rows.size(); i += 3) only_flat.rows.push_back(flat.rows[i]);
  for (const auto& r : only_flat.rows) only_flat.pointers.push_back(r.data());
  EXPECT_EQ(assignWith(only_flat, WordScores::Kernel::kAuto, kSiftDims),
            assignWith(only_flat, WordScores::Kernel::kAuto, 0));
}

TEST(WordScores, RejectsBadShapes) {
  EXPECT_THROW(WordScores(Eigen::MatrixXf::Zero(kFeatureDims, 4), Eigen::RowVectorXf::Zero(5)),
               std::invalid_argument);
  EXPECT_THROW(WordScores(Eigen::MatrixXf::Zero(10, 4), Eigen::RowVectorXf::Zero(4)),
               std::invalid_argument);
  const WordScores w(Eigen::MatrixXf::Zero(kFeatureDims, 4), Eigen::RowVectorXf::Zero(4));
  int16_t word = 0;
  const float row[kFeatureDims] = {};
  const float* rows[1] = {row};
  EXPECT_THROW(w.assign(rows, 1, &word, kFeatureDims), std::invalid_argument);
}
