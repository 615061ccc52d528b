#pragma once
// What the map publishes per frame (OBJECT_DETECTIONS): each box of a frame's detections with its
// object, the object's fused posterior, and the score the map ranks the box by as a detection of
// each class. Only evidence fused so far is used: a label never depends on a later frame.
//
// A box of candidate k in object O is a detection of object class c with
//   p(c, box) = p(c | O's views) x p(c | box):
// O's views say which object it is; the box's own view says whether *this box* frames an object of
// that class (a box on a part of a mug, or on the mug and half the table, is a view of the mug's
// object but not a mug detection). The background gets the rest of the probability.
//
// One box per object and frame stands for it (PRIMARY): the one its own view finds most object-like
// (lowest p(background | box); ties: the earlier box). Another box of the same object that overlaps
// it is a DUPLICATE, its weights scaled by exp(-s^2 / kDuplicateSigma), s the share of its area
// inside the primary box (Soft-NMS, Bodla et al. 2017): a box framing the object as the primary
// does, or a part of it inside the primary box, ranks below every detection. A box of the object
// beside the primary one (another part) is a PART and keeps its weights. A candidate in no object
// (yet) is labelled by its own views alone (NO_OBJECT).
#include <cstdint>
#include <vector>

#include "procs/objectmap/fusion.h"
#include "procs/objectmap/object_table.h"

namespace slamaware::objectmap {

/// The width of the duplicates' Gaussian, in the squared share of a box inside the primary one.
constexpr double kDuplicateSigma = 0.1;

enum class BoxRole : int8_t { kPrimary = 0, kDuplicate = 1, kPart = 2, kNoObject = 3 };

/// One box of a frame's detections, with its view's log p(class | box) in the map's class order
/// (background last), clamped as the map fuses it.
struct FrameBox {
  double x = 0, y = 0, w = 0, h = 0;  ///< px
  int32_t candidate = -1;
  std::vector<float> log_p;
};

struct FrameBoxLabel {
  int32_t object = -1;  ///< Object::id, -1 for kNoObject
  BoxRole role = BoxRole::kNoObject;
  int label = -1;                     ///< argmax of the posterior
  std::vector<double> log_posterior;  ///< log p(class | the object's views so far)
  std::vector<double> log_weight;     ///< log w_c (0 for the background)
  std::vector<double> log_score;      ///< log p(c, box); the background the rest
};

/// Labels the boxes of one frame (in order) from `table` (its candidates' views must already hold
/// this frame's). `fusion`: as the map fuses (for a candidate without an object).
std::vector<FrameBoxLabel> labelFrameBoxes(const std::vector<FrameBox>& boxes,
                                           const ObjectTable& table, size_t num_classes,
                                           const FusionOptions& fusion);

/// The posterior of summed log evidence (fusion.h) in logs: log of posteriorFromLogEvidence(),
/// exact also where a sure class's posterior rounds to 1 (the ranking of sure objects stays).
std::vector<double> logPosteriorFromLogEvidence(const std::vector<double>& log_evidence,
                                                double total_weight, double views_exponent);

/// Adds log_factors[c] to each object class c of log_p (background last) and gives the background
/// the rest of the probability.
void scaleObjectClasses(std::vector<double>* log_p, const std::vector<double>& log_factors);

}  // namespace slamaware::objectmap
