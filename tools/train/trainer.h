#pragma once
// Training the recognizer's model from object sets (labelled crops) and scene sequences with
// ground-truth boxes (boxes.csv): their objects of the model's categories are positives (boxes as
// the proposals stage draws them: jittered), everything else in them (other objects included) is
// background.
//
//  1. Split: one instance of each category with >= 2 instances is held out (categories with a
//     single instance hold out every 5th view); of the scenes, one whole sequence when there are
//     several (its neighbouring frames would otherwise be near copies of training frames and the
//     calibration over-confident), else every `holdout_frame_every`-th frame.
//  2. Vocabulary: raw features of the training crops and scene frames, a shuffled subset of
//     `vocabulary_descriptors` of them -> PCA (D dims) -> VLFeat k-means (K codewords).
//  3. Examples: every crop encoded as one box covering it (a crop of a loose photographed set:
//     its object's box, collectCrops), and `context_copies` times more pasted
//     at a random place of a random scene frame (a box in a frame sees its surroundings, a crop
//     alone only its mirrored border); per scene frame `negatives_per_frame` random boxes that
//     overlap no ground-truth box (IoU < 0.1); per `scene_positive_every`-th scene frame, each
//     ground-truth box and `positive_jitter` boxes around it (IoU >= `positive_min_iou`): labelled
//     with the object's category, or background for a category the model does not have; and
//     `partial_negatives` boxes that cut or overhang it (IoU in [`partial_min_iou`,
//     `partial_max_iou`) with it and below `partial_max_iou` with every object): background. A box
//     on a part of a mug, or on a mug and half the table, is not a mug detection (it scores as a
//     false positive), and without these the classifier never saw one labelled so. With proposal
//     boxes (`--proposals`: what the proposals stage drew on a SLAM run of each scene), every
//     `proposal_every`-th frame also gives every proposal box: a view of the object it overlaps by
//     IoU >= `proposal_positive_iou`, background below `proposal_background_iou` with every object
//     (its parts, an object with table, several objects, the table), nothing in between. These are
//     the boxes the recognizer is given at run time, framed as the pipeline frames them.
//  4. One-vs-all logistic regression (SGD, L2) over the categories + "background", then
//     `mining_rounds` rounds of hard-negative mining: `mining_candidates_per_frame` new random
//     background boxes per training frame are scored and those the current model takes for an
//     object (p(background) < 0.5) are added, up to `mining_max_per_round`, and the
//     classifiers are retrained.
//  5. Calibration (classifier.h) on the held-out crops and frames, validation summary on them;
//     then the classifiers are retrained on all data with the same options (the calibration and
//     the summary stay those of the held-out data).
#include <cstdint>
#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "procs/recognizer/classifier.h"
#include "procs/recognizer/frame_encoder.h"
#include "procs/recognizer/model.h"

