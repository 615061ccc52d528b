#pragma once
// The "single_view" and "multi_view" sections of the eval report (DESIGN.md §7): detection of the
// object classes on every 5th frame, each proposal box of DETECTIONS labelled from its frame alone
// (single view) or with the fused evidence of its object at the end of the sequence (multi view),
// scored against the ground-truth boxes by VOC average precision, plus precision and recall at the
// label the system reports (argmax over the classes, background included). Definitions in
// tools/eval/README.md. Only the evaluator reads ground truth.
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "common/bus/system_config.h"
#include "common/dataset.h"
#include "procs/objectmap/object_map.h"
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
double averagePrecision(std::vector<ScoredDetection> detections, int num_truth, std::vector<PrPoint>* curve = nullptr);

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
  std::vector<ScoredDetection> ranked;  ///< every box, scored by the log-odds of p(class), TP when matched
  int truth = 0;                        ///< ground-truth boxes of the class
  int labelled = 0;                     ///< boxes whose argmax is the class
  int labelled_tp = 0;                  ///< of those, matched to a ground-truth box of the class
  int boxed = 0;  ///< ground-truth boxes of the class that some box overlaps at the IoU threshold: no
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
  std::map<std::string, std::map<std::string, int>> confusion;  ///< truth -> label -> boxes on objects
  int fallback_boxes = 0;  ///< multi view: boxes labelled by their own candidate (see README)
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
void scoreFrame(const std::vector<std::string>& model_classes, const std::vector<LabelledBox>& boxes,
                const std::vector<GroundTruthBox>& truth, double iou_threshold, RecognitionScores* scores);

/// Pools the detections of another sequence (AP of the pool, not a mean of APs).
void mergeRecognition(RecognitionScores* into, const RecognitionScores& more);

/// The report section: {"mAP", "recall", "per_class": {c: {"AP", "precision", "recall"}}} in %
/// (null where undefined: AP and recall of a class without ground truth, precision of a class
/// never reported), plus counts and the diagnostics.
nlohmann::json recognitionSection(const RecognitionScores& scores);

/// Precision-recall curves per class (classes with ground truth), single and multi view, one
/// panel per class, into a PNG.
void drawPrCurves(const RecognitionScores& single, const RecognitionScores& multi, const std::string& title,
                  const std::string& path);

// ---- Multi-view labels ------------------------------------------------------------------------

/// Replays the messages the objectmap node gets (CAMERA_INFO, SLAM_MAP, SLAM_POSE, PROPOSALS,
/// DETECTIONS, in the order it got them) through the object map library, and then labels a box by
/// the object its candidate belongs to at the end: the object's posterior (softmax of the summed
/// log-evidence of all its views). A candidate the object map does not hold (its boxes were all
/// refused) falls back to its own evidence: the sum over the sequence of its boxes' log p (one box
/// per frame, the larger; each clamped to [-100, 0] as the object map clamps), softmax. (A
/// candidate without voxels is an object of its own in the map, so its label is its own evidence
/// too.)
class MultiViewLabeller {
 public:
  explicit MultiViewLabeller(const ObjectMapOptions& options);

  void onCameraInfo(const camera_info_t& m);
  void onMap(const point_cloud_t& m);
  void onPose(const pose_t& m);
  void onProposals(const proposals_t& m);
  void onDetections(const detections_t& m);

  /// log p(class | every view of the candidate's object) for `classes` (a class the object map
  /// lacks gets -inf); *from_object is false when the fallback was used.
  std::vector<double> logPosterior(int32_t map_id, int32_t candidate, const std::vector<std::string>& classes,
                                   bool* from_object = nullptr);

  ObjectMapEngine& engine() { return engine_; }
  /// Messages the object map refused (with the reason logged at debug level).
  int refused() const { return refused_; }

 private:
  /// Counts (and logs at debug level) a message the object map refused.
  void countRefusal(bool accepted, const char* channel, const std::string& why);
  struct OwnView {
    float area = 0;
    std::vector<float> log_p;  ///< in own_classes_ order
  };
  ObjectMapEngine engine_;
  std::vector<std::string> own_classes_;
  std::map<std::pair<int32_t, int32_t>, std::map<int32_t, OwnView>> own_;  ///< (map, candidate) -> seq -> view
  int refused_ = 0;
  FusionOptions fusion_;  ///< as the map fuses
};

// ---- A sequence ------------------------------------------------------------------------------

/// The boxes of DETECTIONS by frame seq, with single-view and multi-view scores.
struct RecognitionRecording {
  struct Box {
    LabelledBox single;  ///< the box's own p(class | box)
    LabelledBox fused;   ///< p(class | every view of its object): label and score
    LabelledBox multi;   ///< label of `fused`, scored by scoreMultiView()
    int32_t map_id = -1, candidate = -1;
    int32_t object = -1;  ///< id of its object in the replayed map (-1: fallback)
    double log_objectness = 0;  ///< log p(object | box): its own view's, its candidate's, its object's (scoreMultiView)
    bool multi_from_object = true;
  };
  std::vector<std::string> classes;  ///< the model's, background last
  std::map<int32_t, std::vector<Box>> frames;
  int objects = 0;  ///< objects of the object map at the end
  int candidates = 0;
  int duplicates = 0;  ///< boxes demoted by demoteDuplicateBoxes()
  nlohmann::json object_map;  ///< objectMapSummary() of the replayed map at the end
  /// The replay against the node: 1 when the replayed map's objects (labels, views, voxels) equal
  /// those of the last OBJECT_MAP the objectmap node published, 0 when not, -1 when the recording
  /// has no OBJECT_MAP.
  int matches_node = -1;

