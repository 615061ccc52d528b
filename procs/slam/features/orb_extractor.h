#pragma once
// ORB features (oFAST corners + rotated BRIEF, Rublee et al. ICCV 2011) on an image pyramid,
// spread over the image as in ORB-SLAM: FAST runs per grid cell (with a lower threshold where a
// cell is weak) and a quadtree keeps the strongest corner of each of N regions.
#include <array>
#include <cstdint>
#include <cstring>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "procs/slam/slam_options.h"

namespace slamaware::slam {

/// Scales of the pyramid levels and the position noise of a feature found at each.
struct ScalePyramid {
  std::vector<double> scale;       ///< s^l: one level-l pixel is this many level-0 pixels
  std::vector<double> sigma2;      ///< (s^l)^2, px^2 at level 0: variance of a level-l position
  std::vector<double> inv_sigma2;  ///< 1 / sigma2
  double scale_factor = 1.2;
  double log_scale = 0;  ///< log(scale_factor)

  ScalePyramid() = default;
  ScalePyramid(double scale_factor, int levels);
  int levels() const { return static_cast<int>(scale.size()); }
  /// Level at which a point first seen at `max_distance` (the distance at which it would appear at
  /// level 0) is expected when seen from `distance` (ORB-SLAM's PredictScale), clamped to the
  /// pyramid.
  int predictLevel(double max_distance, double distance) const;
};

/// Keypoints and their descriptors.
struct OrbFeatures {
  std::vector<cv::KeyPoint>
      keypoints;        ///< level-0 pixels of the input image; octave = level, angle in deg
  cv::Mat descriptors;  ///< CV_8U, one row of 32 bytes (256 bits) per keypoint
};

class OrbExtractor {
 public:
  static constexpr int kDescriptorBytes = 32;
  static constexpr int kPatchRadius = 15;  ///< px, radius of the orientation and descriptor disk

  explicit OrbExtractor(const OrbOptions& options);
  /// Detects and describes up to options.num_features features in an 8-bit grey image.
  OrbFeatures extract(const cv::Mat& grey) const;
  const ScalePyramid& pyramid() const { return pyramid_; }

 private:
  void detectLevel(const cv::Mat& image, int level, std::vector<cv::KeyPoint>* out) const;
  /// Keypoints (level-0 coordinates) and descriptors of one pyramid level.
  void describeLevel(const cv::Mat& image, int level, std::vector<cv::KeyPoint>* keypoints,
                     cv::Mat* descriptors) const;

  OrbOptions options_;
  ScalePyramid pyramid_;
  std::vector<int> features_per_level_;
  std::vector<int> umax_;  ///< half-width of the orientation disk at each row offset
  std::vector<std::array<int8_t, 4>>
      pattern_;  ///< 256 point pairs (x1, y1, x2, y2) of the BRIEF tests
};

/// Hamming distance of two 32-byte descriptors. Inline: the matchers call it in their innermost
/// loops (the keyframe pairs' triangulation search compares every free feature with every other).
inline int descriptorDistance(const uint8_t* a, const uint8_t* b) {
  static_assert(OrbExtractor::kDescriptorBytes == 4 * sizeof(uint64_t), "four 64-bit words");
  uint64_t pa[4], pb[4];
  std::memcpy(pa, a, sizeof pa);
  std::memcpy(pb, b, sizeof pb);
  return __builtin_popcountll(pa[0] ^ pb[0]) + __builtin_popcountll(pa[1] ^ pb[1]) +
         __builtin_popcountll(pa[2] ^ pb[2]) + __builtin_popcountll(pa[3] ^ pb[3]);
}

}  // namespace slamaware::slam
