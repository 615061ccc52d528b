#pragma once
// Which proposal boxes of a frame show a candidate from a view the recognizer has not classified
// yet. At 30 Hz consecutive frames see a candidate from almost the same place, so classifying it
// again adds work, not evidence. A box is classified when its candidate
//   - was not in the previous frame the recognizer handled (first sighting, or back after being
//     occluded, out of view, or in a frame that was dropped or failed), or
//   - is seen from a direction more than `angle_deg` away from that of its last classified view
//     (the proposals' view_direction: from the candidate's centroid to the camera, map frame), or
//   - is seen at a median depth, or has a box whose width or height in map units (pixels × depth),
//     that differs by more than the factor 1 + `scale` from its last classified view (closer,
//     farther, or the candidate itself grew or shrank as the map grew);
// otherwise the result of its last classified view is carried to it. Only the candidates of the
// last handled frame are remembered: the state is bounded by construction, and a candidate that
// left the view is classified afresh when it returns. A frame older than the newest one selected
// (proposals sent late for a map's reference keyframe) is classified in full and changes nothing.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

namespace slamaware::recognizer {

struct ViewSelectionOptions {
  bool enabled = true;   ///< false: every box of every frame is classified
  double angle_deg = 5;  ///< degrees of viewing direction that make a view new
  double scale = 0.075;  ///< relative change of depth or metric box size that makes a view new

  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "false: every box of every frame is classified (no result is carried)");
    v("angle_deg", angle_deg,
      "a candidate is classified again when seen from a direction this many degrees from its last "
      "classified view");
    v("scale", scale,
      "... or when its median depth or its box in map units changed by more than this factor "
      "(0.15: 15 %)");
  }
};

/// A box of a frame as the selection sees it (from PROPOSALS).
struct CandidateView {
  int32_t candidate_id = -1;                            ///< < 0: no candidate (always classified)
  Eigen::Vector3f direction = Eigen::Vector3f::Zero();  ///< unit; zero: unknown (always classified)
  float depth = 0;     ///< median depth, map units; <= 0: unknown (always classified)
  float w = 0, h = 0;  ///< px
};

/// The result of a candidate's last classified view, carried to the frames after it.
struct CarriedView {
  int32_t seq = -1;             ///< frame it was classified in
  std::vector<float> log_prob;  ///< per class
};

class ViewSelector {
 public:
  explicit ViewSelector(const ViewSelectionOptions& options) : options_(options) {}

  /// Decides for each box of frame `seq` of `map_id`: nullptr = classify it, else the result to
  /// carry (valid until the next call). Forgets the candidates that are not in this frame. A
  /// frame older than the newest one selected gets nullptr for every box and changes nothing.
  std::vector<const CarriedView*> select(int32_t map_id, int32_t seq,
                                         const std::vector<CandidateView>& views);

  /// Remembers `view` (a box of frame `seq`'s select()) as classified with `log_prob`; nothing for
  /// a frame older than the newest one selected.
  void remember(int32_t map_id, int32_t seq, const CandidateView& view,
                const std::vector<float>& log_prob);

  /// The result remembered for the candidate (of the last frame selected), or nullptr: for a frame
  /// that real time had no time to classify. Valid until the next select() or remember().
  const CarriedView* lastResult(int32_t map_id, int32_t candidate_id) const {
    const auto it = last_.find(std::make_pair(map_id, candidate_id));
    return it == last_.end() ? nullptr : &it->second.result;
  }

  /// Forgets every result and frame (another model was loaded, or the camera stream restarted
  /// and its seqs start again).
  void clear() {
    last_.clear();
    newest_seq_.reset();
  }

  /// Candidates remembered (those of the last frame that were classified or carried).
  size_t size() const { return last_.size(); }

 private:
  struct Remembered {
    CandidateView view;  ///< the last classified view
    CarriedView result;
  };
  /// Whether frame `seq` is older than the newest one selected.
  bool isLate(int32_t seq) const;
  /// Whether `now` differs from the classified view `then` enough to be classified again.
  bool isNewView(const CandidateView& now, const CandidateView& then) const;

  ViewSelectionOptions options_;
  std::map<std::pair<int32_t, int32_t>, Remembered> last_;  ///< (map id, candidate id)
  std::optional<int32_t> newest_seq_;                       ///< newest frame selected
};

}  // namespace slamaware::recognizer
