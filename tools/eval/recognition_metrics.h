#pragma once
// The "single_view", "multi_view_online" and "multi_view_final" sections of the eval report
// (docs/architecture.md §7): detection of the object classes on every 5th frame, each box as the
// processes published it: DETECTIONS (single view: its frame alone), OBJECT_DETECTIONS (multi view
// online: its object's evidence up to that frame, ranked by the object map's score) and the last
// OBJECT_MAP (multi view final, the paper's protocol: its object's evidence over the whole
// sequence), scored against the ground-truth boxes by VOC average precision, plus precision and
// recall at the label the system reports (argmax over the classes, background included). The
// evaluator relabels, re-ranks, fuses and suppresses nothing. Definitions in tools/eval/README.md.
// Only the evaluator reads ground truth.
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "common/bus/system_config.h"
#include "common/dataset.h"
#include "procs/objectmap/objectmap_options.h"
#include "slamaware/object_detections_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "tools/eval/proposal_metrics.h"

namespace slamaware {

// ---- Average precision ------------------------------------------------------------------------

struct ScoredDetection {
  double score = 0;  ///< any monotone confidence (we use log p)
  bool true_positive = false;
};
struct PrPoint {
  double recall = 0, precision = 0;  ///< 0..1
};

/// VOC all-point interpolated average precision (0..1) of detections against `num_truth` ground-
/// truth objects: the area under the precision-recall curve after precision is made monotone
/// (precision at recall r = the best precision at any recall >= r). Detections of equal score are
/// one step of the curve (the curve's points are taken after each group of ties), so the result
/// does not depend on their order. NaN when num_truth is 0. `curve` gets the raw points.
double averagePrecision(std::vector<ScoredDetection> detections, int num_truth,
                        std::vector<PrPoint>* curve = nullptr);

// ---- Scoring boxes against ground truth --------------------------------------------------------

/// A box of a frame with its class scores: log p(class | evidence), in the order of the model's
/// classes (background last).
struct LabelledBox {
  Box2 box;
  std::vector<double> log_p;  ///< ranks the box as a detection of each class
  int label = -1;             ///< the class the system reports; -1: the argmax of log_p
};

/// Tallies of one evaluated class.
struct ClassTally {
  std::vector<ScoredDetection>
      ranked;           ///< every box, scored by the log-odds of p(class), TP when matched
  int truth = 0;        ///< ground-truth boxes of the class
  int labelled = 0;     ///< boxes whose argmax is the class
  int labelled_tp = 0;  ///< of those, matched to a ground-truth box of the class
  int boxed =
      0;  ///< ground-truth boxes of the class that some box overlaps at the IoU threshold: no
          ///< labelling of these boxes can find more (recall <= boxed / truth, so AP too)
};

/// Detection scores of one sequence or (merged) of a suite.
struct RecognitionScores {
  std::map<std::string, ClassTally> classes;  ///< the evaluated classes
  int frames = 0;                             ///< frames evaluated
  int boxes = 0;                              ///< boxes labelled
  // Where the boxes are (best IoU with any ground-truth box >= 0.5) and what they were called:
  int boxes_on_objects = 0, correct_on_objects = 0, background_on_objects = 0;
  int boxes_on_distractors = 0, background_on_distractors = 0;
  int boxes_elsewhere = 0, background_elsewhere = 0;
  std::map<std::string, std::map<std::string, int>>
      confusion;  ///< truth -> label -> boxes on objects
};

/// Scores without tallies for the evaluated classes.
RecognitionScores emptyScores(const std::vector<std::string>& evaluated_classes);

/// Adds one frame: `model_classes` names the entries of every box's log_p (background last);
/// a box is labelled with its `label`, or the argmax of its log_p;
/// `truth` is every ground-truth box of the frame (boxes of classes that are not evaluated are
/// distractors: not ground truth, and a box on one is not a true positive of any class). Matching
/// per class: boxes in descending score, each to the unmatched ground-truth box of the class with
/// the highest IoU >= iou_threshold. A box's score for class c is the log-odds of p(c),
/// log p(c) - log(1 - p(c)): the order of p(c) without the ties that rounding makes of saturated
/// fused posteriors.
void scoreFrame(const std::vector<std::string>& model_classes,
                const std::vector<LabelledBox>& boxes, const std::vector<GroundTruthBox>& truth,
                double iou_threshold, RecognitionScores* scores);

/// Pools the detections of another sequence (AP of the pool, not a mean of APs).
void mergeRecognition(RecognitionScores* into, const RecognitionScores& more);

/// The report section: {"mAP", "recall", "per_class": {c: {"AP", "precision", "recall"}}} in %
/// (null where undefined: AP and recall of a class without ground truth, precision of a class
/// never reported), plus counts and the diagnostics.
nlohmann::json recognitionSection(const RecognitionScores& scores);

/// Precision-recall curves per class (classes with ground truth), single view and the multi-view
/// online and final labels, one panel per class, into a PNG.
void drawPrCurves(const RecognitionScores& single, const RecognitionScores& online,
                  const RecognitionScores& final, const std::string& title,
                  const std::string& path);

// ---- What the processes published ----------------------------------------------------------

/// The object map's outputs of a run: OBJECT_DETECTIONS by frame seq and the last OBJECT_MAP.
struct ObjectMapOutputs {
  std::map<int32_t, object_detections_t> frames;
  object_map_t last_map;
  bool have_map = false;
};

/// The OBJECT_DETECTIONS and last OBJECT_MAP recorded in a log. Throws LogError for a damaged log.
ObjectMapOutputs readObjectMapOutputs(const std::string& log_path, const Channels& channels);

/// The object map run again on a recording's inputs (CAMERA_INFO, SLAM_MAP, SLAM_POSE, PROPOSALS,
/// DETECTIONS, in the recorded order) with other `options`, publishing as the lockstep node does:
/// one OBJECT_DETECTIONS and one OBJECT_MAP per DETECTIONS. With the node's options it gives the
/// recorded messages byte for byte (tested), so options can be tried on recordings without running
/// the pipeline again (--objectmap-config).
ObjectMapOutputs rerunObjectMap(const std::string& log_path, const Channels& channels,
                                const objectmap::ObjectMapOptions& options);

/// What the last OBJECT_MAP holds (the "object_map" section of a sequence): segments, objects,
/// labelled objects, and in the segment whose objects hold the most voxels: its objects, their
/// voxels and the share of them the largest object holds (near 100 % when the scene is one object
/// and its parts lie in it: the Middlebury temple).
nlohmann::json objectMapSummary(const object_map_t& map);

// ---- A sequence ------------------------------------------------------------------------------

/// The boxes of a recording by frame seq, each labelled three ways from what the processes
/// published; the evaluator never fuses, re-ranks or suppresses (tools/eval/README.md).
struct RecognitionRecording {
  struct Box {
    LabelledBox single;  ///< DETECTIONS: the box's own log p(class | box)
    /// OBJECT_DETECTIONS of the same frame: the map's log_score, labelled by its posterior (what a
    /// user saw at that moment; evidence up to that frame).
    LabelledBox online;
    /// The paper's protocol, in hindsight: the box's object labelled by its log posterior in the
    /// last OBJECT_MAP, with the box's published log_weight per object class (the background the
    /// rest); a box without an object in that map keeps its online scores.
    LabelledBox final;
    int32_t map_id = -1, candidate = -1;
    int32_t object = -1;   ///< OBJECT_DETECTIONS' object id (-1: none)
    int role = -1;         ///< object_detections_t role; -1: no OBJECT_DETECTIONS for the frame
    bool carried = false;  ///< DETECTIONS carried its scores from an earlier view (classified_seq)
  };
  std::vector<std::string> classes;  ///< DETECTIONS' class names (the model's, background last)
  std::map<int32_t, std::vector<Box>> frames;
  int objects = 0;  ///< in the last OBJECT_MAP
  int frames_without_object_detections =
      0;                         ///< DETECTIONS with no OBJECT_DETECTIONS (an incomplete run)
  int final_without_object = 0;  ///< boxes whose object the last OBJECT_MAP does not hold
  std::map<int, int> roles;      ///< boxes per OBJECT_DETECTIONS role
  nlohmann::json object_map;     ///< objectMapSummary() of the last OBJECT_MAP

