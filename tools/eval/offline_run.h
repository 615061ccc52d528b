#pragma once
// Runs the SLAM library in-process, lockstep, over a sequence folder and records what the node
// would have published (for development and for checks without a bus).
#include <string>

#include "common/dataset.h"
#include "procs/slam/slam_options.h"
#include "tools/eval/slam_metrics.h"

namespace slamaware {

struct OfflineRunStats {
  std::vector<double> track_ms;  ///< per frame
  std::vector<double> depth_ms;  ///< per depth-filter update
};

/// verbose: one log line per frame.
SlamRecording runSlamOffline(const SequenceFolder& sequence, const slam::SlamOptions& options,
                             bool verbose, OfflineRunStats* stats = nullptr);

}  // namespace slamaware
