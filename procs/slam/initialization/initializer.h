#pragma once
// Monocular initialisation: keeps a reference frame, matches each new frame to it and, when the
// two views give a valid reconstruction (geometry/two_view.h), builds the first two keyframes and
// their points, refines them by bundle adjustment and scales the map so that the median depth
// of the first keyframe is 1.
#include <memory>
#include <optional>
#include <string>

#include "procs/slam/map/frame.h"
#include "procs/slam/map/map.h"
#include "procs/slam/slam_options.h"

namespace slamaware::slam {

class Initializer {
 public:
  explicit Initializer(const SlamOptions& options) : options_(options) {}

  /// Forgets the reference frame.
  void reset() { reference_.reset(); }
  bool hasReference() const { return reference_.has_value(); }

  /// Offers a frame. Returns a new map (id `map_id`, two keyframes, median depth 1) when the
  /// reference and this frame initialise; otherwise nullptr, and *why says what was missing.
  /// On success frame.T_camera_world is set and frame.points hold the new points.
  std::shared_ptr<Map> tryInitialize(Frame& frame, int map_id, IdSource& ids, std::string* why);

 private:
  std::shared_ptr<Map> buildMap(const Frame& reference, Frame& frame,
                                const struct TwoViewResult& tv,
                                const std::vector<std::pair<int, int>>& matches, int map_id,
                                IdSource& ids, std::string* why);

  SlamOptions options_;
  std::optional<Frame> reference_;
  int attempts_ = 0;
};

}  // namespace slamaware::slam
