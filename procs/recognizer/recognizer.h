#pragma once
// The recognizer stage without the bus: a frame and its proposal boxes in, per-box calibrated
// class log-probabilities out (what DETECTIONS carries).
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "procs/recognizer/frame_encoder.h"
#include "procs/recognizer/model.h"
#include "procs/recognizer/view_selector.h"

namespace slamaware::recognizer {

struct RecognizerOptions {
  std::string model = "models/recognizer.model";  ///< model file (slamaware-train)
  /// Classes the rest of the system expects; those the model lacks are reported (the process
  /// keeps running with the classes it has).
  std::vector<std::string> expected_classes;
  std::string encoder = "auto";  ///< auto | direct | flair
  int max_boxes = 300;           ///< boxes per frame beyond this are rejected
  /// The node: of two classified boxes of a frame that overlap by more than this IoU, the less
  /// confident is not published (suppressOverlaps; >= 1: every box is published).
  double nms_iou = 0.5;
  /// true: a box is suppressed only by a more confident box of the same most probable object class.
  bool nms_per_class = true;
  /// Log-probability given to "background" when the model was trained without negatives (it has
  /// no background class); the object classes share the rest.
  double missing_background_log_prob = -13.8;
  EncoderCostModel cost;
  /// The node: which boxes are classified and which carry their candidate's last result.
  ViewSelectionOptions view_selection;
  // Node: joining CAMERA and PROPOSALS.
  int frame_buffer = 30;           ///< CAMERA frames kept for joining (oldest dropped)
  int proposals_buffer = 30;       ///< PROPOSALS waiting for their frame
  double pending_timeout_s = 2.0;  ///< s a PROPOSALS message waits for its frame (wall clock)
  double model_retry_s = 5.0;      ///< s between attempts to load a missing or bad model
  /// s between checks whether the model file was replaced (then it is reloaded live); 0: never.
  double model_watch_s = 1.0;
  /// Frame size whose buffers are prepared when the model loads (FrameEncoder::warmUp); 0: none.
  int warm_up_width = 640, warm_up_height = 480;

