#include "procs/objectmap/frame_labels.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "common/geometry.h"

namespace slamaware::objectmap {

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
  for (size_t i = 0; i < boxes.size(); ++i) {
    const FrameBox& b = boxes[i];
    FrameBoxLabel& l = out[i];
    const Object* o = table.objectOfCandidate(b.candidate);
    const bool in_object = o && o->log_evidence.size() == num_classes;
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
    l.log_weight.assign(num_classes, 0.0);
    for (size_t c = 0; c < bg; ++c)
      l.log_weight[c] =
          c < b.log_p.size() ? std::min(0.0, static_cast<double>(b.log_p[c])) : kMinLogProb;
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
