#include "procs/slam/map/frame.h"

#include <algorithm>
#include <cmath>

#include "procs/slam/map/map_point.h"

namespace slamaware::slam {

Intrinsics::Intrinsics(const CameraModel& cam, const ScalePyramid& pyr)
    : fx(cam.fx()),
      fy(cam.fy()),
      cx(cam.cx()),
      cy(cam.cy()),
      max_x(cam.width() - 1),
      max_y(cam.height() - 1),
      pyramid(pyr) {}

Eigen::Matrix3d Intrinsics::K() const {
  Eigen::Matrix3d K;
  K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

FrameFeatures::FrameFeatures(OrbFeatures orb, std::shared_ptr<const Intrinsics> intr)
    : keypoints(std::move(orb.keypoints)),
      descriptors(std::move(orb.descriptors)),
      intrinsics(std::move(intr)) {
  const Intrinsics& in = *intrinsics;
  px.resize(keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i)
    px[i] = Eigen::Vector2d(keypoints[i].pt.x, keypoints[i].pt.y);
  grid_cols_ = std::max(1, static_cast<int>(std::ceil((in.max_x - in.min_x + 1) / kCellPx)));
  grid_rows_ = std::max(1, static_cast<int>(std::ceil((in.max_y - in.min_y + 1) / kCellPx)));
  grid_.assign(static_cast<size_t>(grid_cols_) * grid_rows_, {});
  for (size_t i = 0; i < px.size(); ++i) {
    const int c = static_cast<int>(std::floor((px[i].x() - in.min_x) / kCellPx));
    const int r = static_cast<int>(std::floor((px[i].y() - in.min_y) / kCellPx));
    if (c < 0 || r < 0 || c >= grid_cols_ || r >= grid_rows_) continue;
    grid_[static_cast<size_t>(r) * grid_cols_ + c].push_back(static_cast<int>(i));
  }
}

std::vector<int> FrameFeatures::inArea(double x, double y, double r, int min_level,
                                       int max_level) const {
  std::vector<int> out;
  const Intrinsics& in = *intrinsics;
  const int c0 = std::max(0, static_cast<int>(std::floor((x - r - in.min_x) / kCellPx)));
  const int c1 =
      std::min(grid_cols_ - 1, static_cast<int>(std::floor((x + r - in.min_x) / kCellPx)));
  const int r0 = std::max(0, static_cast<int>(std::floor((y - r - in.min_y) / kCellPx)));
  const int r1 =
      std::min(grid_rows_ - 1, static_cast<int>(std::floor((y + r - in.min_y) / kCellPx)));
  if (c0 > c1 || r0 > r1) return out;
  for (int row = r0; row <= r1; ++row) {
    for (int col = c0; col <= c1; ++col) {
      for (int i : grid_[static_cast<size_t>(row) * grid_cols_ + col]) {
        const int l = keypoints[i].octave;
        if (min_level >= 0 && l < min_level) continue;
        if (max_level >= 0 && l > max_level) continue;
        if (std::abs(px[i].x() - x) <= r && std::abs(px[i].y() - y) <= r) out.push_back(i);
      }
    }
  }
  return out;
}

void Frame::resetMatches() {
  points.assign(size(), nullptr);
  outlier.assign(size(), false);
}

int Frame::countInliers() const {
  int n = 0;
  for (int i = 0; i < size(); ++i) n += points[i] && !outlier[i];
  return n;
}

}  // namespace slamaware::slam
