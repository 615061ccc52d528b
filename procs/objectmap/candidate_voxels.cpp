#include "procs/objectmap/candidate_voxels.h"

#include <algorithm>
#include <cmath>

namespace slamaware::objectmap {

double depthBandHalfWidth(const VoteBox& box, const CameraModel& camera,
                          const VotingOptions& options) {
  const double f = 0.5 * (camera.fx() + camera.fy());
  const double size = std::max(box.w, box.h) / f * box.median_depth;  // map units at that depth
  return std::max(options.depth_band * box.median_depth, options.depth_band_box * size);
}

std::vector<std::vector<VoxelKey>> voxelsInBoxes(const std::vector<OccupiedVoxel>& occupied,
                                                 const CameraModel& camera,
                                                 const SE3& T_world_camera,
                                                 const std::vector<VoteBox>& boxes,
                                                 const VotingOptions& options) {
  std::vector<std::vector<VoxelKey>> out(boxes.size());
  if (boxes.empty() || occupied.empty() || !camera.valid()) return out;
  const int cell = std::max(1, options.grid_cell_px);
  const int gw = (camera.width() + cell - 1) / cell, gh = (camera.height() + cell - 1) / cell;
  // Project every voxel once; bucket the ones in the image by grid cell.
  struct Projected {
    float u, v, z;
    uint32_t index;
  };
  std::vector<std::vector<Projected>> grid(static_cast<size_t>(gw) * static_cast<size_t>(gh));
  const SE3 T_camera_world = T_world_camera.inverse();
  const Eigen::Matrix3f R = T_camera_world.linear().cast<float>();
  const Eigen::Vector3f t = T_camera_world.translation().cast<float>();
  for (size_t i = 0; i < occupied.size(); ++i) {
    const Eigen::Vector3f p = R * occupied[i].centre + t;
    if (p.z() <= 1e-6f) continue;
    const Eigen::Vector2d px = camera.project(p.cast<double>());
    if (!camera.inImage(px)) continue;
    const int gx = std::min(gw - 1, static_cast<int>(px.x()) / cell);
    const int gy = std::min(gh - 1, static_cast<int>(px.y()) / cell);
    grid[static_cast<size_t>(gy) * static_cast<size_t>(gw) + static_cast<size_t>(gx)].push_back(
        {static_cast<float>(px.x()), static_cast<float>(px.y()), p.z(), static_cast<uint32_t>(i)});
  }
  for (size_t b = 0; b < boxes.size(); ++b) {
    const VoteBox& box = boxes[b];
    if (!(box.w > 0 && box.h > 0 && box.median_depth > 0) || !std::isfinite(box.x) ||
        !std::isfinite(box.y) || !std::isfinite(box.w) || !std::isfinite(box.h) ||
        !std::isfinite(box.median_depth))
      continue;
    const double half = depthBandHalfWidth(box, camera, options);
    const float zmin = static_cast<float>(box.median_depth - half),
                zmax = static_cast<float>(box.median_depth + half);
    const int x0 = std::clamp(static_cast<int>(std::floor(box.x / cell)), 0, gw - 1);
    const int x1 = std::clamp(static_cast<int>(std::floor((box.x + box.w) / cell)), 0, gw - 1);
    const int y0 = std::clamp(static_cast<int>(std::floor(box.y / cell)), 0, gh - 1);
    const int y1 = std::clamp(static_cast<int>(std::floor((box.y + box.h) / cell)), 0, gh - 1);
    std::vector<VoxelKey>& keys = out[b];
    for (int gy = y0; gy <= y1; ++gy)
      for (int gx = x0; gx <= x1; ++gx)
        for (const Projected& p :
             grid[static_cast<size_t>(gy) * static_cast<size_t>(gw) + static_cast<size_t>(gx)])
          if (p.u >= box.x && p.u <= box.x + box.w && p.v >= box.y && p.v <= box.y + box.h &&
              p.z >= zmin && p.z <= zmax)
            keys.push_back(occupied[p.index].key);
    std::sort(keys.begin(), keys.end());
  }
  return out;
}

}  // namespace slamaware::objectmap
