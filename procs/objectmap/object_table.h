#pragma once
// The objects of one map segment. A candidate is a 3D cluster of the proposals stage (its id is
// stable across frames); it collects, view after view, the class evidence of its boxes and votes
// for the occupied voxels its boxes cover (candidate_voxels.h). An object is a group of
// candidates whose voxels overlap strongly and are of similar size (GroupingOptions), groups
// that fill the same space (their voxels near each other's), then groups that overlap and are
// called the same object class (a part and its whole), and parts called background that lie in
// an object whose class they half agree with: the
// proposals stage over-segments at several scales and its clusters split, merge and change ids as
// the map grows, so candidates are grouped again whenever their voxels change, and object ids are
// kept stable across regroupings (an object keeps the id of the previous object it shares most
// candidates with).
//
// An object's class evidence is the sum of log p(class | view) over the union of its candidates'
// views (fusion.h); a frame in which two candidates of one object have a box counts once (the box
// its view finds most object-like: the lowest p(background | box), then the larger), so merging
// never counts a view twice and splitting gives each part exactly its own candidates' views.
#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "procs/objectmap/fusion.h"
#include "procs/objectmap/objectmap_options.h"
#include "procs/objectmap/voxel_key.h"

namespace slamaware::objectmap {

/// A frame's evidence about one candidate.
struct View {
  int64_t utime = 0;            ///< µs, capture time of the frame
  int32_t seq = -1;             ///< seq of the frame
  float area = 0;               ///< px², area of the box
  std::vector<float> log_prob;  ///< natural log p(class | box), classes in the map's order
  /// Frames this view stands for: 1, or the frames of the time bin its candidate's older views were
  /// merged into (ObjectTable::mergeOldViews(), views_full_rate_s).
  int32_t frames = 1;
  /// A merged view's p(object) per frame, the mean of its frames' (then `area` is their mean area
  /// and `log_prob` their mean, weighted by objectness when the map fuses so); < 0: a frame's view,
  /// whose p(object) is 1 - p(background) from `log_prob`.
  float objectness = -1;
};

/// The seq of a merged view's key (ObjectTable::mergeOldViews()): its utime is the start of its
/// bin.
constexpr int32_t kMergedViewSeq = -1;

/// Views are identified by their frame: (utime, seq).
using ViewKey = std::pair<int64_t, int32_t>;

/// sumLogProbabilities() (fusion.h) of views, each counted for the frames it stands for.
std::vector<double> sumViewEvidence(const std::vector<const View*>& views, size_t num_classes,
                                    bool objectness_weights, double* total_weight);

struct Candidate {
  int32_t id = -1;
  std::map<ViewKey, View> views;
  /// (voxel, views that voted it), sorted by voxel: 16 bytes a voxel (a hash map took about 50;
  /// votes are most of the map's memory).
  std::vector<std::pair<VoxelKey, int32_t>> votes;
  int32_t voting_views = 0;  ///< views that voted (localised, with a depth)
  /// Where its boxes put it (box centres back-projected at their median depth), for objects that
  /// have no voxels yet: sum, count, and the last box's larger side in map units.
  Eigen::Vector3d box_position_sum = Eigen::Vector3d::Zero();
  int32_t box_positions = 0;
  double box_size = 0;
  std::vector<VoxelKey> voxels;  ///< derived by ObjectTable::update(), sorted
  /// The class a user gave its object (ObjectTable::setUserLabel), "" if none. Held by the
  /// candidates, so that it stays with them whatever the grouping does.
  std::string user_label;
};

struct Object {
  int32_t id = -1;
  std::vector<int32_t> candidates;  ///< sorted candidate ids
  // Derived by ObjectTable::update():
  std::vector<double> log_evidence;  ///< per class, sum over the union of views
  double evidence_weight = 0;        ///< the views' total weight in log_evidence
  std::vector<double> posterior;     ///< posteriorFromLogEvidence() of log_evidence (fusion.h)
  int label = -1;                    ///< argmax class, -1 without classes
  int32_t num_views = 0;             ///< frames its fused views stand for (one per frame)
  bool has_position = false;         ///< false: never seen from a localised frame
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< map units
  Eigen::Vector3d extent = Eigen::Vector3d::Zero();    ///< map units, axis-aligned size
  int32_t num_voxels = 0;
  /// Its first and last views' frames (the first: the start of its bin once old views were
  /// merged).
  int64_t first_seen_utime = 0, last_seen_utime = 0;
  /// The user's class: the user_label held by most of its candidates (ties: the first name in
  /// order), "" if none holds one.
  std::string user_label;
};

class ObjectTable {
 public:
  /// views_full_rate_s: every view of the last views_full_rate_s seconds (before the table's
  /// newest view) is kept, older ones are merged (mergeOldViews()); <= 0: every view is kept.
  explicit ObjectTable(double resolution, double views_full_rate_s = 0)
      : resolution_(resolution),
        full_rate_us_(static_cast<int64_t>(std::max(0.0, views_full_rate_s) * 1e6)) {}

