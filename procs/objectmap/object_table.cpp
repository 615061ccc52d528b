#include "procs/objectmap/object_table.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <iterator>
#include <numeric>
#include <set>
#include <tuple>
#include <unordered_map>

#include "procs/objectmap/fusion.h"

namespace slamaware::objectmap {

namespace {

struct UnionFind {
  std::vector<size_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  size_t find(size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(size_t a, size_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

using VoxelTest = std::function<bool(const std::vector<VoxelKey>&, const std::vector<VoxelKey>&)>;

/// Tries the pairs of items in the order given: the groups of the two are joined when their voxel
/// unions pass `joins(a, b)` (tested on unions, so a chain of small overlaps cannot grow a group
/// that swallows what lies in it). `voxels[i]`: item i's sorted voxels. Returns the union of each
/// joined root (a root not in it has its item's own voxels).
std::map<size_t, std::vector<VoxelKey>> joinInOrder(
    const std::vector<std::tuple<double, size_t, size_t>>& pairs,
    const std::vector<const std::vector<VoxelKey>*>& voxels, UnionFind& uf,
    const VoxelTest& joins) {
  std::map<size_t, std::vector<VoxelKey>> unions;  // by root, sorted
  auto voxelsOf = [&](size_t root) -> std::vector<VoxelKey>& {
    auto it = unions.find(root);
    if (it == unions.end()) it = unions.emplace(root, *voxels[root]).first;
    return it->second;
  };
  for (const auto& [r, i, j] : pairs) {
    const size_t ri = uf.find(i), rj = uf.find(j);
    if (ri == rj) continue;
    std::vector<VoxelKey>& a = voxelsOf(ri);
    std::vector<VoxelKey>& b = voxelsOf(rj);
    if (!joins(a, b)) continue;
    std::vector<VoxelKey> merged;
    std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(merged));
    unions.erase(ri);
    unions.erase(rj);
    uf.unite(ri, rj);
    unions[uf.find(ri)] = std::move(merged);
  }
  return unions;
}

/// Joins items whose voxels overlap (the grouping of candidates, and the merging of same-label
/// groups): every pair of items that shares voxels and that `listed(i, j, shared)` admits is tried
/// in ascending `rank(shared, na, nb)` (then i, j), and the groups of the two are joined when their
/// voxel unions pass `joins(shared, a, b)` (joinInOrder).
std::map<size_t, std::vector<VoxelKey>> joinOverlapping(
    const std::vector<const std::vector<VoxelKey>*>& voxels, UnionFind& uf,
    const std::function<bool(size_t, size_t, size_t)>& listed,
    const std::function<double(size_t, size_t, size_t)>& rank,
    const std::function<bool(size_t, const std::vector<VoxelKey>&, const std::vector<VoxelKey>&)>&
        joins) {
  // The voxels each pair of items shares, from one sorted list of (voxel, item): a run of one voxel
  // lists its owners in ascending order (each item's voxels are sorted and unique). Then, item by
  // item, a dense counter over the later items it shares voxels with. This runs for every
  // DETECTIONS message over every candidate's voxels; hash and tree maps allocating a node per
  // voxel and per pair took a quarter of the object map's time in a real-time replay.
  const size_t items = voxels.size();
  std::vector<std::pair<VoxelKey, uint32_t>> owned;
  size_t total = 0;
  for (const auto* v : voxels) total += v->size();
  owned.reserve(total);
  for (size_t i = 0; i < items; ++i)
    for (VoxelKey k : *voxels[i]) owned.emplace_back(k, static_cast<uint32_t>(i));
  std::sort(owned.begin(), owned.end());
  std::vector<std::pair<size_t, size_t>> runs;        // [begin, end) in owned: two or more owners
  std::vector<std::vector<uint32_t>> runs_of(items);  // item -> its voxels' runs
  for (size_t p = 0; p < owned.size();) {
    size_t end = p + 1;
    while (end < owned.size() && owned[end].first == owned[p].first) ++end;
    if (end - p > 1) {
      for (size_t q = p; q < end; ++q)
        runs_of[owned[q].second].push_back(static_cast<uint32_t>(runs.size()));
      runs.emplace_back(p, end);
    }
    p = end;
  }
  std::vector<std::tuple<double, size_t, size_t>> pairs;
  std::vector<uint32_t> shared(items, 0), touched;
  for (size_t i = 0; i < items; ++i) {
    for (uint32_t r : runs_of[i])
      for (size_t q = runs[r].first; q < runs[r].second; ++q) {
        const uint32_t j = owned[q].second;
        if (j > i && shared[j]++ == 0) touched.push_back(j);
      }
    std::sort(touched.begin(), touched.end());
    for (uint32_t j : touched) {
      const size_t n = shared[j];
      shared[j] = 0;
      if (listed(i, j, n)) pairs.emplace_back(rank(n, voxels[i]->size(), voxels[j]->size()), i, j);
    }
    touched.clear();
  }
  std::sort(pairs.begin(), pairs.end());
  return joinInOrder(pairs, voxels, uf,
                     [&](const std::vector<VoxelKey>& a, const std::vector<VoxelKey>& b) {
                       size_t both = 0;  // |a ∩ b| of the two sorted sets, without building it
                       for (auto i = a.begin(), j = b.begin(); i != a.end() && j != b.end();) {
                         if (*i < *j) {
                           ++i;
                         } else if (*j < *i) {
                           ++j;
                         } else {
                           ++both, ++i, ++j;
                         }
                       }
                       return joins(both, a, b);
                     });
}

/// The groups of `uf`'s roots, each the concatenation of its members' groups (root = lowest index:
/// groups stay in order).
std::vector<std::vector<int32_t>> concatenateJoined(const std::vector<std::vector<int32_t>>& groups,
                                                    UnionFind& uf) {
  std::map<size_t, std::vector<int32_t>> by_root;
  for (size_t g = 0; g < groups.size(); ++g) {
    auto& m = by_root[uf.find(g)];
    m.insert(m.end(), groups[g].begin(), groups[g].end());
  }
  std::vector<std::vector<int32_t>> out;
  for (auto& [root, members] : by_root) {
    std::sort(members.begin(), members.end());
    out.push_back(std::move(members));
  }
  return out;
}

/// p(object | view): View::objectness of a merged view, else 1 - p(background | view) (background
/// last); 0 for a view without log-probabilities.
double viewObjectness(const View& v) {
  if (v.objectness >= 0) return v.objectness;
  return v.log_prob.empty() ? 0.0 : std::exp(logObjectness(v.log_prob.back()));
}

/// Of two views of one object with the same key (boxes of two of its candidates in one frame, or
/// their views merged into one bin), whether `a` is the one to count: the one standing for more
/// frames, then the more object-like box (moreObjectLikeView(); merged views by their objectness),
/// then the larger.
bool betterView(const View& a, const View& b) {
  if (a.frames != b.frames) return a.frames > b.frames;
  if (a.objectness < 0 && b.objectness < 0)
    return moreObjectLikeView(a.log_prob, a.area, b.log_prob, b.area);
  const double oa = viewObjectness(a), ob = viewObjectness(b);
  if (oa != ob) return oa > ob;
  return a.area > b.area;
}

/// The votes a voxel needs to be one of the candidate's (VotingOptions: min_votes, min_vote_share).
double votesNeeded(const Candidate& c, const VotingOptions& options) {
  return std::max<double>(options.min_votes, options.min_vote_share * c.voting_views);
}

}  // namespace

void ObjectTable::addView(int32_t candidate, View view) {
  Candidate& c = candidates_[candidate];
  c.id = candidate;
  newest_view_utime_ = std::max(newest_view_utime_, view.utime);
  const ViewKey key{view.utime, view.seq};
  c.views[key] = std::move(view);  // the same frame again replaces its view
}

namespace {

/// k such that a view `age_us` old is merged into bins of period 2^(k-1) / 16: 0 within one period
/// (kept as it is), k for an age in [period 2^(k-1), period 2^k).
int ageLevel(int64_t age_us, int64_t period_us) {
  int k = 0;
  for (int64_t limit = period_us; age_us >= limit && k < 30; limit *= 2) ++k;
  return k;
}

/// The start of the bin of width `width` (> 0) holding `utime`.
int64_t binStart(int64_t utime, int64_t width) {
  const int64_t q = utime / width;
  return (q - (utime % width < 0 ? 1 : 0)) * width;
}

/// One view for the views [first, last) of a bin starting at `start`
/// (ObjectTable::mergeOldViews()).
View mergeViews(std::map<ViewKey, View>::const_iterator first,
                std::map<ViewKey, View>::const_iterator last, int64_t start,
                bool objectness_weights) {
  View m;
  m.utime = start;
  m.seq = kMergedViewSeq;
  const size_t classes = first->second.log_prob.size();
  // Per class the sums of n log p and of n o log p (n frames, o objectness), and their weights.
  std::vector<double> plain(classes, 0.0), weighted(classes, 0.0);
  double frames = 0, area = 0, objectness = 0, plain_weight = 0, weight = 0;
  for (auto it = first; it != last; ++it) {
    const View& v = it->second;
    const double n = v.frames, o = viewObjectness(v);
    frames += n;
    area += n * v.area;
    objectness += n * o;
    if (v.log_prob.size() != classes) continue;  // classes are remapped for every view at once
    plain_weight += n;
    weight += n * o;
    for (size_t c = 0; c < classes; ++c) {
      plain[c] += n * static_cast<double>(v.log_prob[c]);
      weighted[c] += n * o * static_cast<double>(v.log_prob[c]);
    }
  }
  // Fusion sums frames x objectness x log p with objectness weights (frames x log p without): the
  // mean that gives the same sum. Frames all certain to be background weigh nothing: their mean.
  const bool by_objectness = objectness_weights && weight > 0;
  const std::vector<double>& sum = by_objectness ? weighted : plain;
  const double w = by_objectness ? weight : plain_weight;
  m.frames = static_cast<int32_t>(frames);
  m.area = static_cast<float>(area / frames);
  m.objectness = static_cast<float>(objectness / frames);
  for (size_t c = 0; c < classes; ++c) m.log_prob.push_back(static_cast<float>(sum[c] / w));
  return m;
}

}  // namespace

void ObjectTable::mergeOldViews(int64_t now_utime, bool objectness_weights) {
  if (full_rate_us_ <= 0) return;
  // Sixteen bins per doubling of age.
  const int64_t base_us = std::max<int64_t>(1, full_rate_us_ / 16);
  for (auto c = candidates_.begin(); c != candidates_.end();) {
    if (!c->second.user_label.empty()) {
      ++c;
      continue;
    }
    auto& views = c->second.views;
    // Oldest first, bin after bin; stops at the first view within the full-rate period.
    for (auto it = views.begin(); it != views.end();) {
      const int k = ageLevel(now_utime - it->first.first, full_rate_us_);
      if (k == 0) break;
      const int64_t width = base_us << (k - 1);
      const int64_t start = binStart(it->first.first, width);
      // A bin the older views' level starts at the same time (their bins are twice as wide, and the
      // level's boundary falls in its first half): these views join it.
      if (it != views.begin() && std::prev(it)->first == ViewKey{start, kMergedViewSeq})
        it = std::prev(it);
      // The bin's views of this level: older than P 2^(k-1) (and younger than P 2^k, as `it` is).
      const int64_t level_end = now_utime - (full_rate_us_ << (k - 1));
      auto end = std::next(it);
      while (end != views.end() && end->first.first < start + width &&
             end->first.first <= level_end)
        ++end;
      if (std::next(it) == end && it->first == ViewKey{start, kMergedViewSeq}) {
        it = end;  // merged already
        continue;
      }
      View merged = mergeViews(it, end, start, objectness_weights);
      it = views.erase(it, end);
      it = std::next(views.emplace_hint(it, ViewKey{start, kMergedViewSeq}, std::move(merged)));
    }
    int64_t frames = 0;
    for (const auto& [key, v] : views) frames += v.frames;
    const bool forget =
        !views.empty() &&
        frames < (int64_t{1} << ageLevel(now_utime - views.rbegin()->first.first, full_rate_us_));
    if (forget) {
      c = candidates_.erase(c);
      continue;
    }
    ++c;
  }
  // The full-rate period is the map's short-term memory: what it last called background (the last
  // class) and has not seen within it goes with its candidates; objects stay.
  for (const auto& [id, o] : objects_) {
    const bool background = o.label >= 0 && static_cast<size_t>(o.label) + 1 == o.posterior.size();
    if (background && o.user_label.empty() && o.last_seen_utime < now_utime - full_rate_us_)
      for (int32_t c : o.candidates) candidates_.erase(c);
  }
}

namespace {

/// The votes of a candidate that pass its own voxel threshold, each scaled from `c.voting_views` to
/// `views` voting views (rounded up: a share at the threshold stays at it).
std::vector<std::pair<VoxelKey, int32_t>> passingVotesScaled(const Candidate& c, int32_t views,
                                                             const VotingOptions& options) {
  const double need = votesNeeded(c, options);
  std::vector<std::pair<VoxelKey, int32_t>> out;
  if (c.voting_views <= 0) return out;
  for (const auto& [key, n] : c.votes)
    if (n >= need)
      out.emplace_back(
          key, static_cast<int32_t>(std::ceil(static_cast<double>(n) * views / c.voting_views)));
  return out;
}

/// Folds candidate `from` into `into` (ObjectTable::foldStaleCandidates); `from` is dropped after.
void foldCandidate(Candidate& into, Candidate&& from, const VotingOptions& options) {
  for (auto& [key, v] : from.views) {
    auto [it, added] = into.views.try_emplace(key, std::move(v));
    // Ties keep `into`'s view: the lower id's, as the object's fusion does (members in id order).
    if (!added && betterView(v, it->second)) it->second = std::move(v);
  }
  const int32_t views = std::max(into.voting_views, from.voting_views);
  if (views > 0) {
    // The candidate with the most voting views keeps its votes as they are; the other's voxels
    // keep their share of its views.
    std::vector<std::pair<VoxelKey, int32_t>> a = into.voting_views == views
                                                      ? std::move(into.votes)
                                                      : passingVotesScaled(into, views, options);
    const std::vector<std::pair<VoxelKey, int32_t>> b =
        from.voting_views == views && into.voting_views != views
            ? std::move(from.votes)
            : passingVotesScaled(from, views, options);
    std::vector<std::pair<VoxelKey, int32_t>> merged;
    merged.reserve(a.size() + b.size());
    auto i = a.cbegin(), j = b.cbegin();
    while (i != a.cend() || j != b.cend()) {
      if (j == b.cend() || (i != a.cend() && i->first < j->first)) {
        merged.push_back(*i++);
      } else if (i == a.cend() || j->first < i->first) {
        merged.push_back(*j++);
      } else {
        merged.emplace_back(i->first, std::max(i->second, j->second));
        ++i, ++j;
      }
    }
    into.votes = std::move(merged);
    into.voting_views = views;
  }
  // An object without voxels is as large as its members' largest box (describeGroup()).
  into.box_size = std::max(into.box_size, from.box_size);
  into.box_position_sum += from.box_position_sum;
  into.box_positions += from.box_positions;
}

}  // namespace

void ObjectTable::foldStaleCandidates(int64_t now_utime, const VotingOptions& options) {
  if (full_rate_us_ <= 0) return;
  const int64_t since = now_utime - full_rate_us_;
  for (const auto& [id, o] : objects_) {
    // The stale candidates of the object, by user's label; each list in id order.
    std::map<std::string, std::vector<int32_t>> stale;
    for (int32_t cid : o.candidates) {
      auto it = candidates_.find(cid);
      if (it == candidates_.end()) continue;  // forgotten since
      const Candidate& c = it->second;
      if (c.views.empty() || c.views.rbegin()->first.first >= since) continue;
      stale[c.user_label].push_back(cid);
    }
    for (const auto& [label, ids] : stale) {
      if (ids.size() < 2) continue;
      Candidate& keeper = candidates_.at(ids.front());
      for (size_t k = 1; k < ids.size(); ++k) {
        foldCandidate(keeper, std::move(candidates_.at(ids[k])), options);
        candidates_.erase(ids[k]);
      }
    }
  }
}

std::vector<double> sumViewEvidence(const std::vector<const View*>& views, size_t num_classes,
                                    bool objectness_weights, double* total_weight) {
  std::vector<const std::vector<float>*> log_p;
  std::vector<int32_t> frames;
  std::vector<double> objectness;
  for (const View* v : views) {
    log_p.push_back(&v->log_prob);
    frames.push_back(v->frames);
    objectness.push_back(v->objectness);
  }
  return sumLogProbabilities(log_p, num_classes, objectness_weights, total_weight, frames,
                             objectness);
}

void ObjectTable::addVotes(int32_t candidate, const std::vector<VoxelKey>& keys,
                           const VotingOptions& options) {
  Candidate& c = candidates_[candidate];
  c.id = candidate;
  ++c.voting_views;
  std::vector<VoxelKey> sorted;
  const std::vector<VoxelKey>* in = &keys;
  if (!std::is_sorted(keys.begin(), keys.end())) {
    sorted = keys;
    std::sort(sorted.begin(), sorted.end());
    in = &sorted;
  }
  // Merge of two sorted lists; a key given twice counts once.
  std::vector<std::pair<VoxelKey, int32_t>> merged;
  merged.reserve(c.votes.size() + in->size());
  auto old = c.votes.begin();
  for (size_t i = 0; i < in->size(); ++i) {
    const VoxelKey k = (*in)[i];
    if (i > 0 && (*in)[i - 1] == k) continue;
    while (old != c.votes.end() && old->first < k) merged.push_back(*old++);
    if (old != c.votes.end() && old->first == k) {
      merged.emplace_back(k, old->second + 1);
      ++old;
    } else {
      merged.emplace_back(k, 1);
    }
  }
  merged.insert(merged.end(), old, c.votes.end());
  if (options.forget_share > 0 && c.voting_views % 10 == 0) {
    const double keep = options.forget_share * c.voting_views;
    merged.erase(std::remove_if(merged.begin(), merged.end(),
                                [&](const auto& v) { return v.second < keep; }),
                 merged.end());
  }
  c.votes = std::move(merged);
}

void ObjectTable::addBoxPosition(int32_t candidate, const Eigen::Vector3d& p_world, double size) {
  Candidate& c = candidates_[candidate];
  c.id = candidate;
  c.box_position_sum += p_world;
  ++c.box_positions;
  c.box_size = size;
}

Candidate* ObjectTable::findCandidate(int32_t id) {
  auto it = candidates_.find(id);
  return it == candidates_.end() ? nullptr : &it->second;
}

const Object* ObjectTable::objectOfCandidate(int32_t candidate) const {
  for (const auto& [id, o] : objects_)
    if (std::binary_search(o.candidates.begin(), o.candidates.end(), candidate)) return &o;
  return nullptr;
}

void ObjectTable::restoreObject(int32_t id, std::vector<int32_t> candidates) {
  std::sort(candidates.begin(), candidates.end());
  Object& o = objects_[id];
  o.id = id;
  o.candidates = std::move(candidates);
}

bool ObjectTable::setUserLabel(int32_t object_id, const std::string& label) {
  auto it = objects_.find(object_id);
  if (it == objects_.end()) return false;
  for (int32_t cid : it->second.candidates) candidates_.at(cid).user_label = label;
  it->second.user_label = label;
  return true;
}

std::string ObjectTable::userLabelOf(const std::vector<int32_t>& members) const {
  std::map<std::string, int> count;
  for (int32_t cid : members) {
    const std::string& l = candidates_.at(cid).user_label;
    if (!l.empty()) ++count[l];
  }
  std::string best;
  int most = 0;
  for (const auto& [l, n] : count)
    if (n > most) {
      best = l;
      most = n;
    }
  return best;
}

void ObjectTable::remapClasses(const std::vector<int>& old_to_new, size_t new_size,
                               int old_background) {
  for (auto& [id, c] : candidates_) {
    for (auto& [key, v] : c.views) {
      const float floor =
          old_background >= 0 && static_cast<size_t>(old_background) < v.log_prob.size()
              ? v.log_prob[static_cast<size_t>(old_background)]
          : v.log_prob.empty() ? 0.f
                               : *std::min_element(v.log_prob.begin(), v.log_prob.end());
      std::vector<float> out(new_size, floor);
      for (size_t i = 0; i < v.log_prob.size() && i < old_to_new.size(); ++i)
        if (old_to_new[i] >= 0 && static_cast<size_t>(old_to_new[i]) < new_size)
          out[static_cast<size_t>(old_to_new[i])] = v.log_prob[i];
      v.log_prob = std::move(out);
    }
  }
}

// The views of a group (one per frame: its most object-like box), their evidence and the group's
// voxels, each computed once per group (a group: its sorted candidate ids) during one update().
class ObjectTable::GroupFacts {
 public:
  struct Fused {
    std::map<ViewKey, const View*> views;
    std::vector<double> evidence;
    double weight = 0;   ///< the views' total weight
    int64_t frames = 0;  ///< the frames the views stand for
  };
  GroupFacts(const ObjectTable& table, size_t num_classes, const FusionOptions& fusion)
      : table_(table), num_classes_(num_classes), fusion_(fusion) {}