namespace slamaware::recognizer {

struct TrainOptions {
  EncodingParams encoding;
  /// The model's categories; crops of the object sets' other categories are background examples
  /// (a real object set of many categories). Empty: every category of the object sets.
  std::vector<std::string> classes;
  /// Within a class that has both rendered and photographed examples, the photographed ones carry
  /// this share of the class's weight (the same share in every class, background included, so that
  /// looking like a photograph is no evidence for any class); <= 0: every example weighs 1.
  double real_share = 0.5;
  /// Standard deviation of the Gaussian added to the log aspect ratio of every training box's
  /// shape block (FrameEncoder::setShapeNoise): how far a box the proposals draw around an object
  /// differs in aspect from the object's own box (measured on the training scenes, README). A
  /// class is then told apart by its shape only where it differs by more than boxes do.
  double shape_noise = 0.15;
  int seed = 7;                         ///< every random choice of the trainer
  int vocabulary_descriptors = 100000;  ///< features sampled for PCA and k-means
  int kmeans_iterations = 100;
  int max_views_per_instance = 72;  ///< 0 = every view (72: every 3rd of a 216-view turntable)
  int background_views_per_instance = 16;  ///< views per instance of a background object set
  int context_copies = 1;                  ///< crops also encoded pasted into scene frames
  int real_copies = 0;       ///< photographed crops also pasted varied (scale, colour, blur)
  bool mirror_crops = true;  ///< crops also encoded mirrored left-right
  /// Encoded training examples kept in the model per object class (background: 4 times as many),
  /// evenly spread over the training data, so that `slamaware-train --base` can add classes later.
  int exemplars_per_class = 40;
  SgdOptions sgd;
  int negatives_per_frame = 4;
  int mining_rounds = 2;
  int mining_candidates_per_frame = 40;
  int mining_max_per_round = 1000;
  double negative_max_iou = 0.1;  ///< background boxes overlap every object less than this
  int negative_min_size_px = 24;
  double negative_max_size = 0.6;  ///< of the image width / height
  bool validation = true;          ///< hold out data for calibration and the summary
  int holdout_frame_every = 5;     ///< (one scene only) every n-th frame is held out
  int scene_positive_every = 4;    ///< every n-th scene frame gives its objects' boxes (0: none)
  int positive_jitter = 2;         ///< jittered boxes per ground-truth box
  double positive_min_iou = 0.6;   ///< a jittered box overlaps its object at least this much
  int partial_negatives = 2;       ///< background boxes cutting or overhanging each scene object
  double partial_min_iou = 0.1;    ///< ... that overlap it at least this much
  double partial_max_iou = 0.4;    ///< ... and it (and every other object) less than this
  int proposal_every = 2;          ///< every n-th scene frame gives its proposal boxes (0: none)
  double proposal_positive_iou =
      0.5;  ///< a proposal box this close to an object is an example of it
  double proposal_background_iou =
      0.4;  ///< a proposal box below this with every object is background
  /// A proposal box overlapping one ranked ahead of it (earlier in the file) by more than this IoU
  /// is not used (>= 1: every box). The dumps hold every box the proposals stage draws (the
  /// recognizer suppresses after classifying them); the shipped model was trained on them
  /// suppressed at 0.5 in the stage's order, and twice the boxes would need about twice the memory.
  double proposal_nms_iou = 0.5;
  /// Threads of the long loops (0: one per core). Not an option of the model: the model is the same
  /// for any number, so it is neither read from config files nor written into the provenance
  /// (slamaware-train --threads).
  int threads = 0;

