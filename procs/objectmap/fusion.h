#pragma once
// Multi-view class fusion (docs/architecture.md §3; Pillai & Leonard 2015, Sec. IV-D). With views
// x_1..x_N of one object taken as independent and a uniform prior p(c), Bayes gives
//   p(c | x_1..x_N) ∝ p(c) ∏_i p(x_i | c) ∝ ∏_i p(c | x_i) / p(c)^(N-1) ∝ ∏_i p(c | x_i),
// so the maximum-likelihood label is argmax_c sum_i log p(c | x_i). The object map keeps that sum
// (the log evidence) per class; the posterior is its softmax.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace slamaware::objectmap {

/// Log-probabilities are clamped here where the map takes them in: e^-100 is zero for every
/// purpose, and sums stay finite.
constexpr float kMinLogProb = -100.f;

/// How the views of an object are fused (ObjectMapOptions: objectness_weights,
/// posterior_views_exponent; see sumLogProbabilities() and posteriorFromLogEvidence()).
struct FusionOptions {
  bool objectness_weights = false;
  double views_exponent = 0;
};

/// sum_i log p(c | x_i) per class over the views (each a vector of natural-log probabilities, one
/// per class, num_classes long). Summed in double, in the order given.
///
/// objectness_weights: sum_i w_i log p(c | x_i) with w_i = 1 - p(background | x_i), the last class
/// being background: the product of the views' p(c | x_i)^w_i. A view whose box the recognizer
/// takes for background (the object cut by the image border, hidden, or the box off the object)
/// says little about which object it is and counts little; views of the whole object count fully.
/// total_weight (if given): sum_i w_i (the number of views without objectness weights).
/// frames (empty: 1 each): how many frames each view stands for (the object map merges old views);
/// its term counts that many times. objectness (empty, or < 0 for a view: 1 - p(background | x_i)):
/// the w_i of each view (a merged view's is its frames' mean).
std::vector<double> sumLogProbabilities(const std::vector<const std::vector<float>*>& views,
                                        size_t num_classes, bool objectness_weights = false,
                                        double* total_weight = nullptr,
                                        const std::vector<int32_t>& frames = {},
                                        const std::vector<double>& objectness = {});

/// p(c | all views) = softmax of the summed log evidence (shifted by its maximum, so that sums of
/// hundreds of views do not underflow). Empty in, empty out.
///
/// views_exponent e > 0: softmax of log_evidence / W^e, W = the views' total weight (at least 1).
/// The views of one object are far from independent (neighbouring frames see nearly the same
/// image), and with e = 0 the posterior of an object seen in a few dozen views is 0 or 1 whatever
/// its views said. e = 1 makes it the normalised weighted geometric mean of the views' posteriors
/// (what the average view says); e = 0.5 lets the evidence grow with the square root of the views.
/// The argmax, the label, is the same for every e.
std::vector<double> posteriorFromLogEvidence(const std::vector<double>& log_evidence,
                                             double total_weight = 1, double views_exponent = 0);

/// The evidence as posteriorFromLogEvidence() scales it: log_evidence / max(1, W)^e.
std::vector<double> scaledLogEvidence(const std::vector<double>& log_evidence, double total_weight,
                                      double views_exponent);

/// Of two boxes of one object in one frame, whether view a (its natural-log p per class, background
/// last; its box's area) frames the object better than view b, so that a frame counts once: the
/// view that finds its box most object-like (the lower p(background | box)), the larger box on a
/// tie. A box on the object and its neighbour is larger than the box on the object alone, but its
/// view is less sure that it sees one object. An empty view has p(background) 1.
bool moreObjectLikeView(const std::vector<float>& log_p_a, double area_a,
                        const std::vector<float>& log_p_b, double area_b);

/// log(1 - p(background)) from natural-log probabilities with the background last (0 for none),
/// exact also for p(background) near 0 or 1.
double logObjectness(double log_p_background);

/// The class with the highest value; ties go to the lower index; -1 for an empty vector.
int argmaxClass(const std::vector<double>& values);

}  // namespace slamaware::objectmap
