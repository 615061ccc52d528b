#pragma once
// The object map without the bus: SLAM_MAP, SLAM_POSE, CAMERA_INFO, PROPOSALS and DETECTIONS
// messages in; the OBJECT_MAP message, query replies and a snapshot for saving out. The node
// (objectmap_main.cpp) feeds it from LCM; tests feed it directly.
//
// Segments: each SLAM map (map id) is a segment with its own occupancy and objects; a new map id
// starts a new segment and the others stay as they are (queryable, saved). SLAM map ids are
// unique only within one run of the pipeline, so the segment of a map id is looked up in the
// current session; a new session starts when the pose stream goes back in seq or time (the
// camera or a replay restarted), and its map ids get new segments. A segment's id is its SLAM map
// id unless an earlier session used that id.
//
// Per frame (the join on seq of SLAM_POSE, PROPOSALS and DETECTIONS): every box adds a view of
// its candidate with the box's class log-probabilities; in a localised frame it also votes for the
// occupied voxels it covers near the candidate's median depth (candidate_voxels.h). Objects are
// regrouped after each DETECTIONS (and after a restore): reading the map (objectMap(), answer(),
// snapshot(): const) never changes it, so in lockstep the objects and their ids do not depend on
// when the node saved or was queried; occupancy changes show at the next DETECTIONS.
// Regrouping is the costly part and its cost grows with the session (every candidate of a segment
// is grouped again); in real time the node defers it (deferRegrouping()) and calls regroup() at
// most every regroup_period_s, before answering a query and before the last save.
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "common/camera_model.h"
#include "procs/objectmap/map_store.h"
#include "procs/objectmap/object_table.h"
#include "procs/objectmap/objectmap_options.h"
#include "procs/objectmap/occupancy_map.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/detections_t.hpp"
#include "slamaware/object_detections_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/object_query_reply_t.hpp"
#include "slamaware/object_query_t.hpp"
#include "slamaware/point_cloud_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/proposals_t.hpp"

namespace slamaware::objectmap {

/// The name of the class that means "no object" (the recognizer's last class).
constexpr const char* kBackgroundClass = "background";

/// Colour of a class's voxels in the saved .ot: fixed per class name (a table for the paper's five
/// classes, else a hue from a hash of the name), dark grey for background; kUnassignedColour for
/// occupied voxels of no object. The JSON lists the colours of its classes ("colours").
Rgb labelColour(const std::string& class_name);
constexpr Rgb kUnassignedColour{170, 170, 170};

struct Segment {
  int32_t id = -1;           ///< object_t.map_id
  int32_t slam_map_id = -1;  ///< SLAM's map id in the session that created it
  OccupancyMap occupancy;
  ObjectTable table;
  bool dirty = true;  ///< objects need regrouping
  /// SLAM keyframe -> its points already in the map (from incremental clouds or the last full
  /// one). SLAM republishes a keyframe as its points converge, appending to them: only the new
  /// ones are inserted.
  std::map<int32_t, size_t> inserted;
  Segment(int32_t id, int32_t slam_map_id, OccupancyMap map, double views_full_rate_s)
      : id(id),
        slam_map_id(slam_map_id),
        occupancy(std::move(map)),
        table(occupancy.resolution(), views_full_rate_s) {}
};

struct CloudReport {
  int32_t segment = -1;
  bool full = false;
  InsertStats insert;
  size_t repeated = 0;  ///< points of a republished keyframe that were inserted before
  /// A full cloud's keyframes: given again as they were, replaced (moved, points added or
  /// dropped), taken back (no longer in SLAM's map).
  size_t keyframes_unchanged = 0, keyframes_changed = 0, keyframes_removed = 0;
  double ms = 0;
};

struct FrameReport {
  int32_t segment = -1;
  int boxes = 0;            ///< boxes fused (views added)
  int boxes_rejected = 0;   ///< non-finite box or log-probabilities
  int boxes_voted = 0;      ///< boxes that voted for voxels
  bool localised = false;   ///< the frame had a usable pose, camera and proposals
  std::string no_geometry;  ///< why the frame's boxes did not vote ("" if they did)
};

class ObjectMapEngine {
 public:
  explicit ObjectMapEngine(const ObjectMapOptions& options);
  ObjectMapEngine(ObjectMapEngine&&) noexcept;
  ObjectMapEngine& operator=(ObjectMapEngine&&) noexcept;
  ~ObjectMapEngine();

  /// False (and *why) for a camera that cannot be used.
  bool onCameraInfo(const camera_info_t& info, std::string* why);
  /// Inserts a cloud into its segment's occupancy (a full cloud replaces it). False (and *why)
  /// when the arrays disagree with the counts.
  bool onMap(const point_cloud_t& cloud, std::string* why, CloudReport* report = nullptr);
  /// Keeps the pose for the join (bounded); a pose going back in seq or time starts a new session.
  /// False (and *why) for a non-finite pose (it is not kept).
  bool onPose(const pose_t& pose, std::string* why);
  /// Keeps the proposals for the join (bounded). False (and *why) when the arrays disagree.
  bool onProposals(const proposals_t& proposals, std::string* why);
  /// Fuses one frame's detections. False (and *why) for a malformed message (arrays that disagree,
  /// repeated class names): nothing of it is used. Bad boxes are skipped and counted in the report.
  bool onDetections(const detections_t& detections, std::string* why,
                    FrameReport* report = nullptr);