  bool empty() const { return classes.empty(); }
};

/// Joins the DETECTIONS of a recorded log with the object map's outputs (`outputs`: recorded, or
/// re-run) box by box. Throws LogError for a damaged log. Empty when the log has no DETECTIONS.
RecognitionRecording readRecognitionRecording(const std::string& log_path, const Channels& channels,
                                              const ObjectMapOutputs& outputs);

struct RecognitionEvalOptions {
  int stride = 5;  ///< every stride-th frame (the proposals section's frames)
  double iou = 0.5;
};

struct RecognitionResult {
  RecognitionScores single, online, final;
  std::vector<std::string>
      classes;  ///< evaluated: the model's (background excluded) that the sequence lists
};

/// The classes a sequence is evaluated on: the model's object classes that its sequence.yaml lists.
std::vector<std::string> evaluatedClasses(const std::vector<std::string>& model_classes,
                                          const SequenceFolder& sequence);

/// The frames of a sequence that are scored: of a continuous video (it has ground-truth poses)
/// every stride-th frame; of a sequence of separate views (boxes, no poses: each frame was chosen
/// and annotated on its own, e.g. uw_scenes_v2_public) every frame.
std::vector<int> framesToScore(const SequenceFolder& sequence, int stride);

/// Scores the frames framesToScore() picks (frames without boxes count: their ground truth is
/// missed, their boxes are false positives).
RecognitionResult scoreRecognition(const RecognitionRecording& run, const SequenceFolder& sequence,
                                   const RecognitionEvalOptions& options);

}  // namespace slamaware
