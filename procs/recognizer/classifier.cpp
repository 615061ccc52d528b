#include "procs/recognizer/classifier.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#include "common/parallel.h"

namespace slamaware::recognizer {

namespace {

inline double sigmoid(double u) {
  if (u >= 0) return 1.0 / (1.0 + std::exp(-u));
  const double e = std::exp(u);
  return e / (1.0 + e);
}

}  // namespace

void LinearClassifier::scores(const Eigen::Ref<const MatrixRM>& x, MatrixRM* s) const {
  if (x.cols() != dims()) throw std::invalid_argument("LinearClassifier::scores: wrong dimension");
  s->resize(x.rows(), numClasses());
  if (x.rows() == 0) return;
  s->noalias() = x * weights.transpose();
  s->rowwise() += bias.transpose();
}

void calibratedLogProbabilities(const float* s, int C, float temperature, float uniform_mix,
                                float* out) {
  double m = -std::numeric_limits<double>::infinity();
  for (int c = 0; c < C; ++c) m = std::max(m, static_cast<double>(s[c]) / temperature);
  double z = 0;
  for (int c = 0; c < C; ++c) z += std::exp(static_cast<double>(s[c]) / temperature - m);
  const double lse = m + std::log(z);
  for (int c = 0; c < C; ++c) {
    const double log_softmax = static_cast<double>(s[c]) / temperature - lse;
    out[c] = uniform_mix > 0 ? static_cast<float>(std::log(
                                   (1.0 - uniform_mix) * std::exp(log_softmax) + uniform_mix / C))
                             : static_cast<float>(log_softmax);
  }
}

void LinearClassifier::logProbabilities(const MatrixRM& s, MatrixRM* log_p) const {
  log_p->resize(s.rows(), s.cols());
  for (int64_t r = 0; r < s.rows(); ++r)
    calibratedLogProbabilities(s.row(r).data(), static_cast<int>(s.cols()), temperature,
                               uniform_mix, log_p->row(r).data());
}

int LinearClassifier::classIndex(const std::string& name) const {
  for (size_t i = 0; i < classes.size(); ++i)
    if (classes[i] == name) return static_cast<int>(i);
  return -1;
}

LinearClassifier trainOneVsAll(const ExampleSet& examples, const std::vector<std::string>& classes,
                               const SgdOptions& options, const std::function<void(int)>& progress,
                               int threads) {
  const int C = static_cast<int>(classes.size());
  const int64_t n = examples.size(), dims = examples.dims();
  if (C < 1 || n < 1) throw std::invalid_argument("trainOneVsAll: no classes or no examples");
  // Class balance from the examples' weights: the positives of a class weigh as much as the rest.
  std::vector<double> positives(static_cast<size_t>(C), 0.0);
  double total = 0;
  for (int64_t i = 0; i < n; ++i) {
    const int l = examples.label(i);
    if (l < 0 || l >= C) throw std::invalid_argument("trainOneVsAll: label out of range");
    const double w = examples.weight(i);
    if (!(w >= 0) || !std::isfinite(w))
      throw std::invalid_argument("trainOneVsAll: example weight not finite or negative");
    positives[static_cast<size_t>(l)] += w;
    total += w;
  }
  std::vector<double> w_pos(static_cast<size_t>(C), 1.0), w_neg(static_cast<size_t>(C), 1.0);
  if (options.balance)
    for (int c = 0; c < C; ++c) {
      const double p = positives[static_cast<size_t>(c)];
      if (p > 0) w_pos[static_cast<size_t>(c)] = total / (2.0 * p);
      if (total - p > 0) w_neg[static_cast<size_t>(c)] = total / (2.0 * (total - p));
    }

  // w_c = scale_c * v_c, so that the L2 shrinkage costs O(1) per step (Bottou's SGD trick); an
  // example touches only its non-zero blocks.
  MatrixRM v = MatrixRM::Zero(C, dims);
  std::vector<double> scale(static_cast<size_t>(C), 1.0), bias(static_cast<size_t>(C), 0.0);
  std::vector<int64_t> order(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
  std::mt19937 rng(static_cast<uint32_t>(options.seed));
  const int64_t bd = examples.blockDims();
  const double lambda = options.lambda;
  // The classes learn independently from the same example order, so they are split among the
  // workers: the result is the same for any number of threads.
  const int workers = std::min(workerThreads(threads), C);
  int64_t t0 = 0;  // steps before this epoch
  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    // Fisher-Yates with mt19937's raw output (std::shuffle's use of it is implementation-defined).
    for (int64_t i = n - 1; i > 0; --i)
      std::swap(order[static_cast<size_t>(i)],
                order[static_cast<size_t>(rng() % static_cast<uint32_t>(i + 1))]);
    runWorkers(workers, [&](int w) {
      std::vector<int32_t> index;
      std::vector<float> values;
      const int c_begin = C * w / workers, c_end = C * (w + 1) / workers;
      int64_t t = t0;
      for (int64_t idx : order) {
        const int nb = examples.blocks(idx, &index, &values);
        const int label = examples.label(idx);
        const double example_weight = examples.weight(idx);
        const double eta = options.eta0 / (1.0 + lambda * options.eta0 * static_cast<double>(t));
        for (int c = c_begin; c < c_end; ++c) {
          const size_t cc = static_cast<size_t>(c);
          float* vc = v.row(c).data();
          float dot = 0;
          for (int k = 0; k < nb; ++k)
            dot += Eigen::Map<const Eigen::VectorXf>(vc + index[static_cast<size_t>(k)] * bd, bd)
                       .dot(Eigen::Map<const Eigen::VectorXf>(values.data() + k * bd, bd));
          const double s = scale[cc] * static_cast<double>(dot) + bias[cc];
          const double z = label == c ? 1.0 : -1.0;
          const double weight = example_weight * (z > 0 ? w_pos[cc] : w_neg[cc]);
          const double g = -z * weight * sigmoid(-z * s);  // d loss / d s
          scale[cc] *= 1.0 - eta * lambda;
          if (g != 0) {
            const float step = static_cast<float>(-eta * g / scale[cc]);
            for (int k = 0; k < nb; ++k)
              Eigen::Map<Eigen::VectorXf>(vc + index[static_cast<size_t>(k)] * bd, bd) +=
                  step * Eigen::Map<const Eigen::VectorXf>(values.data() + k * bd, bd);
          }
          bias[cc] -= eta * options.bias_rate * g;
          if (scale[cc] < 1e-6) {
            v.row(c) *= static_cast<float>(scale[cc]);
            scale[cc] = 1.0;
          }
        }
        ++t;
      }
    });
    t0 += n;
    if (progress) progress(epoch + 1);
  }
  LinearClassifier model;
  model.classes = classes;
  model.weights.resize(C, dims);
  model.bias.resize(C);
  for (int c = 0; c < C; ++c) {
    model.weights.row(c) = v.row(c) * static_cast<float>(scale[static_cast<size_t>(c)]);
    model.bias[c] = positives[static_cast<size_t>(c)] > 0
                        ? static_cast<float>(bias[static_cast<size_t>(c)])
                        : -20.f;
  }
  return model;
}

namespace {

double meanNll(const MatrixRM& scores, const std::vector<int>& labels, double temperature,
               double mix) {
  const int C = static_cast<int>(scores.cols());
  std::vector<float> lp(static_cast<size_t>(C));
  double nll = 0;
  for (int64_t r = 0; r < scores.rows(); ++r) {
    calibratedLogProbabilities(scores.row(r).data(), C, static_cast<float>(temperature),
                               static_cast<float>(mix), lp.data());
    nll -= lp[static_cast<size_t>(labels[static_cast<size_t>(r)])];
  }
  return nll / std::max<int64_t>(1, scores.rows());
}

}  // namespace

double calibrate(const MatrixRM& scores, const std::vector<int>& labels,
                 LinearClassifier* classifier) {
  if (scores.rows() == 0 || static_cast<size_t>(scores.rows()) != labels.size())
    throw std::invalid_argument("calibrate: need held-out scores with one label each");
  const double mixes[] = {0.0, 1e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1};
  double best = std::numeric_limits<double>::infinity(), best_t = 1, best_mix = 0;
  for (double mix : mixes) {
    // Coarse grid over log T, then golden-section search around the best point.
    double lo = std::log(0.01), hi = std::log(100.0), arg = 0,
           val = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 40; ++i) {
      const double lt = lo + (hi - lo) * i / 40.0;
      const double f = meanNll(scores, labels, std::exp(lt), mix);
      if (f < val) {
        val = f;
        arg = lt;
      }
    }
    double a = arg - (hi - lo) / 40.0, b = arg + (hi - lo) / 40.0;
    const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = b - phi * (b - a), x2 = a + phi * (b - a);
    double f1 = meanNll(scores, labels, std::exp(x1), mix),
           f2 = meanNll(scores, labels, std::exp(x2), mix);
    for (int it = 0; it < 30; ++it) {
      if (f1 < f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - phi * (b - a);
        f1 = meanNll(scores, labels, std::exp(x1), mix);
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + phi * (b - a);
        f2 = meanNll(scores, labels, std::exp(x2), mix);
      }
    }
    const double lt = f1 < f2 ? x1 : x2;
    const double f = std::min({f1, f2, val});
    if (f < best) {
      best = f;
      best_t = f == val ? std::exp(arg) : std::exp(lt);
      best_mix = mix;
    }
  }
  classifier->temperature = static_cast<float>(best_t);
  classifier->uniform_mix = static_cast<float>(best_mix);
  return best;
}

}  // namespace slamaware::recognizer