  double resolution() const { return resolution_; }

  /// Adds (or replaces: same frame) a view of a candidate, creating the candidate.
  void addView(int32_t candidate, View view);
  /// One view's votes for a candidate's voxels (`keys` sorted, as voxelsInBoxes() gives them;
  /// sorted here otherwise). Every 10 voting views, voxels voted in less than
  /// forget_share of them are forgotten (bounded memory; they come back if voted again).
  void addVotes(int32_t candidate, const std::vector<VoxelKey>& keys, const VotingOptions& options);
  /// Where a box of the candidate puts it (see Candidate::box_position_sum).
  void addBoxPosition(int32_t candidate, const Eigen::Vector3d& p_world, double size);

  /// Bounds the views of a long session. Views older than the full-rate period P (before
  /// `now_utime`) are merged, per candidate, into time bins: a view between P 2^(k-1) and P 2^k old
  /// goes into the bin of width P 2^(k-1) / 16 (aligned to multiples of it, so that the bins of
  /// every candidate are the same and nest as they age) holding its capture time. A merged view
  /// (key: the bin's start, kMergedViewSeq) stands for the frames of its views, with their mean
  /// log p per class (weighted by objectness when `objectness_weights`, as fusion weighs them),
  /// their mean objectness and area: its term in the object's evidence and weight is theirs
  /// exactly, and a candidate keeps the views of the last P plus at most 16 per doubling of its
  /// age. A candidate that stands for fewer frames than 2^k, k its newest view's, is forgotten
  /// (seen in a few frames long ago: a tentative cluster of the proposals stage, most often): the
  /// sampling this merging replaced kept on average 2^-k of such views. A candidate holding a
  /// user's label keeps every view. The candidates of an object the last update() called background
  /// (without a user's label) and that no view of the last P shows are forgotten: background is
  /// kept only while it is in view. Run by update() whenever the newest view is P / 8 past the
  /// last run.
  void mergeOldViews(int64_t now_utime, bool objectness_weights);

  /// Bounds what an object keeps of its past. The candidates of an object (as of the last update())
  /// that no view of the full-rate period before `now_utime` shows are folded into one of them (the
  /// lowest id; only candidates holding the same user's label are folded together): its views are
  /// the union of theirs (per frame the most object-like, the rule of the object's fusion), its
  /// votes per voxel the largest of theirs once each is scaled to the largest number of voting
  /// views (a candidate's votes below its own voxel threshold are dropped first), its box
  /// positions the sum, its box size the largest. The object's evidence, voxels and extent are the
  /// same (the folded candidate's voxels are the union of theirs); what it stops growing with is
  /// the number of candidates the proposals gave it as their clusters came and went. Run by
  /// update() with mergeOldViews().
  void foldStaleCandidates(int64_t now_utime, const VotingOptions& options);

