#include "procs/objectmap/fusion.h"

#include <algorithm>
#include <cmath>

namespace slamaware {

std::vector<double> sumLogProbabilities(const std::vector<const std::vector<float>*>& views,
                                        size_t num_classes, bool objectness_weights) {
  std::vector<double> sum(num_classes, 0.0);
  for (const auto* v : views) {
    double w = 1.0;
    if (objectness_weights && num_classes > 0 && v->size() >= num_classes)
      w = 1.0 - std::exp(std::min(0.0, static_cast<double>((*v)[num_classes - 1])));
    for (size_t c = 0; c < num_classes && c < v->size(); ++c)
      sum[c] += w * static_cast<double>((*v)[c]);
  }
  return sum;
}

std::vector<double> posteriorFromLogEvidence(const std::vector<double>& log_evidence) {
  if (log_evidence.empty()) return {};
  const double top = *std::max_element(log_evidence.begin(), log_evidence.end());
  std::vector<double> p(log_evidence.size());
  double z = 0;
  for (size_t c = 0; c < p.size(); ++c) z += p[c] = std::exp(log_evidence[c] - top);
  for (double& x : p) x /= z;
  return p;
}

int argmaxClass(const std::vector<double>& values) {
  int best = -1;
  for (size_t c = 0; c < values.size(); ++c)
    if (best < 0 || values[c] > values[static_cast<size_t>(best)]) best = static_cast<int>(c);
  return best;
}

}  // namespace slamaware
