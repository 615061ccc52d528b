#pragma once
// Linear classifiers on encoded boxes: one-vs-all logistic regression with L2 regularisation,
// trained by SGD, and the calibration that turns its scores into log-probabilities that can be
// summed across views.
//
// Calibration. The C one-vs-all scores s_c = w_c . x + b_c of a box are turned into one
// distribution over the classes: p(c | x) = (1 - mix) softmax_c(s / T) + mix / C. The temperature T
// and the floor `mix` are fitted on held-out data (instances and scene frames the classifiers did
// not see) by minimising the negative log-likelihood. Summing log p over views (naive Bayes with
// a uniform prior, docs/architecture.md §3) then behaves: a fitted T undoes the over-confidence
// of scores on training-like data, and the floor keeps one bad view from vetoing a class (log p >=
// log(mix/C)).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "procs/recognizer/encoding_params.h"
#include "procs/recognizer/example_set.h"

namespace slamaware::recognizer {

struct SgdOptions {
  double lambda = 1e-4;    ///< L2 regularisation weight
  int epochs = 30;         ///< passes over the data
  double eta0 = 1.0;       ///< learning rate eta_t = eta0 / (1 + lambda eta0 t)
  double bias_rate = 0.1;  ///< the bias learns at this fraction of the rate (it is not regularised)
  bool balance = true;     ///< weight positives and negatives of each class equally
  int seed = 1;            ///< order of the examples

  template <class V>
  void visit(V& v) {
    v("lambda", lambda, "L2 regularisation weight");
    v("epochs", epochs, "SGD passes over the training examples");
    v("eta0", eta0, "initial learning rate; eta_t = eta0 / (1 + lambda eta0 t)");
    v("bias_rate", bias_rate, "learning-rate factor of the (unregularised) bias");
    v("balance", balance, "weight the positives and negatives of each class equally");
    v("seed", seed, "seed of the example order");
  }
};

struct LinearClassifier {
  std::vector<std::string> classes;  ///< the last one is "background" when trained with negatives
  MatrixRM weights;                  ///< C x dims
  Eigen::VectorXf bias;              ///< C
  float temperature = 1.f;           ///< calibration (see the top of this file)
  float uniform_mix = 0.f;

  int numClasses() const { return static_cast<int>(classes.size()); }
  int64_t dims() const { return weights.cols(); }
  /// One-vs-all scores of the rows of x (B x dims): s = x W^T + b, one matrix product.
  void scores(const Eigen::Ref<const MatrixRM>& x, MatrixRM* s) const;
  /// Calibrated natural-log probabilities from scores (B x C); rows sum to 1 in probability.
  void logProbabilities(const MatrixRM& scores, MatrixRM* log_p) const;
  /// Index of `name` in classes, -1 if absent.
  int classIndex(const std::string& name) const;
};

/// log p of one row of scores under a calibration (T, mix), into out (C floats).
void calibratedLogProbabilities(const float* scores, int C, float temperature, float uniform_mix,
                                float* out);

/// Trains one logistic regression per class (label == c against all other examples) by SGD with
/// L2 regularisation. Deterministic for given examples and options, and the same for any number of
/// `threads` (0: one per core; the classes are split among them). `progress(epoch)` is called
/// after each epoch when set.
LinearClassifier trainOneVsAll(const ExampleSet& examples, const std::vector<std::string>& classes,
                               const SgdOptions& options,
                               const std::function<void(int)>& progress = {}, int threads = 1);

/// Fits temperature and floor on held-out scores (B x C) with labels; returns the mean negative
/// log-likelihood reached.
double calibrate(const MatrixRM& scores, const std::vector<int>& labels,
                 LinearClassifier* classifier);

}  // namespace slamaware::recognizer
