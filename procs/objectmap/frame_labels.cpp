#include "procs/objectmap/frame_labels.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "common/geometry.h"

namespace slamaware::objectmap {

namespace {

/// Objectness of a candidate's views: each value with the frames its view stands for.
using Sample = std::vector<std::pair<double, int32_t>>;

double logMean(const Sample& p) {
  double sum = 0, n = 0;
  for (const auto& [v, frames] : p) {
    sum += v * frames;
    n += frames;
  }
  return std::log(std::max(1e-300, sum / n));
}

/// The median of a sorted sample with each value repeated as often as its frames.
double logMedian(const Sample& p) {
  int64_t n = 0;
  for (const auto& s : p) n += s.second;
  // The values at positions (n - 1) / 2 and n / 2 of the repeated sample (the same for odd n).
  auto at = [&p](int64_t pos) {
    for (const auto& [v, frames] : p)
      if ((pos -= frames) < 0) return v;
    return p.back().first;
  };
  const double median = (at((n - 1) / 2) + at(n / 2)) / 2;
  return std::log(std::max(1e-300, median));
}

}  // namespace

std::vector<double> logPosteriorFromLogEvidence(const std::vector<double>& log_evidence,
                                                double weight, double views_exponent) {
  std::vector<double> e = scaledLogEvidence(log_evidence, weight, views_exponent);
  if (e.empty()) return e;
  const double m = *std::max_element(e.begin(), e.end());
  double z = 0;
  for (double v : e) z += std::exp(v - m);
  const double lse = m + std::log(z);
  for (double& v : e) v -= lse;
  return e;
}

void scaleObjectClasses(std::vector<double>* log_p, const std::vector<double>& log_factors) {
  if (log_p->empty()) return;
  const size_t bg = log_p->size() - 1;
  double object_sum = 0;
  for (size_t c = 0; c < bg; ++c) {
    (*log_p)[c] += log_factors[c];
    object_sum += std::exp((*log_p)[c]);
  }
  (*log_p)[bg] = std::log(std::max(1e-300, 1.0 - std::min(1.0, object_sum)));
}

std::vector<FrameBoxLabel> labelFrameBoxes(const std::vector<FrameBox>& boxes,
                                           const ObjectTable& table, size_t num_classes,
                                           const FusionOptions& fusion) {
  std::vector<FrameBoxLabel> out(boxes.size());
  if (num_classes == 0) return out;
  const size_t bg = num_classes - 1;
  // The candidates' and objects' typical views, once per frame.
  std::map<int32_t, double> candidate_mean, candidate_median, object_median;
  for (const FrameBox& b : boxes) {
    const Object* o = table.objectOfCandidate(b.candidate);
    if (o && o->log_evidence.size() == num_classes && !object_median.count(o->id)) {
      Sample p;
      for (int32_t c : o->candidates)
        if (auto it = table.candidates().find(c); it != table.candidates().end())
          p.insert(p.end(), it->second.objectness.begin(), it->second.objectness.end());
      std::sort(p.begin(), p.end());  // the candidates' sorted runs, one after another
      if (!p.empty()) object_median[o->id] = logMedian(p);
    }
    if (candidate_mean.count(b.candidate)) continue;
    auto it = table.candidates().find(b.candidate);
    if (it == table.candidates().end() || it->second.objectness.empty()) continue;
    // Both over the sorted values the table keeps: walking the views' tree and taking each view's
    // exponential again for every box of every frame grew with the session (a candidate kept
    // about 2,000 views after 15 minutes before old views were merged) and was half of the node's
    // time.
    candidate_mean[b.candidate] = logMean(it->second.objectness);
    candidate_median[b.candidate] = logMedian(it->second.objectness);
  }
  for (size_t i = 0; i < boxes.size(); ++i) {
    const FrameBox& b = boxes[i];
    FrameBoxLabel& l = out[i];
    const Object* o = table.objectOfCandidate(b.candidate);
    const bool in_object = o && o->log_evidence.size() == num_classes && object_median.count(o->id);
    std::vector<double> log_posterior;
    if (in_object) {
      l.object = o->id;
      l.role = BoxRole::kPrimary;
      log_posterior =
          logPosteriorFromLogEvidence(o->log_evidence, o->evidence_weight, fusion.views_exponent);
    } else if (auto it = table.candidates().find(b.candidate);
               it != table.candidates().end() && !it->second.views.empty()) {
      // Its own views, fused as the map fuses an object's.
      std::vector<const View*> views;
      for (const auto& [key, v] : it->second.views) views.push_back(&v);
      double weight = 0;
      const std::vector<double> evidence =
          sumViewEvidence(views, num_classes, fusion.objectness_weights, &weight);
      log_posterior = logPosteriorFromLogEvidence(evidence, weight, fusion.views_exponent);
    } else {
      log_posterior.assign(num_classes, kMinLogProb);
      for (size_t c = 0; c < num_classes && c < b.log_p.size(); ++c) log_posterior[c] = b.log_p[c];
    }
    l.log_posterior = log_posterior;
    l.log_score = log_posterior;
    l.label = argmaxClass(log_posterior);
    const double typical =
        candidate_mean.count(b.candidate)
            ? candidate_mean.at(b.candidate) +
                  (in_object ? object_median.at(o->id) : candidate_median.at(b.candidate))
            : 2 * (b.log_p.size() == num_classes ? logObjectness(b.log_p[bg]) : 0.0);
    l.log_weight.assign(num_classes, 0.0);
    for (size_t c = 0; c < bg; ++c) {
      const double own =
          c < b.log_p.size() ? std::min(0.0, static_cast<double>(b.log_p[c])) : kMinLogProb;
      l.log_weight[c] = (own + typical) / 3;
    }
  }
  // One box per object stands for it; the others that overlap it are duplicates.
  std::map<int32_t, size_t> primary;
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (out[i].object < 0) continue;
    const auto [it, added] = primary.emplace(out[i].object, i);
    // By log p(background | box) itself: 1 - p(background) rounds to 1 for sure views.
    if (!added && boxes[i].log_p.size() == num_classes &&
        boxes[it->second].log_p.size() == num_classes &&
        boxes[i].log_p[bg] < boxes[it->second].log_p[bg])
      it->second = i;
  }
  for (size_t i = 0; i < boxes.size(); ++i) {
    FrameBoxLabel& l = out[i];
    if (l.object < 0 || primary.at(l.object) == i) continue;
    const FrameBox& a = boxes[i];
    const FrameBox& p = boxes[primary.at(l.object)];
    const double area = a.w * a.h;
    const double inside =
        area > 0 ? rectIntersection(a.x, a.y, a.w, a.h, p.x, p.y, p.w, p.h) / area : 0.0;
    if (!(inside > 0)) {
      l.role = BoxRole::kPart;
      continue;
    }
    l.role = BoxRole::kDuplicate;
    const double demote = std::max<double>(kMinLogProb, -inside * inside / kDuplicateSigma);
    for (size_t c = 0; c < bg; ++c) l.log_weight[c] += demote;
  }
  for (auto& l : out) scaleObjectClasses(&l.log_score, l.log_weight);
  return out;
}

}  // namespace slamaware::objectmap
