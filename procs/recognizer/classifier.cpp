#include "procs/recognizer/classifier.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#ifdef __F16C__
#include <immintrin.h>
#endif

namespace slamaware {

namespace {

#ifndef __F16C__
// IEEE binary32 -> binary16, round to nearest even (what F16C's _mm256_cvtps_ph does).
uint16_t toHalf(float f) {
  uint32_t x;
  std::memcpy(&x, &f, 4);
  const uint32_t sign = (x >> 16) & 0x8000u;
  const uint32_t absx = x & 0x7fffffffu;
  if (absx >= 0x7f800000u)
    return static_cast<uint16_t>(sign | (absx > 0x7f800000u ? 0x7e00u : 0x7c00u));
  if (absx >= 0x477ff000u) return static_cast<uint16_t>(sign | 0x7c00u);  // overflow -> inf
  if (absx < 0x38800000u) {  // subnormal or zero in half
    if (absx < 0x33000000u) return static_cast<uint16_t>(sign);
    const uint32_t mant = (absx & 0x7fffffu) | 0x800000u;
    const int shift = 126 - static_cast<int>(absx >> 23) + 13 + 1;
    uint32_t h = mant >> shift;
    const uint32_t rem = mant & ((1u << shift) - 1), halfway = 1u << (shift - 1);
    if (rem > halfway || (rem == halfway && (h & 1u))) ++h;
    return static_cast<uint16_t>(sign | h);
  }
  uint32_t h = ((absx - 0x38000000u) >> 13);
  const uint32_t rem = absx & 0x1fffu;
  if (rem > 0x1000u || (rem == 0x1000u && (h & 1u))) ++h;
  return static_cast<uint16_t>(sign | h);
}

float fromHalf(uint16_t h) {
  const uint32_t sign = (h & 0x8000u) << 16;
  uint32_t exp = (h >> 10) & 0x1fu, mant = h & 0x3ffu, x;
  if (exp == 0) {
    if (mant == 0) {
      x = sign;
    } else {  // subnormal: normalise
      int e = -1;
      do {
        ++e;
        mant <<= 1;
      } while ((mant & 0x400u) == 0);
      x = sign | (static_cast<uint32_t>(112 - e) << 23) | ((mant & 0x3ffu) << 13);
    }
  } else if (exp == 31) {
    x = sign | 0x7f800000u | (mant << 13);
  } else {
    x = sign | ((exp + 112) << 23) | (mant << 13);
  }
  float f;
  std::memcpy(&f, &x, 4);
  return f;
}
#endif

inline double sigmoid(double u) {
  if (u >= 0) return 1.0 / (1.0 + std::exp(-u));
  const double e = std::exp(u);
  return e / (1.0 + e);
}

}  // namespace

void floatsToHalf(const float* in, int64_t n, uint16_t* out) {
  int64_t i = 0;
#ifdef __F16C__
  for (; i + 8 <= n; i += 8)
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i),
                     _mm256_cvtps_ph(_mm256_loadu_ps(in + i), _MM_FROUND_TO_NEAREST_INT));
  for (; i < n; ++i) out[i] = _cvtss_sh(in[i], _MM_FROUND_TO_NEAREST_INT);
#else
  for (; i < n; ++i) out[i] = toHalf(in[i]);
#endif
}

void halfToFloats(const uint16_t* in, int64_t n, float* out) {
  int64_t i = 0;
#ifdef __F16C__
  for (; i + 8 <= n; i += 8)
    _mm256_storeu_ps(out + i,
                     _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i))));
  for (; i < n; ++i) out[i] = _cvtsh_ss(in[i]);
#else
  for (; i < n; ++i) out[i] = fromHalf(in[i]);
#endif
}

const uint16_t* ExampleSet::row(int64_t i) const {
  return blocks_[static_cast<size_t>(i / kRowsPerBlock)].data() + (i % kRowsPerBlock) * dims_;
}

uint16_t* ExampleSet::row(int64_t i) { return const_cast<uint16_t*>(std::as_const(*this).row(i)); }

uint16_t* ExampleSet::newRow(int label, int group) {
  const int64_t i = size();
  if (i / kRowsPerBlock >= static_cast<int64_t>(blocks_.size()))
    blocks_.emplace_back(static_cast<size_t>(kRowsPerBlock * dims_));
  labels_.push_back(label);
  groups_.push_back(group);
  return row(i);
}

void ExampleSet::truncate(int64_t n) {
  blocks_.resize(static_cast<size_t>((n + kRowsPerBlock - 1) / kRowsPerBlock));
  labels_.resize(static_cast<size_t>(n));
  groups_.resize(static_cast<size_t>(n));
}

