#include "procs/recognizer/view_selector.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace slamaware::recognizer {

namespace {

bool known(const CandidateView& v) {
  return v.candidate_id >= 0 && v.direction.allFinite() && v.direction.squaredNorm() > 0.5f &&
         std::isfinite(v.depth) && v.depth > 0 && std::isfinite(v.w) && v.w > 0 &&
         std::isfinite(v.h) && v.h > 0;
}

}  // namespace

bool ViewSelector::isNewView(const CandidateView& now, const CandidateView& then) const {
  const double cos_angle =
      static_cast<double>(now.direction.normalized().dot(then.direction.normalized()));
  if (cos_angle < std::cos(options_.angle_deg * M_PI / 180.0)) return true;
  const double limit = std::log1p(std::max(0.0, options_.scale));
  const auto changed = [&](double a, double b) { return std::abs(std::log(a / b)) > limit; };
  return changed(now.depth, then.depth) ||
         changed(double{now.w} * now.depth, double{then.w} * then.depth) ||
         changed(double{now.h} * now.depth, double{then.h} * then.depth);
}

bool ViewSelector::isLate(int32_t seq) const { return newest_seq_ && seq < *newest_seq_; }

std::vector<const CarriedView*> ViewSelector::select(int32_t map_id, int32_t seq,
                                                     const std::vector<CandidateView>& views) {
  std::vector<const CarriedView*> out(views.size(), nullptr);
  if (isLate(seq)) return out;
  newest_seq_ = seq;
  // A candidate boxed twice in one frame is classified both times (the proposals never do that).
  std::map<int32_t, int> boxes_of;
  for (const auto& v : views) ++boxes_of[v.candidate_id];
  std::set<std::pair<int32_t, int32_t>> keep;
  for (size_t i = 0; i < views.size(); ++i) {
    const CandidateView& v = views[i];
    if (!options_.enabled || !known(v) || boxes_of[v.candidate_id] > 1) continue;
    const auto key = std::make_pair(map_id, v.candidate_id);
    const auto it = last_.find(key);
    if (it == last_.end() || isNewView(v, it->second.view)) {
      if (it != last_.end()) last_.erase(it);  // remember() puts the new view back
      continue;
    }
    keep.insert(key);
    out[i] = &it->second.result;
  }
  for (auto it = last_.begin(); it != last_.end();)
    it = keep.count(it->first) ? std::next(it) : last_.erase(it);
  return out;
}

void ViewSelector::remember(int32_t map_id, int32_t seq, const CandidateView& view,
                            const std::vector<float>& log_prob) {
  if (!options_.enabled || !known(view) || isLate(seq)) return;
  last_[std::make_pair(map_id, view.candidate_id)] = Remembered{view, CarriedView{seq, log_prob}};
}

}  // namespace slamaware::recognizer