  template <class V>
  void visit(V& v) {
    v("model", model, "model file written by slamaware-train (relative to the working directory)");
    v("expected_classes", expected_classes,
      "classes the system expects; missing ones are reported");
    v("encoder", encoder, "auto (cheaper of the two per frame), direct or flair");
    v("max_boxes", max_boxes, "boxes per frame beyond this are rejected");
    v("nms_iou", nms_iou,
      "of two classified boxes overlapping by more than this IoU, the less confident is not "
      "published (>= 1: none)");
    v("nms_per_class", nms_per_class,
      "true: only boxes of the same most probable object class suppress each other");
    v("missing_background_log_prob", missing_background_log_prob,
      "log p(background) published when the model has no background class");
    v.section("cost", cost,
              "time model that picks the encoder (slamaware-bench-recognizer measures it)");
    v.section("view_selection", view_selection,
              "which boxes are classified; the others carry their candidate's last result");
    v("frame_buffer", frame_buffer, "CAMERA frames kept for joining with PROPOSALS");
    v("proposals_buffer", proposals_buffer, "PROPOSALS waiting for their frame");
    v("pending_timeout_s", pending_timeout_s, "s a PROPOSALS message waits for its CAMERA frame");
    v("model_retry_s", model_retry_s, "s between attempts to load a missing or unreadable model");
    v("model_watch_s", model_watch_s,
      "s between checks whether the model file was replaced (then it is reloaded live); 0: never");
    v("warm_up_width", warm_up_width,
      "px, frame width whose buffers are prepared when the model loads (0: none; the first frames "
      "pay)");
    v("warm_up_height", warm_up_height, "px, frame height of the same");
  }
};

/// Largest warm-up frame side accepted (a typo must not allocate gigabytes).
constexpr int kMaxWarmUpPx = 4096;

/// Throws ConfigError naming `source` (the file) and the key for an unknown encoder, an
/// `nms_iou` that is not positive, a view-selection angle outside 0-180 degrees or a negative
/// scale, or a warm-up size that is not a frame size (or 0 x 0).
void checkOptions(const RecognizerOptions& options, const std::string& source);

/// A proposal box: pixels, (x, y) = top-left corner. With `carried`, the box is checked and
/// clipped like any other but not classified: it gets the carried result (ViewSelector).
struct BoxRequest {
  double x = 0, y = 0, w = 0, h = 0;
  int32_t candidate_id = -1;
  const CarriedView* carried = nullptr;
};

struct BoxDetection {
  int input_index = -1;  ///< position in the request
  int32_t candidate_id = -1;
  float x = 0, y = 0, w = 0, h = 0;  ///< the box clipped to the image
  std::vector<float> log_prob;       ///< per class of FrameDetections::classes
  int32_t carried_seq = -1;          ///< >= 0: log_prob carried from the view of that frame
};

struct FrameDetections {
  std::vector<std::string> classes;  ///< "background" last
  std::vector<BoxDetection> boxes;   ///< valid boxes, in request order
  int rejected_not_finite = 0, rejected_empty = 0, rejected_outside = 0, rejected_over_limit = 0;
  int clipped = 0;
  int suppressed = 0;  ///< boxes removed by suppressOverlaps()
  int carried = 0;     ///< valid boxes that carried a result instead of being classified
  int uncarried = 0;   ///< carryOnly(): valid boxes left out, having no result to carry
  FrameEncoder::Stats stats;
  double total_ms = 0;  ///< encoding + scoring
  int rejected() const {
    return rejected_not_finite + rejected_empty + rejected_outside + rejected_over_limit;
  }
};

/// Non-maximum suppression of classified boxes (docs/architecture.md §3: overlapping boxes,
/// IoU > max_iou, are suppressed). The boxes are taken in order of their most probable object
/// class's probability (the background excluded; ties: request order), and a box is removed when it
/// overlaps one kept before it by IoU > max_iou (with `per_class`, only one whose most probable
/// object class is the same: a bowl's box beside the box of the bowl and a mug, surer of a mug,
/// stays). The others stay, in request order. Done after
/// classification rather than in the proposals stage, which can only rank the boxes by the
/// geometry of their candidates: there a part of an object found at more density scales (a cap's
/// crown) outranked and suppressed the whole object's box, while the classifier, trained with
/// such parts as background, is the surer of the whole. Returns the number removed (also in
/// `suppressed`); nothing is removed for max_iou >= 1.
int suppressOverlaps(FrameDetections* detections, double max_iou, bool per_class = false);

class Recognizer {
 public:
  /// Throws std::invalid_argument for a bad encoder name.
  Recognizer(std::shared_ptr<const RecognizerModel> model, const RecognizerOptions& options);
  /// The published class list: the model's classes, "background" last (appended if missing).
  const std::vector<std::string>& classes() const { return classes_; }
  /// Classes of options.expected_classes the model does not have.
  std::vector<std::string> missingClasses() const;
  const RecognizerModel& model() const { return *model_; }

  /// Classifies the valid boxes of one 8-bit BGR frame (those with a `carried` result take it,
  /// when it has one log-probability per class). Boxes that are not finite, have no area, or lie
  /// outside the image are rejected (counted); boxes partly outside are clipped. Deterministic for
  /// a given input.
  FrameDetections recognize(const cv::Mat& bgr, const std::vector<BoxRequest>& boxes);

  /// The boxes of a `width` x `height` frame answered without its pixels: checked and clipped as
  /// by recognize(), each valid box with a `carried` result gets it, and the others are left out
  /// (counted in `uncarried`). For a frame that real time has no time to classify.
  FrameDetections carryOnly(int width, int height, const std::vector<BoxRequest>& boxes) const;

  /// Prepares the buffers of frames of this size with the configured encoder
  /// (FrameEncoder::warmUp) and the buffer of the boxes' encodings; returns the ms spent.
  double warmUp(int width, int height);

  /// Boxes encoded and scored together: the encodings' buffer holds this many rows.
  static constexpr size_t kRowsPerPass = 32;

 private:
  /// recognize() and carryOnly(): the valid boxes of `requests` in `out`, those to classify also
  /// snapped (`snapped`, and their places in out.boxes in `classified`); with `carry_only` they
  /// are left out instead.
  void takeBoxes(int width, int height, const std::vector<BoxRequest>& requests, bool carry_only,
                 FrameDetections* out, std::vector<PyramidBox>* snapped,
                 std::vector<size_t>* classified) const;

  std::shared_ptr<const RecognizerModel> model_;
  RecognizerOptions options_;
  EncoderKind kind_;
  std::vector<std::string> classes_;
  bool append_background_ = false;
  FrameEncoder encoder_;
  ReusableMatrix encoded_;
  MatrixRM scores_, log_p_;
};

}  // namespace slamaware::recognizer
