#pragma once
// Candidates of the map -> boxes in one frame (docs/architecture.md §3): each candidate's points
// projected with the frame's pose, its box and median depth; a depth buffer of the candidates culls
// those hidden behind nearer ones; small boxes are dropped; the boxes are ranked, and overlapping
// ones suppressed when `nms_iou` < 1 (by default the recognizer suppresses them once classified).
#include <vector>

#include "common/camera_model.h"
#include "common/geometry.h"
#include "procs/proposals/candidate_map.h"

namespace slamaware::proposals {

struct ProposalBox {
  int32_t candidate_id = -1;
  float x = 0, y = 0, w = 0, h = 0;  ///< px, top-left corner and size
  float median_depth = 0;            ///< map units
  /// Unit vector from the candidate's centroid to the camera centre, world frame: where the
  /// candidate is seen from (the recognizer classifies a candidate again when it changes).
  Eigen::Vector3f view_direction = Eigen::Vector3f::Zero();
  int scale = 0;
  int stability = 1;
  bool by_colour = false;  ///< the candidate was found only on position and colour
  int parts = 1;           ///< the candidate's parts: 2 or more are touching objects
  int points = 0;          ///< projected points inside the image
  bool lost = false;       ///< the candidate is kept after a re-clustering lost it (keep_lost_s)
};

struct ProjectionStats {
  int in_view = 0, occluded = 0, too_small = 0, suppressed = 0;
};

/// IoU of two boxes.
double boxIou(const ProposalBox& a, const ProposalBox& b);

std::vector<ProposalBox> projectCandidates(const std::vector<Candidate>& candidates,
                                           const CameraModel& camera, const SE3& T_world_camera,
                                           const ProposalOptions& options,
                                           ProjectionStats* stats = nullptr);

}  // namespace slamaware::proposals