  /// The OBJECT_MAP message (saved_map_path and saved_utime are the node's business).
  object_map_t objectMap() const;
  /// OBJECT_DETECTIONS of a DETECTIONS message just given to onDetections(): every box of it with
  /// its object as the map holds it now (regrouped after the frame unless deferred), the object's
  /// posterior and the box's score (frame_labels.h). The boxes of a message the map refused are
  /// labelled by what it holds (nothing of the frame fused); a candidate it holds nothing of keeps
  /// the box's own evidence (NO_OBJECT).
  object_detections_t frameDetections(const detections_t& detections) const;
  /// The reply to a query (error set for an unknown kind, label or map id, or a bad region).
  object_query_reply_t answer(const object_query_t& query) const;
  /// KIND_LABEL / KIND_UNLABEL: gives (or takes back) a user's class for the object `object_id`
  /// (ObjectTable::setUserLabel); the reply holds the object, or an error for an unknown id or a
  /// name that cannot be a category folder (1-64 of A-Z a-z 0-9 _ -). Regroups first.
  object_query_reply_t label(const object_query_t& query);

  /// Everything needed to continue after a restart (regroups first; colours the trees by label).
  MapSnapshot snapshot() const;
  /// Replaces the state by a saved one. Throws std::runtime_error when the content is
  /// inconsistent; the state is then unchanged.
  void restore(const MapSnapshot& snapshot);

  /// Increments whenever objects or occupancy may have changed (save on change).
  int64_t changes() const { return changes_; }

  /// true: DETECTIONS only collect evidence and votes, and the objects change at regroup() (real
  /// time); false (the default: lockstep, the evaluator): regrouped after every DETECTIONS.
  void deferRegrouping(bool defer) { defer_regrouping_ = defer; }
  /// Whether inputs since the last regrouping may change the objects.
  bool regroupPending() const;
  /// Regroups the segments whose voxels or evidence changed (after each input unless deferred, and
  /// after a restore).
  void regroup();
  /// Increments for each segment regrouped (publish on change).
  int64_t regroupings() const { return regroupings_; }
  const std::vector<std::string>& classes() const { return classes_; }
  /// Segments by id.
  const std::map<int32_t, std::unique_ptr<Segment>>& segments() const { return segments_; }
  /// The segment the last localised pose or detections were in, -1 before any.
  int32_t currentSegment() const { return current_segment_; }
  int64_t sessions() const { return sessions_; }
  size_t numObjects() const;
  size_t numCandidates() const;
  /// The views the candidates hold (merged views count once).
  size_t numViews() const;
  size_t numOccupiedVoxels() const;
  /// The object that a candidate of a SLAM map (of the current session) belongs to now, after
  /// regrouping; nullptr when the map or the candidate is unknown. Read-only use (the evaluator's
  /// multi-view labels); the pointer is valid until the next input.
  const Object* objectOfCandidate(int32_t slam_map_id, int32_t candidate) const;

 private:
  Segment& segmentFor(int32_t slam_map_id);
  std::vector<int> mapClasses(const std::vector<std::string>& names);
  /// Each name's index in the map's classes (-1: not one of them).
  std::vector<int> classIndices(const std::vector<std::string>& names) const;

  ObjectMapOptions options_;
  CameraModel camera_;
  bool have_camera_ = false;
  std::vector<std::string> classes_;
  std::map<int32_t, std::unique_ptr<Segment>> segments_;
  std::map<int32_t, int32_t> session_maps_;  ///< SLAM map id -> segment id, this session
  int64_t sessions_ = 1;
  int64_t last_pose_utime_ = 0;
  int32_t last_pose_seq_ = -1;
  std::map<int32_t, pose_t> poses_;
  std::map<int32_t, proposals_t> proposals_;
  int32_t next_object_id_ = 1;
  int32_t current_segment_ = -1;
  int64_t last_utime_ = 0;
  int32_t last_seq_ = -1;
  int64_t changes_ = 0;
  bool defer_regrouping_ = false;
  int64_t regroupings_ = 0;
};

/// Lockstep order of the inputs (docs/architecture.md §4): a frame's SLAM_MAP, SLAM_POSE and
/// PROPOSALS messages are handled when a DETECTIONS message of that frame or a later one comes,
/// just before it, in their order of arrival. With several frames in the pipeline
/// (`bus.lockstep_window`) a later frame's map may arrive before an earlier frame's detections;
/// in this order it is never fused into them, so the outputs are those of one frame at a time.
/// Late proposals (a map's reference keyframe, sent just before the frame that released them)
/// release the inputs of that frame too, as one frame at a time would have had them: that frame
/// is the first SLAM_POSE after the newest PROPOSALS seen when they came.
/// The node and the evaluator's re-run of a recording (tools/eval) both go through it.
class LockstepInputs {
 public:
  using Input = std::variant<point_cloud_t, pose_t, proposals_t>;
  using Handler = std::function<void(const Input&)>;
  /// Inputs kept at most; beyond, the oldest is handled at once (no DETECTIONS are coming).
  static constexpr size_t kMaxWaiting = 64;

  /// Keeps `input` of frame `seq` (or hands the oldest to `handle` when too many wait).
  void add(int32_t seq, Input input, const Handler& handle);
  /// Hands the inputs of frames up to `seq` (for late proposals' frame: up to the frame that
  /// released them) to `handle`, in their order of arrival.
  void releaseUpTo(int32_t seq, const Handler& handle);
  size_t waiting() const { return waiting_.size(); }

 private:
  std::deque<std::pair<int32_t, Input>> waiting_;
  std::optional<int32_t> newest_proposals_;
  std::deque<int32_t> poses_;               ///< seqs of the latest SLAM_POSE messages
  std::map<int32_t, int32_t> released_by_;  ///< late proposals' seq -> the frame that released them
};

}  // namespace slamaware::objectmap
