#include "procs/objectmap/fusion.h"

#include <algorithm>
#include <cmath>

namespace slamaware::objectmap {

std::vector<double> sumLogProbabilities(const std::vector<const std::vector<float>*>& views,
                                        size_t num_classes, bool objectness_weights,
                                        double* total_weight, const std::vector<int32_t>& frames,
                                        const std::vector<double>& objectness) {
  std::vector<double> sum(num_classes, 0.0);
  double weight = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const std::vector<float>* v = views[i];
    double w = i < frames.size() ? static_cast<double>(frames[i]) : 1.0;
    if (objectness_weights && i < objectness.size() && objectness[i] >= 0)
      w *= objectness[i];
    else if (objectness_weights && num_classes > 0 && v->size() >= num_classes)
      w *= 1.0 - std::exp(std::min(0.0, static_cast<double>((*v)[num_classes - 1])));
    weight += w;
    for (size_t c = 0; c < num_classes && c < v->size(); ++c)
      sum[c] += w * static_cast<double>((*v)[c]);
  }
  if (total_weight) *total_weight = weight;
  return sum;
}

std::vector<double> scaledLogEvidence(const std::vector<double>& log_evidence, double total_weight,
                                      double views_exponent) {
  std::vector<double> e = log_evidence;
  if (views_exponent > 0 && total_weight > 1) {
    const double scale = std::pow(total_weight, -views_exponent);
    for (double& x : e) x *= scale;
  }
  return e;
}

std::vector<double> posteriorFromLogEvidence(const std::vector<double>& log_evidence,
                                             double total_weight, double views_exponent) {
  if (log_evidence.empty()) return {};
  const std::vector<double> e = scaledLogEvidence(log_evidence, total_weight, views_exponent);
  const double top = *std::max_element(e.begin(), e.end());
  std::vector<double> p(e.size());
  double z = 0;
  for (size_t c = 0; c < p.size(); ++c) z += p[c] = std::exp(e[c] - top);
  for (double& x : p) x /= z;
  return p;
}

bool moreObjectLikeView(const std::vector<float>& log_p_a, double area_a,
                        const std::vector<float>& log_p_b, double area_b) {
  const float background_a = log_p_a.empty() ? 0.f : log_p_a.back();
  const float background_b = log_p_b.empty() ? 0.f : log_p_b.back();
  return background_a != background_b ? background_a < background_b : area_a > area_b;
}

int argmaxClass(const std::vector<double>& values) {
  int best = -1;
  for (size_t c = 0; c < values.size(); ++c)
    if (best < 0 || values[c] > values[static_cast<size_t>(best)]) best = static_cast<int>(c);
  return best;
}

double logObjectness(double log_p_background) {
  const double lb = std::min(0.0, log_p_background);
  return lb > -0.693 ? std::log(-std::expm1(lb)) : std::log1p(-std::exp(lb));
}

}  // namespace slamaware::objectmap