  template <class V>
  void visit(V& v) {
    v.section("encoding", encoding);
    v("classes", classes,
      "the model's categories; the object sets' other categories are background (empty: all of "
      "them)");
    v("real_share", real_share,
      "share of each class's weight carried by its photographed examples when it also has rendered "
      "ones "
      "(<= 0: all examples weigh the same)");
    v("shape_noise", shape_noise,
      "standard deviation added to each training box's log aspect ratio (box shape noise)");
    v("seed", seed, "seed of every random choice of the trainer");
    v("vocabulary_descriptors", vocabulary_descriptors, "features sampled for PCA and k-means");
    v("kmeans_iterations", kmeans_iterations, "maximum k-means iterations");
    v("max_views_per_instance", max_views_per_instance, "views used per object instance (0 = all)");
    v("background_views_per_instance", background_views_per_instance,
      "views used per instance of the --background-objects sets (0 = all)");
    v("context_copies", context_copies, "copies of each crop pasted into random scene frames");
    v("real_copies", real_copies,
      "copies of each photographed crop pasted into scene frames scaled, mirrored, recoloured and "
      "blurred");
    v("mirror_crops", mirror_crops, "training crops also encoded mirrored left-right");
    v("exemplars_per_class", exemplars_per_class,
      "encoded examples kept in the model per object class (background: 4x) for adding classes "
      "later");
    v.section("sgd", sgd);
    v("negatives_per_frame", negatives_per_frame, "initial background boxes per scene frame");
    v("mining_rounds", mining_rounds, "rounds of hard-negative mining");
    v("mining_candidates_per_frame", mining_candidates_per_frame,
      "background boxes scored per frame and round");
    v("mining_max_per_round", mining_max_per_round, "hard negatives added per round at most");
    v("negative_max_iou", negative_max_iou,
      "background boxes overlap every object box less than this IoU");
    v("negative_min_size_px", negative_min_size_px, "px, smallest background box side");
    v("negative_max_size", negative_max_size, "largest background box side, fraction of the image");
    v("validation", validation,
      "hold out instances and frames for calibration and the validation summary");
    v("holdout_frame_every", holdout_frame_every,
      "with one scene sequence, every n-th frame is held out");
    v("scene_positive_every", scene_positive_every,
      "every n-th scene frame gives its objects' boxes (0: none)");
    v("positive_jitter", positive_jitter, "jittered boxes per ground-truth box of a scene");
    v("positive_min_iou", positive_min_iou,
      "a jittered box overlaps its object at least this much");
    v("partial_negatives", partial_negatives,
      "background boxes cutting or overhanging each object of a scene frame that gives positives");
    v("partial_min_iou", partial_min_iou, "a partial box overlaps its object at least this much");
    v("partial_max_iou", partial_max_iou, "a partial box overlaps every object less than this");
    v("proposal_every", proposal_every,
      "every n-th scene frame gives its proposal boxes (0: none)");
    v("proposal_positive_iou", proposal_positive_iou,
      "a scene's proposal box with this IoU with an object is an example of that object");
    v("proposal_background_iou", proposal_background_iou,
      "a scene's proposal box with less IoU than this with every object is background");
    v("proposal_nms_iou", proposal_nms_iou,
      "a scene's proposal box overlapping one ranked ahead by more than this IoU is not used (>= "
      "1: all)");
  }
};

/// One labelled crop.
struct LabeledCrop {
  std::string path;
  std::string category;
  std::string instance;
  std::string mask_path;  ///< the object's pixels ("" if the set has no mask)
  bool real = false;      ///< photographed (false: rendered by the generator)
  /// Where the object is in a loose crop (collectCrops); empty: the crop is framed by its object.
  cv::Rect object_box;
};

/// A scene frame with its ground-truth object boxes (anything else in it is background).
struct SceneFrame {
  std::string path;
  std::string sequence;
  int index = 0;
  std::vector<cv::Rect2d> objects;
  std::vector<std::string> object_classes;  ///< category of each of `objects`
  std::vector<cv::Rect2d> proposals;  ///< boxes the proposals stage drew in this frame (if known)
  bool real = false;                  ///< photographed (false: rendered by the generator)
};

/// The crops of the object sets (categories merged by name across sets), at most
/// max_views_per_instance per instance (evenly spaced). A photographed set whose objects cover
/// under half of their crops (GrabCut, median of 16) is loose: its crops without a mask get their
/// object's box (objectBoxInCrop, object_box.h). Throws DatasetError.
std::vector<LabeledCrop> collectCrops(const std::vector<std::string>& object_dirs,
                                      int max_views_per_instance);
/// The crops of one object set with their instances named after the set ("<set>/<instance>": two
/// sets may both hold a "ball_1").
std::vector<LabeledCrop> collectNamedCrops(const std::string& object_dir,
                                           int max_views_per_instance);
/// The frames of sequence folders with boxes.csv. Throws DatasetError (also for a folder without
/// boxes.csv: its background is unknown). With `proposals_dir`, each frame also gets the boxes of
/// `<proposals_dir>/<sequence folder name>.csv` (`frame,rank,x,y,w,h`, written by
/// `slamaware-eval --dump-proposals`): the boxes the proposals stage drew on a run of the
/// sequence, so that the classifiers also learn from boxes as the pipeline will draw them. A
/// sequence without its file is trained without proposals (and says so); a damaged file throws.
std::vector<SceneFrame> collectSceneFrames(const std::vector<std::string>& sequence_dirs,
                                           const std::string& proposals_dir = "");
/// Reads a proposal-box file (`frame,rank,x,y,w,h` per line after a header) into boxes per frame.
/// Throws DatasetError naming the file and line for a malformed line.
std::map<int, std::vector<cv::Rect2d>> readProposalBoxes(const std::string& path);
/// The examples a frame's proposal boxes give: the label of each box (index into `classes`; an
/// object of a category the model lacks is `background`), or -1 for a box between the two IoU
/// thresholds (neither a view of an object nor background) and for a box suppressed by one ahead
/// of it (proposal_nms_iou). With `aspect_offsets`, appends for each box that is a view of an
/// object ln(aspect of the box) - ln(aspect of the object's box): the spread shape_noise stands
/// for.
std::vector<int> labelProposals(const SceneFrame& frame, const std::vector<std::string>& classes,
                                int background, const TrainOptions& options,
                                std::vector<double>* aspect_offsets = nullptr);

/// Sets the weights of `set`'s examples (ExampleSet::weight, ExampleSet::domain: 1 photographed) so
/// that in every class holding both domains the photographed examples carry `real_share` of the
/// class's weight and the rendered ones the rest, the class's total weight staying its number of
/// examples; the examples of a class with one domain weigh 1. The domain then carries no evidence
/// for a class: without it, a training set of many rendered objects and few photographed ones,
/// most of them background, teaches that looking like a photograph means background. No change
/// for real_share outside (0, 1).
void balanceDomains(ExampleSet* set, int classes, double real_share);

/// The exemplars a model keeps (RecognizerModel::exemplars): of each label below `classes`,
/// `per_class` examples (label `background`: 4 times as many) evenly spread over the set's order,
/// each with weight 1.
ExampleSet pickExemplars(const ExampleSet& set, int classes, int background, int per_class);

/// `count` boxes around `object` (scaled and shifted at random) that overlap it by IoU >= min_iou
/// and lie in the image.
std::vector<cv::Rect2d> jitteredBoxes(const cv::Rect2d& object, int width, int height, int count,
                                      double min_iou, uint32_t seed);
/// `count` boxes on a part of `objects[index]` or overhanging it (scaled and shifted at random,
/// in the image) with IoU in [min_iou, max_iou) with it and < max_iou with each of `objects`.
std::vector<cv::Rect2d> partialBoxes(const std::vector<cv::Rect2d>& objects, size_t index,
                                     int width, int height, int count, double min_iou,
                                     double max_iou, uint32_t seed);
/// `count` random boxes of an image that overlap each of `objects` by IoU < max_iou.
std::vector<cv::Rect2d> randomBackgroundBoxes(int width, int height,
                                              const std::vector<cv::Rect2d>& objects, int count,
                                              const TrainOptions& options, uint32_t seed);

/// Fits PCA and vocabulary on a shuffled subset of the raw features of the crops and frames.
void fitEncoding(const std::vector<LabeledCrop>& crops, const std::vector<SceneFrame>& frames,
                 const TrainOptions& options, Pca* pca, Vocabulary* vocabulary,
                 const std::function<void(int64_t, int64_t)>& progress = {});

/// Encodes each crop as one box covering it into an ExampleSet (label = index of its category in
/// `classes`, `other_label` for a category not in it; group = index of its instance in
/// `instances`); with `mirror`, each crop is followed by its left-right mirror image.
ExampleSet encodeCrops(const std::vector<LabeledCrop>& crops,
                       const std::vector<std::string>& classes,
                       const std::vector<std::string>& instances, FrameEncoder& encoder,
                       bool mirror = false,
                       const std::function<void(int64_t, int64_t)>& progress = {},
                       int other_label = -1);

struct ValidationSummary {
  bool available = false;
  std::vector<std::string> held_out_instances;
  int64_t crops = 0;               ///< held-out crops
  double object_accuracy = 0;      ///< % of held-out crops whose best object class is right
  double accuracy = 0;             ///< % of held-out crops whose best class overall is right
  int64_t negatives = 0;           ///< held-out background boxes
  double background_accuracy = 0;  ///< % of them classified background
  int64_t real_crops = 0;          ///< held-out crops of photographed instances
  double real_accuracy = 0;        ///< % of them whose best class overall is right
  int64_t real_negatives = 0;      ///< held-out background boxes of photographed frames and objects
  double real_background_accuracy = 0;          ///< % of them classified background
  double nll = 0;                               ///< mean negative log-likelihood after calibration
  std::vector<std::vector<int64_t>> confusion;  ///< [true class][predicted class]
};

struct TrainReport {
  std::vector<std::string> classes;
  int64_t train_crops = 0, train_negatives = 0;
  std::vector<int64_t> mined;  ///< hard negatives added per round
  ValidationSummary validation;
  std::string toJson() const;
  std::string toText() const;
};

/// What a trained model was trained on, from its provenance (slamaware-train --report MODEL): its
/// classes, the object sets and scenes with what was used of them, the validation on held-out data,
/// the training time and peak memory, and the options as a config file that trains it again.
std::string provenanceText(const RecognizerModel& model);

/// What addClasses() did.
struct AddClassesReport {
  std::vector<std::string> added, replaced;  ///< classes new to the model, and retrained ones
  int64_t views = 0;                      ///< crops read (each also mirrored: train.mirror_crops)
  int64_t positives = 0, background = 0;  ///< encoded examples of the classes, of background
  int64_t exemplars = 0;                  ///< the base model's exemplars trained on
  double seconds = 0;
  std::string toText() const;
};

/// A model that knows the categories of `object_dirs` (object sets, e.g. harvested by
/// slamaware-harvest; their category "background" is background) besides the classes of `base`,
/// made without the base's training data: the base's encoding (PCA, vocabulary), calibration and
/// classifiers are kept as they are; a classifier for each new category is trained on its views
/// against the base's exemplars (RecognizerModel::exemplars) and the sets' background. A category
/// the base already has is refused unless `replace` (then its exemplars are dropped and its
/// classifier is trained anew the same way). Throws std::runtime_error (DatasetError for unreadable
/// sets) for a base without exemplars or background, or sets without views of a class.
RecognizerModel addClasses(const RecognizerModel& base, const std::vector<std::string>& object_dirs,
                           const TrainOptions& options, bool replace, AddClassesReport* report);

/// Category accuracy of an object set on instances unseen in training. Each fold holds out a set of
/// instances: PCA, vocabulary and classifiers are trained on the other instances only (no
/// background class) and every crop of the held-out instances is classified by the best category.
struct HeldOutResult {
  std::string protocol;  ///< "leave-one-instance-out" or "one held-out instance per category"
  std::vector<std::string> classes;
  std::vector<std::string> instances;
  std::vector<std::vector<int64_t>> confusion;      ///< [true category][predicted category]
  std::map<std::string, double> instance_accuracy;  ///< % per held-out instance
  int64_t crops = 0, correct = 0;
  int64_t extra_crops = 0;  ///< crops of the extra training sets added to every fold
  double accuracy() const { return crops ? 100.0 * correct / crops : 0; }
};
using FoldProgress = std::function<void(const std::string& stage, int64_t done, int64_t total)>;
/// Every instance in turn (as many folds as instances), or only the `held_out` ones. The crops of
/// `extra_dirs` (other object sets, e.g. rendered ones) whose category the set has are added to the
/// training data of every fold; they are never tested.
HeldOutResult leaveOneInstanceOut(const std::string& object_dir, const TrainOptions& options,
                                  const FoldProgress& progress = {},
                                  const std::vector<std::string>& extra_dirs = {},
                                  const std::vector<std::string>& held_out = {});
/// One fold: one instance of each category with two or more (chosen with options.seed).
HeldOutResult oneInstancePerCategoryOut(const std::string& object_dir, const TrainOptions& options,
                                        const FoldProgress& progress = {},
                                        const std::vector<std::string>& extra_dirs = {});

/// Trains a model (see the top of this file). Progress bars go to stderr. The crops of
/// `background_object_dirs` (object sets of other categories: the things a robot sees besides the
/// model's objects) are background examples like the scenes' other objects, at most
/// `background_views_per_instance` views per instance; their categories that the model has are
/// left out.
RecognizerModel trainModel(const std::vector<std::string>& object_dirs,
                           const std::vector<std::string>& scene_dirs, const TrainOptions& options,
                           TrainReport* report, const std::string& proposals_dir = "",
                           const std::vector<std::string>& background_object_dirs = {});

}  // namespace slamaware::recognizer
