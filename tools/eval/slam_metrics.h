#pragma once
// What SLAM published for one sequence, and the "slam" section of the eval report computed from it
// against the sequence's ground truth (docs/architecture.md §7).
// Only the evaluator reads ground truth.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/dataset.h"
#include "common/geometry.h"

namespace slamaware {

/// The outputs of SLAM for one run, keyed the way the messages are.
struct SlamRecording {
  struct Pose {
    int8_t state = 0;  ///< pose_t::STATE_*
    SE3 T_world_camera = SE3::Identity();
    int map_id = 0;
  };
  struct Keyframe {
    int32_t seq = -1;
    int map_id = 0;
    SE3 T_world_camera = SE3::Identity();  ///< the last pose published for it
    bool culled = false;
  };
  struct Point {
    Eigen::Vector3f p_world;
    int64_t keyframe_id = -1;
    float depth_std = 0;
  };
  std::map<int32_t, Pose> poses;          ///< by frame seq (= frame index of the sequence folder)
  std::map<int64_t, Keyframe> keyframes;  ///< by keyframe id
  std::map<int, std::vector<Point>> points;  ///< semi-dense points per map id (the final map)

  /// Adds a point cloud message's content: a full cloud replaces the map's points; an incremental
  /// one replaces the points of its keyframe.
  void addCloud(int map_id, bool full, int64_t keyframe_id, std::vector<Point> cloud_points);
};

struct SlamEvalOptions {
  std::string plot_path;                ///< top-down trajectory PNG ("" = none)
  double max_time_difference_s = 0.02;  ///< frame time <-> ground-truth time association
};

/// The report's slam section for one sequence: ate_rmse (m, per map after a Sim(3) Umeyama
/// alignment), ate_rmse_pct_of_path, ate_rmse_pct_of_extent, tracked_pct, localized_pct,
/// reinitializations and, when the sequence has depth/, the semi-dense depth error and points per
/// keyframe. Also writes the plot.
nlohmann::json evaluateSlam(const SlamRecording& run, const SequenceFolder& sequence,
                            const SlamEvalOptions& options);

/// The overall slam section over several sequences' sections (frames-weighted where it matters).
nlohmann::json summarizeSlam(const std::vector<nlohmann::json>& sections);

}  // namespace slamaware