  /// Merges old views and folds stale candidates (mergeOldViews(), foldStaleCandidates(), when
  /// due), then recomputes the candidates' voxels (voted in >= min_votes and >= min_vote_share of
  /// the voting views, and occupied now), the groups (GroupingOptions: pairs of candidates are
  /// tried from the most overlapping, and two groups merge when their voxel unions pass the test),
  /// the object ids (new_id() for groups that continue no previous object) and every object's
  /// evidence and geometry.
  void update(const std::function<bool(VoxelKey)>& occupied, const VotingOptions& options,
              const GroupingOptions& grouping, size_t num_classes,
              const std::function<int32_t()>& new_id, const FusionOptions& fusion = {});

  const std::map<int32_t, Candidate>& candidates() const { return candidates_; }
  Candidate* findCandidate(int32_t id);
  /// Objects by id (as of the last update()).
  const std::map<int32_t, Object>& objects() const { return objects_; }
  /// The object a candidate belongs to (as of the last update()); nullptr for a candidate that no
  /// object holds (unknown, or added since).
  const Object* objectOfCandidate(int32_t candidate) const;

  /// Classes changed: the view value of old class i moves to index old_to_new[i]; a class a view
  /// did not have was part of its background: it gets the view's log p of old class
  /// `old_background` (without one, the view's lowest log-probability; see README).
  void remapClasses(const std::vector<int>& old_to_new, size_t new_size, int old_background = -1);

  /// Gives (label "") or takes back a user's class for an object: every candidate it holds now
  /// carries it. false: no object has this id.
  bool setUserLabel(int32_t object_id, const std::string& label);

  /// Restores a candidate and a previous grouping (loading a saved map); update() follows.
  Candidate& restoreCandidate(int32_t id) { return candidates_[id]; }
  void restoreObject(int32_t id, std::vector<int32_t> candidates);

 private:
  /// The user_label most of `members` (candidate ids) hold (ties: the first in order), "" if none.
  std::string userLabelOf(const std::vector<int32_t>& members) const;
  /// A group's fused views and evidence and its voxels, each computed once per update() (a
  /// group: its sorted candidate ids).
  class GroupFacts;
  /// Merges groups whose fused evidence gives the same object class (not `background`) and that
  /// share same_label_overlap of the smaller's voxels (parts and wholes of one object); order kept.
  std::vector<std::vector<int32_t>> mergeSameLabel(std::vector<std::vector<int32_t>> groups,
                                                   const GroupingOptions& grouping,
                                                   GroupFacts& facts, int background) const;

  /// The sorted union of a group's candidates' voxels (GroupFacts keeps each group's once).
  std::vector<VoxelKey> groupVoxels(const std::vector<int32_t>& group) const;

  // The steps of update().
  /// Each candidate's voxels: voted often enough, and occupied now.
  void deriveVoxels(const std::function<bool(VoxelKey)>& occupied, const VotingOptions& options);
  /// Groups of candidates by shared voxels (GroupingOptions), in order of their lowest candidate.
  std::vector<std::vector<int32_t>> groupOverlapping(const GroupingOptions& grouping) const;
  /// The id of each group: a previous object's, or new_id().
  std::vector<int32_t> stableIds(const std::vector<std::vector<int32_t>>& groups,
                                 const std::function<int32_t()>& new_id) const;
  /// The object a group makes: its evidence and geometry.
  Object describeGroup(int32_t id, const std::vector<int32_t>& members, GroupFacts& facts,
                       const FusionOptions& fusion) const;

  double resolution_;
  int64_t full_rate_us_ = 0;
  int64_t newest_view_utime_ = 0;
  int64_t next_merge_utime_ = 0;
  std::map<int32_t, Candidate> candidates_;
  std::map<int32_t, Object> objects_;
};

}  // namespace slamaware::objectmap
