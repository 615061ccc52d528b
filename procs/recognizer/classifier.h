#pragma once
// Linear classifiers on encoded boxes: one-vs-all logistic regression with L2 regularisation,
// trained by SGD, and the calibration that turns its scores into log-probabilities that can be
// summed across views.
//
// Calibration. The C one-vs-all scores s_c = w_c . x + b_c of a box are turned into one
// distribution over the classes: p(c | x) = (1 - mix) softmax_c(s / T) + mix / C. The temperature T
// and the floor `mix` are fitted on held-out data (instances and scene frames the classifiers did
// not see) by minimising the negative log-likelihood. Summing log p over views (naive Bayes with a
// uniform prior, DESIGN.md §3) then behaves: a fitted T undoes the over-confidence of scores on
// training-like data, and the floor keeps one bad view from vetoing a class (log p >= log(mix/C)).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "procs/recognizer/encoding_params.h"

namespace slamaware {

/// Encoded examples (rows of vladDims floats) stored in half precision (IEEE binary16), with a
/// class label and a group (e.g. the object instance) each. The rows are held in blocks of
/// kRowsPerBlock, each allocated once at its full size: a growing set never copies itself into a
/// buffer twice its size (a 100k-D row is 210 kB; a trainer's tens of thousands of rows fill most of
/// the memory, and one doubling of a single buffer was what ran out of it).
class ExampleSet {
 public:
  static constexpr int64_t kRowsPerBlock = 128;
  explicit ExampleSet(int64_t dims = 0) : dims_(dims) {}
  int64_t dims() const { return dims_; }
  int64_t size() const { return static_cast<int64_t>(labels_.size()); }
  /// Appends a row (rounded to half precision).
  void add(const float* x, int label, int group = -1);
  /// Appends every example of `other` (same dims).
  void append(const ExampleSet& other);
  int label(int64_t i) const { return labels_[static_cast<size_t>(i)]; }
  int group(int64_t i) const { return groups_[static_cast<size_t>(i)]; }
  /// Row i converted to float.
  void get(int64_t i, float* out) const;
  /// Keeps the examples for which keep(i) is true.
  void filter(const std::function<bool(int64_t)>& keep);
  /// A copy of the examples for which keep(i) is true.
  ExampleSet select(const std::function<bool(int64_t)>& keep) const;
  /// Bytes of the rows held.
  size_t bytes() const { return static_cast<size_t>(size()) * rowBytes(dims_); }
  /// Bytes of one row of `dims` values.
  static size_t rowBytes(int64_t dims) { return static_cast<size_t>(dims) * sizeof(uint16_t); }
  /// Bytes allocated for rows: at most one block more than bytes().
  size_t allocatedBytes() const;

 private:
  uint16_t* row(int64_t i);
  const uint16_t* row(int64_t i) const;
  /// Room for one more row at the end, with its label and group (a new block when the last is full).
  uint16_t* newRow(int label, int group);
  /// Keeps the first n rows and releases the blocks past them.
  void truncate(int64_t n);

  int64_t dims_;
  std::vector<std::vector<uint16_t>> blocks_;
  std::vector<int> labels_, groups_;
};

/// Round-trip of floats through half precision (exposed for tests).
void floatsToHalf(const float* in, int64_t n, uint16_t* out);
void halfToFloats(const uint16_t* in, int64_t n, float* out);

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
/// L2 regularisation. Deterministic for given examples and options. `progress(epoch)` is called
/// after each epoch when set.
LinearClassifier trainOneVsAll(const ExampleSet& examples, const std::vector<std::string>& classes,
                               const SgdOptions& options,
                               const std::function<void(int)>& progress = {});

/// Fits temperature and floor on held-out scores (B x C) with labels; returns the mean negative
/// log-likelihood reached.
double calibrate(const MatrixRM& scores, const std::vector<int>& labels,
                 LinearClassifier* classifier);

}  // namespace slamaware
