// ORB features: the requested number, spread over the whole image (the quadtree), and
// descriptors that survive an in-plane rotation (oriented BRIEF): most matches between an image
// and its rotated copy land where the rotation says.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <set>

#include "procs/slam/features/orb_extractor.h"
#include "procs/slam/map/frame.h"
#include "procs/slam/matching/matcher.h"

using namespace slamaware;
using namespace slamaware::slam;

namespace {
cv::Mat texturedImage(uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat acc(480, 640, CV_32F, cv::Scalar(0));
  for (int scale : {3, 9, 27}) {
    cv::Mat small(480 / scale, 640 / scale, CV_32F);
    rng.fill(small, cv::RNG::UNIFORM, 0, 255);
    cv::Mat big;
    cv::resize(small, big, acc.size(), 0, 0, cv::INTER_CUBIC);
    acc += big / 3;
  }
  cv::Mat out;
  acc.convertTo(out, CV_8U);
  return out;
}
}  // namespace

TEST(OrbExtractor, GivesTheRequestedNumberSpreadOverTheImage) {
  OrbOptions opt;
  const OrbExtractor ex(opt);
  const OrbFeatures f = ex.extract(texturedImage(1));
  EXPECT_GT(static_cast<int>(f.keypoints.size()), 0.9 * opt.num_features);
  EXPECT_LE(static_cast<int>(f.keypoints.size()), opt.num_features + opt.num_levels);
  EXPECT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
  // Every cell of a 4 x 4 grid over the image holds features.
  int cells[4][4] = {};
  for (const auto& kp : f.keypoints)
    ++cells[static_cast<int>(kp.pt.y * 4 / 480)][static_cast<int>(kp.pt.x * 4 / 640)];
  for (auto& row : cells)
    for (int c : row) EXPECT_GT(c, opt.num_features / 16 / 3);
  // Several pyramid levels are used.
  std::set<int> levels;
  for (const auto& kp : f.keypoints) levels.insert(kp.octave);
  EXPECT_GE(levels.size(), 6u);
}

TEST(OrbExtractor, DescriptorsSurviveAnInPlaneRotation) {
  const cv::Mat image = texturedImage(2);
  const cv::Point2f center(319.5f, 239.5f);
  const double angle_deg = 30;
  const cv::Mat R = cv::getRotationMatrix2D(center, angle_deg, 1.0);
  cv::Mat rotated;
  cv::warpAffine(image, rotated, R, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  const OrbExtractor ex{OrbOptions()};
  auto intrinsics =
      std::make_shared<Intrinsics>(CameraModel(640, 480, 500, 500, 319.5, 239.5), ex.pyramid());
  const FrameFeatures a(ex.extract(image), intrinsics), b(ex.extract(rotated), intrinsics);
  std::vector<int> all(a.size());
  for (int i = 0; i < a.size(); ++i) all[i] = i;
  const Matches m = matchBruteForce(a, all, b, 0.8, kMatchDistanceHigh, true);
  ASSERT_GT(m.size(), 200u);
  int correct = 0;
  for (const auto& [i, j] : m) {
    const cv::Point2f p = a.keypoints[i].pt;
    const cv::Point2f q(static_cast<float>(R.at<double>(0, 0) * p.x + R.at<double>(0, 1) * p.y +
                                           R.at<double>(0, 2)),
                        static_cast<float>(R.at<double>(1, 0) * p.x + R.at<double>(1, 1) * p.y +
                                           R.at<double>(1, 2)));
    correct += cv::norm(q - b.keypoints[j].pt) < 3.0 * ex.pyramid().scale[a.keypoints[i].octave];
  }
  EXPECT_GT(correct, 0.9 * m.size());
}

TEST(OrbExtractor, ThreadsDoNotChangeTheFeatures) {
  const cv::Mat image = texturedImage(3);
  OrbOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const OrbFeatures a = OrbExtractor(one).extract(image), b = OrbExtractor(two).extract(image);
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (size_t i = 0; i < a.keypoints.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].pt, b.keypoints[i].pt);
    EXPECT_EQ(a.keypoints[i].angle, b.keypoints[i].angle);
  }
  EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0);
}
