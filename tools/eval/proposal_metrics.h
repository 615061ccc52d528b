#pragma once
// The "proposals" section of the eval report (issue: multi-view proposals): recall of the
// ground-truth boxes on every 5th frame at IoU >= 0.5 and 0.7, boxes per frame, and the
// single-view baseline (OpenCV selective search on the same frames) at the same box count, plus
// a PNG of recall against boxes per frame for both. Only the evaluator reads ground truth.
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "common/bus/system_config.h"
#include "common/dataset.h"
#include "procs/proposals/proposal_options.h"

namespace slamaware {

struct Box2 {
  double x = 0, y = 0, w = 0, h = 0;
};
double iou(const Box2& a, const Box2& b);

/// Selective search (OpenCV ximgproc, fast mode) on a frame downscaled to `width` px (0: as it is):
/// at most `max_boxes` boxes in the frame's pixels, in the order OpenCV ranks them. The single-view
/// baseline of the proposals and of recognition on real frames.
std::vector<Box2> selectiveSearch(const cv::Mat& bgr, int width, int max_boxes);

/// What the proposals stage published for one run, by frame seq; `localized` are the frames
/// SLAM localised (TRACKING or RELOCALIZED).
struct ProposalRecording {
  std::map<int32_t, std::vector<Box2>> boxes;  ///< ranked, best first
  std::map<int32_t, bool> localized;
  int reclusters = 0;       ///< rerunProposals: re-clusterings of the stage
  double recluster_ms = 0;  ///< ... and their time (ClusterStats::ms, summed)
};

/// PROPOSALS and SLAM_POSE of a recorded log. Throws LogError for a damaged log.
ProposalRecording readProposalRecording(const std::string& log_path, const Channels& channels);
/// Why the ground-truth boxes of the evaluated frames that no proposal covers (IoU >= 0.5) are
/// missed, found by running the proposals stage again on the log and projecting its candidates
/// without the step that could have dropped the box. Counts of ground-truth boxes, each in the
/// first cause that applies.
struct ProposalMisses {
  int boxes = 0;          ///< ground-truth boxes of the evaluated frames
  int covered = 0;        ///< a proposal covers it
  int before_first = 0;   ///< frame before the sequence's first proposal (the map is not built yet)
  int not_localized = 0;  ///< SLAM did not localise the frame
  int suppressed =
      0;  ///< a candidate's box covers it, but a box ranked ahead overlapped that box (NMS)
  int occluded = 0;  ///< a candidate's box covers it, but the depth buffer culled it
  int partial = 0;   ///< the best candidate's box overlaps it at IoU 0.3-0.5 (a part, or too much)
  int no_candidate = 0;  ///< no candidate's box overlaps it at IoU 0.3

  /// f(report key, count) for every count of `m` (const or not).
  template <class M, class F>
  static void forEach(M& m, F&& f) {
    f("ground_truth_boxes", m.boxes);
    f("covered", m.covered);
    f("before_first_proposals", m.before_first);
    f("not_localized", m.not_localized);
    f("suppressed", m.suppressed);
    f("occluded", m.occluded);
    f("partial", m.partial);
    f("no_candidate", m.no_candidate);
  }
};

/// Runs the proposals stage offline on the CAMERA_INFO, SLAM_MAP and SLAM_POSE of a recorded log
/// (to try other options without running SLAM again). With `misses` and `sequence`, also counts
/// why the ground-truth boxes of every `stride`-th frame are missed.
ProposalRecording rerunProposals(const std::string& log_path, const Channels& channels,
                                 const proposals::ProposalOptions& options,
                                 const SequenceFolder* sequence = nullptr, int stride = 5,
                                 ProposalMisses* misses = nullptr);
nlohmann::json missesSection(const ProposalMisses& misses);
void mergeMisses(ProposalMisses* into, const ProposalMisses& more);

struct ProposalEvalOptions {
  int stride = 5;            ///< every stride-th frame is evaluated
  int baseline_frames = 20;  ///< selective search runs on at most this many of those frames
  int baseline_width = 320;  ///< px, frames are downscaled to this width for selective search
  int baseline_max_boxes = 2000;
  std::string plot_path;  ///< recall-vs-boxes PNG ("" = none)
  bool baseline = true;
};

/// Per ground-truth box: the rank (1 = first) of the best-ranked proposal that covers it at the
/// IoU threshold, 0 when none does. Recall at k boxes is the share of ranks in 1..k.
struct ProposalScores {
  std::vector<int> rank50, rank70;    ///< ours, every evaluated frame
  std::vector<int> rank50_localized;  ///< ours, the evaluated frames SLAM localised
  std::vector<int> boxes_per_frame;   ///< ours, localised evaluated frames
  int frames = 0, localized_frames = 0;
  std::vector<int> ours_on_baseline_frames;  ///< ours at IoU 0.5, the baseline's frames only
  std::vector<int> baseline_rank50;          ///< selective search, its frames
  int baseline_frames = 0;
  double baseline_ms_per_frame = 0;
};

ProposalScores scoreProposals(const ProposalRecording& run, const SequenceFolder& sequence,
                              const ProposalEvalOptions& options);
/// The report section of one sequence or (several scores merged) of the suite; writes the plot.
nlohmann::json proposalSection(const ProposalScores& scores, const std::string& plot_path = "");
void mergeScores(ProposalScores* into, const ProposalScores& more);

/// Writes every frame's boxes, best first, as CSV `frame,rank,x,y,w,h` (the file slamaware-train
/// --proposals reads), creating the folder. Throws std::runtime_error when it cannot write.
void writeProposalBoxes(const ProposalRecording& run, const std::string& path);
/// Writes <dir>/<frame>.png for evaluated frames (at most `max_frames`, spread evenly): the
/// ground-truth boxes in green, our first `top_k` boxes in orange with their rank.
void drawProposalFrames(const ProposalRecording& run, const SequenceFolder& sequence,
                        const std::string& dir, int stride, int max_frames, int top_k);

}  // namespace slamaware
