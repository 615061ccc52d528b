#pragma once
// How the figures spread over the scenes of one run: per scene the proposals recall, boxes per
// frame, SLAM tracking and the recognition mAPs; the median and the worst scene of each (with
// the config that reproduces it), and a histogram of per-scene proposal recall. The section that
// judges options on random scenes (`make eval-random`), where one pooled figure hides the table
// on which the stage breaks.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace slamaware {

struct SceneFolder {
  std::string name;  ///< report key (folder name)
  std::string dir;   ///< the sequence folder
};

/// The "per_scene" section of `report` (which holds "sequences"), over `scenes`. The config of a
/// scene is <dir>/scene.yaml when the generator wrote one. Draws the recall histogram to
/// `histogram_png` when at least one scene has proposals.
nlohmann::json perSceneSection(const nlohmann::json& report, const std::vector<SceneFolder>& scenes,
                               const std::string& histogram_png);

}  // namespace slamaware
