#pragma once
// Writing what the generator makes: a scene as a sequence folder (DATASETS.md §1) and an object
// set in the layout of the UW RGB-D Object dataset (DATASETS.md §2), plus contact sheets.
#include <cstdint>
#include <string>
#include <vector>

#include "tools/synth/scene.h"
#include "tools/synth/synth_options.h"

namespace slamaware::synth {

struct WriteStats {
  int64_t files = 0;
  int64_t bytes = 0;
  double seconds = 0;
};

/// Writes the scene into `dir`: sequence.yaml, rgb/NNNNNN.jpg, depth/NNNNNN.png (if enabled),
/// groundtruth.txt, boxes.csv, objects.csv, visibility.csv. Frames and depth maps left from an
/// earlier run in rgb/ and depth/ are removed first. `config_name` is recorded in sequence.yaml.
WriteStats writeSceneFolder(SyntheticScene& scene, const std::string& dir,
                            const std::string& config_name, bool progress = true);

/// Renders an object set into `dir` (<category>/<category>_<n>/<...>_{crop,maskcrop}.png and
/// _loc.txt), plus set.yaml describing it. `seed` replaces options.seed when >= 0.
WriteStats writeObjectSet(const ObjectSetOptions& options, const std::string& dir,
                          int64_t seed = -1, bool progress = true);

/// Tiles images (any size, scaled to fit cells of cell_w x cell_h) into one image with a caption
/// under each.
cv::Mat contactSheet(const std::vector<cv::Mat>& images, const std::vector<std::string>& captions,
                     int cols, int cell_w, int cell_h);

}  // namespace slamaware::synth