  bool empty() const { return classes.empty(); }
};

/// What the object map holds (the "object_map" section of a sequence): segments, objects,
/// labelled objects, and in the segment whose objects hold the most voxels: its objects, the voxels
/// they hold together (union) and the share of them the largest object holds — near 100 % when the
/// scene is one object and its parts lie in it (the Middlebury temple), so "one dominant object".
nlohmann::json objectMapSummary(const ObjectMapEngine& engine);

/// log(1 - p(background)) from log-probabilities with the background last (0 for none).
double logObjectness(const std::vector<double>& log_p);

/// The multi-view detection scores of a box (log, in the model's class order, background last)
/// from its object's fused posterior and p(c, object | box) per class (log_box, as long as
/// fused_log_p; otherwise the fused posterior unchanged): p(c) = p(c | object's views) x
/// exp(log_box[c]) for each object class, p(background) the rest. The object's views say which
/// object it is; only the box's views can say whether this box frames the whole object (a box on a
/// part of a mug, or on the mug and half the table, is a view of the mug's object but not a mug
/// detection). The reported label stays the fused posterior's argmax.
std::vector<double> multiViewScores(const std::vector<double>& fused_log_p, const std::vector<double>& log_box);

/// Scores every box of a recording (`frames`, their single and fused log p set) as a multi-view
/// detection: for each object class c, p(c | object's views) x the geometric mean of three: the
/// box's own view's p(c | box), the mean of 1 - p(background) over every box of its candidate in
/// the recording (a candidate that is a part of an object, or an object with a stretch of table, is
/// boxed alike in most of its views, and most of them say so; one view alone is noisy), and the
/// median of that over every box of its object (all its candidates; a box without an object: its
/// candidate's median). The last is what the object's typical view says of whether it is an object
/// at all: the fused class posterior weights each view by its objectness, so a distractor that most
/// of its views call background gets the class its few other views give it (lab_marble's mushroom:
/// 242 of its 309 boxes called background, fused bowl 0.71). The median, not the mean: an object's
/// boxes are of several candidates (the object, a part, the object with its neighbour), and a
/// minority of sure views does not make it an object. The box's own view says how well *this box*
/// shows an object of class c: a box on a part of the object or on it and its neighbour is less
/// sure of the object's class than one that frames it, even where both are sure they frame an
/// object. `log_objectness` keeps the mean with the box's own 1 - p(background | box).
void scoreMultiView(std::map<int32_t, std::vector<RecognitionRecording::Box>>* frames);

/// The width of demoteDuplicateBoxes()'s Gaussian, in the squared share of a box inside the kept one.
constexpr double kDuplicateSigma = 0.1;

/// An object is one detection per frame. Of the boxes of one frame (`boxes`) whose candidates
/// belong to the same object of the map, the one its own view finds most object-like (lowest
/// p(background | box); ties: the earlier box) keeps its multi-view scores; the others are
/// duplicates of it, demoted as by Soft-NMS (Bodla et al. 2017) with a Gaussian of the share s of
/// their area that lies inside the kept box: their object classes are scaled by
/// exp(-s^2 / kDuplicateSigma), at least by e^-100. A box that frames the object much as the kept
/// one does, or a part of it inside the kept box (a cereal box's side face, which the fused
/// evidence calls a cereal box as well), ranks below every detection; a box of the same object
/// that lies mostly outside the kept one (another of its parts, or the whole object around a
/// kept sliver of it) keeps most of its score. Their label, the object's, stays. Boxes without an
/// object (-1), and boxes that do not overlap the kept one, are left alone. Returns the number of
/// duplicates demoted.
int demoteDuplicateBoxes(std::vector<RecognitionRecording::Box>* boxes);

/// Reads DETECTIONS of a recorded log and replays it through MultiViewLabeller (`options`: the
/// objectmap stage's). Throws LogError for a damaged log. Empty when the log has no DETECTIONS.
RecognitionRecording readRecognitionRecording(const std::string& log_path, const Channels& channels,
                                              const ObjectMapOptions& options);

struct RecognitionEvalOptions {
  int stride = 5;  ///< every stride-th frame (the proposals section's frames)
  double iou = 0.5;
};

struct RecognitionResult {
  RecognitionScores single, multi;
  RecognitionScores fused;  ///< multi-view ranked by the fused posterior alone (a diagnostic)
  std::vector<std::string> classes;  ///< evaluated: the model's (background excluded) that the sequence lists
};

/// The classes a sequence is evaluated on: the model's object classes that its sequence.yaml lists.
std::vector<std::string> evaluatedClasses(const std::vector<std::string>& model_classes,
                                          const SequenceFolder& sequence);

/// Scores every stride-th frame of the sequence (frames without boxes count: their ground truth is
/// missed).
RecognitionResult scoreRecognition(const RecognitionRecording& run, const SequenceFolder& sequence,
                                   const RecognitionEvalOptions& options);

}  // namespace slamaware
