#pragma once
// TUM RGB-D trajectory files: "t tx ty tz qx qy qz qw" per line, '#' comments.
#include <stdexcept>
#include <string>
#include <vector>

#include "common/geometry.h"

namespace slamaware {

struct TimedPose {
  double t = 0;  ///< s
  SE3 T_world_camera = SE3::Identity();
};

class TumError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads a TUM trajectory; throws TumError naming file and line on a malformed line.
std::vector<TimedPose> readTum(const std::string& path);
/// Writes a TUM trajectory (timestamps with microsecond precision, 9 significant digits for poses).
void writeTum(const std::string& path, const std::vector<TimedPose>& poses);
/// Pose of `poses` closest in time to t within max_dt, or nullptr.
const TimedPose* closestPose(const std::vector<TimedPose>& poses, double t, double max_dt);

}  // namespace slamaware
