// Our dense SIFT equals VLFeat's vl_dsift (flat window) on the same image and frames, and the
// feature extractor gives a grid point the same 131-D feature whatever region is computed.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "procs/recognizer/dense_features.h"
#include "procs/recognizer/dense_sift.h"
#include "tests/recognizer/synthetic_data.h"

using namespace slamaware;
using namespace slamaware::recognizer;

namespace {

cv::Mat greyFloat(const cv::Mat& bgr, double sigma) {
  cv::Mat g, f;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  g.convertTo(f, CV_32F, 1.0 / 255);
  if (sigma > 0) cv::GaussianBlur(f, f, cv::Size(0, 0), sigma);
  return f;
}

}  // namespace

// Every bin size the encoder uses (6 puts bin centres on a 2 px pitch, the others on 4 px).
class DenseSiftVsVlfeat : public ::testing::TestWithParam<int> {};

TEST_P(DenseSiftVsVlfeat, DescriptorsAndNormsMatch) {
  const int bin = GetParam();
  const cv::Mat image = greyFloat(test::texturedFrame(3, 200, 160), 0.8);
  DsiftGeometry g;
  g.bin = bin;
  g.step = 4;
  g.min_x = bin + 3;  // keeps every frame's support inside the image
  g.min_y = bin + 1;
  g.nx = (image.cols - 2 * g.min_x - 3 * bin) / g.step;
  g.ny = (image.rows - 2 * g.min_y - 3 * bin) / g.step;
  ASSERT_GT(g.nx, 5);
  ASSERT_GT(g.ny, 5);
  const size_t n = static_cast<size_t>(g.nx) * g.ny;
  std::vector<float> ours(n * 128), theirs(n * 128), our_norms(n), their_norms(n);
  DsiftOutput out;
  out.descriptors = ours.data();
  out.norms = our_norms.data();
  denseSiftFlat(image.ptr<float>(), image.cols, image.rows, g, out);
  denseSiftVlfeat(image.ptr<float>(), image.cols, image.rows, g, theirs.data(), 128,
                  their_norms.data());
  double max_diff = 0, max_norm_rel = 0, max_value = 0;
  for (size_t i = 0; i < ours.size(); ++i) {
    max_diff = std::max(max_diff, static_cast<double>(std::fabs(ours[i] - theirs[i])));
    max_value = std::max(max_value, static_cast<double>(theirs[i]));
  }
  for (size_t p = 0; p < n; ++p)
    max_norm_rel =
        std::max(max_norm_rel, std::fabs(our_norms[p] - their_norms[p]) / (their_norms[p] + 1e-6));
  // Descriptors are unit vectors with elements up to ~0.3; VLFeat's own float filtering (running
  // sums over whole columns) differs from ours in the 5th decimal at most.
  EXPECT_GT(max_value, 0.1);
  EXPECT_LT(max_diff, 2e-4) << "bin " << bin;
  EXPECT_LT(max_norm_rel, 1e-3) << "bin " << bin;
}

INSTANTIATE_TEST_SUITE_P(BinSizes, DenseSiftVsVlfeat, ::testing::Values(4, 6, 8, 12));

TEST(DenseSift, RefusesFramesReachingOutOfTheImage) {
  std::vector<float> image(64 * 64, 0.5f), d(128), norm(1);
  DsiftGeometry g;
  g.bin = 8;
  g.min_x = 2;  // the first bin needs 7 px on its left
  g.min_y = 10;
  g.nx = g.ny = 1;
  DsiftOutput out;
  out.descriptors = d.data();
  out.norms = norm.data();
  EXPECT_THROW(denseSiftFlat(image.data(), 64, 64, g, out), std::invalid_argument);
  g.min_x = 10;
  EXPECT_NO_THROW(denseSiftFlat(image.data(), 64, 64, g, out));
  out.tail_dims = 3;  // no room after the 128 elements, and no tail
  EXPECT_THROW(denseSiftFlat(image.data(), 64, 64, g, out), std::invalid_argument);
}

TEST(DenseFeatures, GridPointFeatureDoesNotDependOnTheRegionComputed) {
  FeatureParams params;
  DenseFeatureExtractor ex(params);
  ex.setImage(test::texturedFrame(5, 320, 240));
  const CellRect all = ex.imageCells();
  EXPECT_EQ(all.width(), 40);
  EXPECT_EQ(all.height(), 30);
  FeatureGrid whole, part;
  ex.extract(all, &whole);
  const CellRect sub{7, 3, 19, 12};  // touches nothing
  ex.extract(sub, &part);
  ASSERT_EQ(part.nx, 12 * 2);
  ASSERT_EQ(part.ny, 9 * 2);
  double max_diff = 0;
  for (int t = 0; t < part.scales; ++t)
    for (int j = 0; j < part.ny; ++j)
      for (int i = 0; i < part.nx; ++i) {
        const float* a = part.features.row(part.rowOf(i, j, t));
        const float* b = whole.features.row(whole.rowOf(i + sub.u0 * 2, j + sub.v0 * 2, t));
        for (int c = 0; c < kFeatureDims; ++c)
          max_diff = std::max(max_diff, static_cast<double>(std::fabs(a[c] - b[c])));
      }
  EXPECT_LT(max_diff, 1e-6);
  // The mean RGB columns hold colours in 0..1 and the SIFT part unit vectors.
  const float* f = whole.features.row(whole.rowOf(10, 10, 0));
  double norm = 0;
  for (int c = 0; c < kSiftDims; ++c) norm += f[c] * f[c];
  EXPECT_NEAR(std::sqrt(norm), 1.0, 1e-3);
  for (int c = kSiftDims; c < kFeatureDims; ++c) {
    EXPECT_GE(f[c], 0.f);
    EXPECT_LE(f[c], 1.f);
  }
}

TEST(DenseFeatures, FlatPatchesHaveNoSiftPart) {
  FeatureParams params;
  DenseFeatureExtractor ex(params);
  cv::Mat flat(64, 64, CV_8UC3, cv::Scalar(30, 60, 90));  // B, G, R
  ex.setImage(flat);
  FeatureGrid g;
  ex.extract(ex.imageCells(), &g);
  ASSERT_GT(g.features.rows(), 0);
  for (int64_t r = 0; r < g.features.rows(); ++r) {
    const float* f = g.features.row(r);
    for (int c = 0; c < kSiftDims; ++c) ASSERT_EQ(f[c], 0.f);
    EXPECT_NEAR(f[kSiftDims + 0], 90 / 255.0, 1e-5);  // R
    EXPECT_NEAR(f[kSiftDims + 1], 60 / 255.0, 1e-5);  // G
    EXPECT_NEAR(f[kSiftDims + 2], 30 / 255.0, 1e-5);  // B
  }
}