size_t ExampleSet::allocatedBytes() const {
  size_t n = 0;
  for (const auto& b : blocks_) n += b.capacity() * sizeof(uint16_t);
  return n;
}

void ExampleSet::add(const float* x, int label, int group) {
  floatsToHalf(x, dims_, newRow(label, group));
}

void ExampleSet::append(const ExampleSet& other) {
  if (other.dims_ != dims_) throw std::invalid_argument("ExampleSet::append: dimensions differ");
  const int64_t n = other.size();  // (other may be this set)
  for (int64_t i = 0; i < n; ++i) std::copy_n(other.row(i), dims_, newRow(other.label(i), other.group(i)));
}

void ExampleSet::get(int64_t i, float* out) const { halfToFloats(row(i), dims_, out); }

void ExampleSet::filter(const std::function<bool(int64_t)>& keep) {
  int64_t w = 0;
  for (int64_t i = 0; i < size(); ++i) {
    if (!keep(i)) continue;
    if (w != i) {
      std::copy_n(row(i), dims_, row(w));
      labels_[static_cast<size_t>(w)] = labels_[static_cast<size_t>(i)];
      groups_[static_cast<size_t>(w)] = groups_[static_cast<size_t>(i)];
    }
    ++w;
  }
  truncate(w);
}

ExampleSet ExampleSet::select(const std::function<bool(int64_t)>& keep) const {
  ExampleSet out(dims_);
  for (int64_t i = 0; i < size(); ++i) {
    if (!keep(i)) continue;
    std::copy_n(row(i), dims_, out.newRow(label(i), group(i)));
  }
  return out;
}

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
                               const SgdOptions& options,
                               const std::function<void(int)>& progress) {
  const int C = static_cast<int>(classes.size());
  const int64_t n = examples.size(), dims = examples.dims();
  if (C < 1 || n < 1) throw std::invalid_argument("trainOneVsAll: no classes or no examples");
  std::vector<int64_t> positives(static_cast<size_t>(C), 0);
  for (int64_t i = 0; i < n; ++i) {
    const int l = examples.label(i);
    if (l < 0 || l >= C) throw std::invalid_argument("trainOneVsAll: label out of range");
    ++positives[static_cast<size_t>(l)];
  }
  std::vector<double> w_pos(static_cast<size_t>(C), 1.0), w_neg(static_cast<size_t>(C), 1.0);
  if (options.balance)
    for (int c = 0; c < C; ++c) {
      const double p = static_cast<double>(positives[static_cast<size_t>(c)]);
      if (p > 0) w_pos[static_cast<size_t>(c)] = n / (2.0 * p);
      if (n - p > 0) w_neg[static_cast<size_t>(c)] = n / (2.0 * (n - p));
    }

  // w_c = scale_c * v_c, so that the L2 shrinkage costs O(1) per step (Bottou's SGD trick).
  MatrixRM v = MatrixRM::Zero(C, dims);
  std::vector<double> scale(static_cast<size_t>(C), 1.0), bias(static_cast<size_t>(C), 0.0);
  std::vector<int64_t> order(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
  std::mt19937 rng(static_cast<uint32_t>(options.seed));
  Eigen::VectorXf x(dims);
  const double lambda = options.lambda;
  int64_t t = 0;
  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    // Fisher-Yates with mt19937's raw output (std::shuffle's use of it is implementation-defined).
    for (int64_t i = n - 1; i > 0; --i)
      std::swap(order[static_cast<size_t>(i)],
                order[static_cast<size_t>(rng() % static_cast<uint32_t>(i + 1))]);
    for (int64_t idx : order) {
      examples.get(idx, x.data());
      const int label = examples.label(idx);
      const double eta = options.eta0 / (1.0 + lambda * options.eta0 * static_cast<double>(t));
      for (int c = 0; c < C; ++c) {
        const size_t cc = static_cast<size_t>(c);
        const double s = scale[cc] * static_cast<double>(v.row(c).dot(x.transpose())) + bias[cc];
        const double z = label == c ? 1.0 : -1.0;
        const double weight = z > 0 ? w_pos[cc] : w_neg[cc];
        const double g = -z * weight * sigmoid(-z * s);  // d loss / d s
        scale[cc] *= 1.0 - eta * lambda;
        if (g != 0) v.row(c) += static_cast<float>(-eta * g / scale[cc]) * x.transpose();
        bias[cc] -= eta * options.bias_rate * g;
        if (scale[cc] < 1e-6) {
          v.row(c) *= static_cast<float>(scale[cc]);
          scale[cc] = 1.0;
        }
      }
      ++t;
    }
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

}  // namespace slamaware