  const Fused& fusion(const std::vector<int32_t>& members) {
    auto [it, inserted] = fused_.try_emplace(members);
    if (!inserted) return it->second;
    Fused& f = it->second;
    for (int32_t cid : members)
      for (const auto& [key, v] : table_.candidates_.at(cid).views) {
        auto [view, added] = f.views.emplace(key, &v);
        if (!added && betterView(v, *view->second)) view->second = &v;
      }
    std::vector<const View*> views;
    for (const auto& [key, v] : f.views) {
      views.push_back(v);
      f.frames += v->frames;
    }
    f.evidence = sumViewEvidence(views, num_classes_, fusion_.objectness_weights, &f.weight);
    return f;
  }
  const std::vector<VoxelKey>& voxels(const std::vector<int32_t>& members) {
    auto it = voxels_.find(members);
    if (it == voxels_.end()) it = voxels_.emplace(members, table_.groupVoxels(members)).first;
    return it->second;
  }

 private:
  const ObjectTable& table_;
  size_t num_classes_;
  const FusionOptions& fusion_;
  std::map<std::vector<int32_t>, Fused> fused_;
  std::map<std::vector<int32_t>, std::vector<VoxelKey>> voxels_;
};

std::vector<std::vector<int32_t>> ObjectTable::mergeSameLabel(
    std::vector<std::vector<int32_t>> groups, const GroupingOptions& grouping, GroupFacts& facts,
    int background) const {
  static const std::vector<VoxelKey> kNone;
  std::vector<int> label(groups.size());
  std::vector<const std::vector<VoxelKey>*> sets(groups.size(),
                                                 &kNone);  // none for background groups
  for (size_t g = 0; g < groups.size(); ++g) {
    label[g] = argmaxClass(facts.fusion(groups[g]).evidence);
    if (label[g] >= 0 && label[g] != background) sets[g] = &facts.voxels(groups[g]);
  }
  UnionFind uf(groups.size());
  // Most overlapping (share of the smaller) first; joined groups keep their label (a sum of
  // evidence that two groups both call c is called c).
  const auto unions = joinOverlapping(
      sets, uf, [&](size_t i, size_t j, size_t) { return label[i] == label[j]; },
      [](size_t n, size_t na, size_t nb) {
        return -static_cast<double>(n) / static_cast<double>(std::min(na, nb));
      },
      [&](size_t n, const std::vector<VoxelKey>& a, const std::vector<VoxelKey>& b) {
        return static_cast<double>(n) >=
               grouping.same_label_overlap * static_cast<double>(std::min(a.size(), b.size()));
      });
  // A group without voxels yet (seen, but not from enough localised views) whose boxes put it
  // inside the bounds of a group of its class joins that group (the first, in order). Bounds are
  // those of the merged groups above (joining adds no voxel).
  std::vector<bool> has_voxels(groups.size());
  std::vector<Eigen::Vector3d> lo(groups.size()), hi(groups.size());
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(resolution_ / 2);
  for (size_t h = 0; h < groups.size(); ++h) {
    const auto joined = unions.find(uf.find(h));
    const std::vector<VoxelKey>& v = joined != unions.end() ? joined->second : *sets[uf.find(h)];
    has_voxels[h] = !v.empty();
    lo[h] = Eigen::Vector3d::Constant(1e300);
    hi[h] = -lo[h];
    for (VoxelKey k : v) {
      lo[h] = lo[h].cwiseMin(voxelCentre(k, resolution_) - half);
      hi[h] = hi[h].cwiseMax(voxelCentre(k, resolution_) + half);
    }
  }
  for (size_t g = 0; g < groups.size(); ++g) {
    if (has_voxels[g] || label[g] < 0 || label[g] == background) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int32_t n = 0;
    for (int32_t cid : groups[g]) {
      sum += candidates_.at(cid).box_position_sum;
      n += candidates_.at(cid).box_positions;
    }
    if (n == 0) continue;
    const Eigen::Vector3d p = sum / n;
    for (size_t h = 0; h < groups.size(); ++h)
      if (has_voxels[h] && label[h] == label[g] && ((p - lo[h]).array() >= 0).all() &&
          ((hi[h] - p).array() >= 0).all()) {
        uf.unite(g, h);
        break;
      }
  }
  return concatenateJoined(groups, uf);
}

std::vector<VoxelKey> ObjectTable::groupVoxels(const std::vector<int32_t>& group) const {
  std::vector<VoxelKey> out;
  for (int32_t cid : group) {
    const std::vector<VoxelKey>& v = candidates_.at(cid).voxels;
    out.insert(out.end(), v.begin(), v.end());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void ObjectTable::update(const std::function<bool(VoxelKey)>& occupied,
                         const VotingOptions& options, const GroupingOptions& grouping,
                         size_t num_classes, const std::function<int32_t()>& new_id,
                         const FusionOptions& fusion) {
  if (full_rate_us_ > 0 && newest_view_utime_ >= next_merge_utime_) {
    mergeOldViews(newest_view_utime_, fusion.objectness_weights);
    foldStaleCandidates(newest_view_utime_, options);
    next_merge_utime_ = newest_view_utime_ + full_rate_us_ / 8;
  }
  deriveVoxels(occupied, options);
  std::vector<std::vector<int32_t>> groups = groupOverlapping(grouping);
  GroupFacts facts(*this, num_classes, fusion);
  if (grouping.same_label_overlap > 0 && num_classes > 1)
    groups = mergeSameLabel(std::move(groups), grouping, facts, static_cast<int>(num_classes) - 1);
  const std::vector<int32_t> ids = stableIds(groups, new_id);
  std::map<int32_t, Object> objects;
  for (size_t g = 0; g < groups.size(); ++g) {
    Object o = describeGroup(ids[g], groups[g], facts, fusion);
    objects.emplace(o.id, std::move(o));
  }
  objects_ = std::move(objects);
}

void ObjectTable::deriveVoxels(const std::function<bool(VoxelKey)>& occupied,
                               const VotingOptions& options) {
  for (auto& [id, c] : candidates_) {
    c.voxels.clear();
    const double need = votesNeeded(c, options);
    for (const auto& [key, n] : c.votes)  // sorted by key: so are the voxels
      if (n >= need && occupied(key)) c.voxels.push_back(key);
  }
}

std::vector<std::vector<int32_t>> ObjectTable::groupOverlapping(
    const GroupingOptions& grouping) const {
  // Pairs of candidates sharing voxels, most overlapping (IoU) first; two groups merge when their
  // voxel unions pass the test.
  auto passes = [&](size_t inter, const std::vector<VoxelKey>& a, const std::vector<VoxelKey>& b) {
    const double small = static_cast<double>(std::min(a.size(), b.size()));
    const double large = static_cast<double>(std::max(a.size(), b.size()));
    if (!(small > 0)) return false;
    const double share = static_cast<double>(inter) / small;
    return share >= grouping.merge_overlap && small >= grouping.merge_size_ratio * large;
  };
  std::vector<const Candidate*> cands;
  std::vector<const std::vector<VoxelKey>*> sets;
  for (const auto& [id, c] : candidates_) {
    cands.push_back(&c);
    sets.push_back(&c.voxels);
  }
  UnionFind uf(cands.size());
  joinOverlapping(
      sets, uf, [&](size_t i, size_t j, size_t n) { return passes(n, *sets[i], *sets[j]); },
      [](size_t n, size_t na, size_t nb) {
        return -static_cast<double>(n) / static_cast<double>(na + nb - n);
      },
      passes);
  std::map<size_t, std::vector<int32_t>> by_root;  // root = lowest index = lowest candidate id
  for (size_t i = 0; i < cands.size(); ++i) by_root[uf.find(i)].push_back(cands[i]->id);
  std::vector<std::vector<int32_t>> groups;
  for (auto& [root, members] : by_root) groups.push_back(std::move(members));
  return groups;
}

std::vector<int32_t> ObjectTable::stableIds(const std::vector<std::vector<int32_t>>& groups,
                                            const std::function<int32_t()>& new_id) const {
  // Greedily give each previous object's id to the group sharing most of its candidates (ties:
  // lower previous id, then earlier group); the other groups get new ids.
  std::unordered_map<int32_t, int32_t> previous_of;  // candidate -> previous object id
  for (const auto& [id, o] : objects_)
    for (int32_t c : o.candidates) previous_of[c] = id;
  std::map<std::pair<int32_t, size_t>, int> overlap;  // (previous id, group) -> shared candidates
  for (size_t g = 0; g < groups.size(); ++g)
    for (int32_t c : groups[g]) {
      auto it = previous_of.find(c);
      if (it != previous_of.end()) ++overlap[{it->second, g}];
    }
  std::vector<std::tuple<int, int32_t, size_t>> matches;
  for (const auto& [key, n] : overlap) matches.emplace_back(-n, key.first, key.second);
  std::sort(matches.begin(), matches.end());
  std::vector<int32_t> group_id(groups.size(), -1);
  std::set<int32_t> used;
  for (const auto& [neg, prev, g] : matches) {
    if (group_id[g] >= 0 || used.count(prev)) continue;
    group_id[g] = prev;
    used.insert(prev);
  }
  for (size_t g = 0; g < groups.size(); ++g)
    if (group_id[g] < 0) group_id[g] = new_id();
  return group_id;
}

Object ObjectTable::describeGroup(int32_t id, const std::vector<int32_t>& members,
                                  GroupFacts& facts, const FusionOptions& fusion) const {
  Object o;
  o.id = id;
  o.candidates = members;
  const GroupFacts::Fused& f = facts.fusion(members);
  const std::vector<VoxelKey>& voxels = facts.voxels(members);
  o.log_evidence = f.evidence;
  o.evidence_weight = f.weight;
  o.posterior = posteriorFromLogEvidence(o.log_evidence, f.weight, fusion.views_exponent);
  o.label = argmaxClass(o.log_evidence);
  o.num_views = static_cast<int32_t>(std::min<int64_t>(f.frames, INT32_MAX));
  if (!f.views.empty()) {
    o.first_seen_utime = f.views.begin()->first.first;
    o.last_seen_utime = f.views.rbegin()->first.first;
  }
  o.user_label = userLabelOf(members);
  o.num_voxels = static_cast<int32_t>(voxels.size());
  if (!voxels.empty()) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo, sum = Eigen::Vector3d::Zero();
    for (VoxelKey k : voxels) {
      const Eigen::Vector3d p = voxelCentre(k, resolution_);
      sum += p;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    o.centroid = sum / static_cast<double>(voxels.size());
    // Voxel centres span one voxel less than the voxels.
    o.extent = ((hi - lo).array() + resolution_).matrix();
    o.has_position = true;
    return o;
  }
  // No voxels yet: where its boxes put it.
  Eigen::Vector3d box_sum = Eigen::Vector3d::Zero();
  int32_t box_n = 0;
  double box_size = 0;
  for (int32_t cid : members) {
    const Candidate& c = candidates_.at(cid);
    box_sum += c.box_position_sum;
    box_n += c.box_positions;
    box_size = std::max(box_size, c.box_size);
  }
  if (box_n > 0) {
    o.centroid = box_sum / box_n;
    o.extent = Eigen::Vector3d::Constant(box_size);
    o.has_position = true;
  }
  return o;
}

}  // namespace slamaware::objectmap
