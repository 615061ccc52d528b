#include "procs/objectmap/object_map.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "common/bus/image_msg.h"
#include "common/geometry.h"
#include "procs/objectmap/candidate_voxels.h"
#include "procs/objectmap/frame_labels.h"
#include "procs/objectmap/json_number.h"

namespace slamaware::objectmap {

namespace {

using json = nlohmann::json;

/// A log-probability above this is not one (rounding in the producer is allowed for).
constexpr float kMaxLogProb = 1e-3f;

const double kNaN = std::numeric_limits<double>::quiet_NaN();

bool localisedState(int8_t state) {
  return state == pose_t::STATE_TRACKING || state == pose_t::STATE_RELOCALIZED;
}

const char* stateName(int8_t state) {
  switch (state) {
    case pose_t::STATE_INITIALIZING:
      return "INITIALIZING";
    case pose_t::STATE_TRACKING:
      return "TRACKING";
    case pose_t::STATE_LOST:
      return "LOST";
    case pose_t::STATE_RELOCALIZED:
      return "RELOCALIZED";
    default:
      return "unknown";
  }
}

/// The double nearest to the shortest decimal that gives back `f`: JSON then stores "0.1", not
/// "0.10000000149011612", and reading it back gives exactly `f`.
double compactFloat(float f) {
  if (!std::isfinite(f)) return static_cast<double>(f);
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), f);
  double d = static_cast<double>(f);
  std::from_chars(buf, r.ptr, d);  // locale-independent, unlike strtod
  return d;
}

template <class T>
void trimTo(std::map<int32_t, T>& buffer, int max_size) {
  while (buffer.size() > static_cast<size_t>(std::max(1, max_size))) buffer.erase(buffer.begin());
}

json vec3(const Eigen::Vector3d& v) {
  json a = json::array();
  for (int i = 0; i < 3; ++i) a.push_back(v[i]);
  return a;
}

Eigen::Vector3d vec3From(const json& a) {
  if (!a.is_array() || a.size() != 3) throw std::runtime_error("expected 3 numbers");
  return Eigen::Vector3d(jsonFloat<double>(a[0]), jsonFloat<double>(a[1]), jsonFloat<double>(a[2]));
}

}  // namespace

Rgb labelColour(const std::string& name) {
  if (name == kBackgroundClass) return Rgb{70, 70, 70};
  // The paper's five classes (config/objects/uw5.yaml) get colours that are easy to tell apart in
  // octovis; any other name a fixed hue from a hash of the name, whatever the map's class order.
  static const std::map<std::string, Rgb> table = {{"bowl", {230, 25, 75}},
                                                   {"cap", {60, 180, 75}},
                                                   {"cereal_box", {255, 225, 25}},
                                                   {"coffee_mug", {0, 130, 200}},
                                                   {"soda_can", {245, 130, 48}}};
  if (auto it = table.find(name); it != table.end()) return it->second;
  uint32_t h = 2166136261u;  // FNV-1a
  for (unsigned char ch : name) h = (h ^ ch) * 16777619u;
  const double hue = (h % 360u) / 60.0, s = 0.85, v = 0.95;
  const double c = v * s, x = c * (1 - std::fabs(std::fmod(hue, 2.0) - 1)), m = v - c;
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(hue)) {
    case 0:
      r = c, g = x;
      break;
    case 1:
      r = x, g = c;
      break;
    case 2:
      g = c, b = x;
      break;
    case 3:
      g = x, b = c;
      break;
    case 4:
      r = x, b = c;
      break;
    default:
      r = c, b = x;
      break;
  }
  auto to8 = [&](double u) { return static_cast<uint8_t>(std::lround(255 * (u + m))); };
  return Rgb{to8(r), to8(g), to8(b)};
}

ObjectMapEngine::ObjectMapEngine(const ObjectMapOptions& options) : options_(options) {}
ObjectMapEngine::ObjectMapEngine(ObjectMapEngine&&) noexcept = default;
ObjectMapEngine& ObjectMapEngine::operator=(ObjectMapEngine&&) noexcept = default;
ObjectMapEngine::~ObjectMapEngine() = default;

bool ObjectMapEngine::onCameraInfo(const camera_info_t& info, std::string* why) {
  CameraModel camera;
  if (!cameraFromMessage(info, &camera, why)) return false;
  camera_ = camera;
  have_camera_ = true;
  return true;
}

Segment& ObjectMapEngine::segmentFor(int32_t slam_map_id) {
  auto it = session_maps_.find(slam_map_id);
  if (it != session_maps_.end()) return *segments_.at(it->second);
  int32_t id = slam_map_id;
  if (id < 0 || segments_.count(id))
    id = segments_.empty() ? 0 : std::max(0, segments_.rbegin()->first + 1);
  auto seg = std::make_unique<Segment>(
      id, slam_map_id, OccupancyMap(options_.occupancy, options_.occupancy.resolution),
      options_.views_full_rate_s);
  Segment& ref = *seg;
  segments_.emplace(id, std::move(seg));
  session_maps_[slam_map_id] = id;
  return ref;
}

bool ObjectMapEngine::onMap(const point_cloud_t& c, std::string* why, CloudReport* report) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = static_cast<size_t>(std::max(0, c.num_points));
  if (c.num_points < 0 || c.x.size() != n || c.y.size() != n || c.z.size() != n ||
      c.depth_std.size() != n || c.keyframe_ids.size() != n) {
    *why = "point cloud of seq " + std::to_string(c.seq) + ": arrays disagree with num_points " +
           std::to_string(c.num_points);
    return false;
  }
  const size_t nk = static_cast<size_t>(std::max(0, c.num_keyframes));
  if (c.num_keyframes < 0 || c.kf_ids.size() != nk || c.kf_x.size() != nk || c.kf_y.size() != nk ||
      c.kf_z.size() != nk) {
    *why = "point cloud of seq " + std::to_string(c.seq) +
           ": keyframe arrays disagree with num_keyframes " + std::to_string(c.num_keyframes);
    return false;
  }
  Segment& seg = segmentFor(c.map_id);
  std::unordered_map<int32_t, Eigen::Vector3f> origins;
  for (size_t k = 0; k < nk; ++k) {
    const Eigen::Vector3f o(c.kf_x[k], c.kf_y[k], c.kf_z[k]);
    if (o.allFinite()) origins[c.kf_ids[k]] = o;
  }
  // One batch per keyframe (its points share the ray origin), in keyframe order.
  const int max_points = std::max(1, options_.occupancy.max_points);
  const size_t stride =
      c.full && n > static_cast<size_t>(max_points) ? (n + max_points - 1) / max_points : 1;
  std::map<int32_t, std::vector<Eigen::Vector3f>> batches;
  CloudReport r;
  r.full = c.full;
  r.segment = seg.id;
  std::map<int32_t, size_t> seen;  // points of each keyframe in this cloud
  for (size_t i = 0; i < n; ++i) {
    // Its index among its keyframe's points: in an incremental cloud those before seg.inserted
    // are in the map already. A full cloud gives each keyframe's points whole.
    const size_t index = seen[c.keyframe_ids[i]]++;
    if (i % stride != 0) continue;
    if (!c.full && index < seg.inserted[c.keyframe_ids[i]]) {
      ++r.repeated;
      continue;
    }
    if (options_.occupancy.max_depth_std > 0 &&
        !(c.depth_std[i] <= options_.occupancy.max_depth_std)) {
      ++r.insert.dropped;
      continue;
    }
    batches[c.keyframe_ids[i]].emplace_back(c.x[i], c.y[i], c.z[i]);
  }
  if (c.full) {
    // Every keyframe's points as they are now: a keyframe whose points or origin changed is
    // replaced, one no longer in the map (culled, or without points) is taken back, the others
    // cost nothing (OccupancyMap: the evidence of keyframes adds up in any order).
    for (int32_t kf : seg.occupancy.keyframes())
      if (!batches.count(kf)) {
        seg.occupancy.removeKeyframe(kf);
        ++r.keyframes_removed;
      }
    seg.inserted.clear();
  }
  for (const auto& [kf, count] : seen) seg.inserted[kf] = std::max(seg.inserted[kf], count);
  for (const auto& [kf, points] : batches) {
    auto o = origins.find(kf);
    const Eigen::Vector3f* origin = o == origins.end() ? nullptr : &o->second;
    const InsertStats s = c.full ? seg.occupancy.setKeyframe(kf, points, origin)
                                 : seg.occupancy.addToKeyframe(kf, points, origin);
    if (c.full) ++(s.unchanged ? r.keyframes_unchanged : r.keyframes_changed);
    r.repeated += s.unchanged;
    r.insert.points += s.points;
    r.insert.dropped += s.dropped;
    r.insert.occupied_updates += s.occupied_updates;
    r.insert.free_updates += s.free_updates;
  }
  seg.dirty = true;
  ++changes_;
  r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (report) *report = r;
  return true;
}

bool ObjectMapEngine::onPose(const pose_t& pose, std::string* why) {
  bool finite = true;
  for (double v : pose.position) finite = finite && std::isfinite(v);
  double qn = 0;
  for (double v : pose.orientation) {
    finite = finite && std::isfinite(v);
    qn += v * v;
  }
  if (!finite || (localisedState(pose.state) && qn < 1e-12)) {
    *why = "pose of seq " + std::to_string(pose.seq) + " is not finite or has a zero quaternion";
    return false;
  }
  if (last_pose_seq_ >= 0 && (pose.seq < last_pose_seq_ || pose.utime < last_pose_utime_)) {
    // The camera or a replay restarted: SLAM's map ids start again and mean other maps. The
    // segments of the session that ended take no more clouds.
    ++sessions_;
    for (const auto& [slam_id, sid] : session_maps_) {
      segments_.at(sid)->occupancy.freeze();
      segments_.at(sid)->inserted.clear();
    }
    session_maps_.clear();
    poses_.clear();
    proposals_.clear();
  }
  last_pose_seq_ = pose.seq;
  last_pose_utime_ = pose.utime;
  if (localisedState(pose.state)) current_segment_ = segmentFor(pose.map_id).id;
  poses_[pose.seq] = pose;
  trimTo(poses_, options_.seq_buffer);
  return true;
}

bool ObjectMapEngine::onProposals(const proposals_t& p, std::string* why) {
  const size_t n = static_cast<size_t>(std::max(0, p.num_boxes));
  if (p.num_boxes < 0 || p.boxes.size() != n || p.candidate_ids.size() != n ||
      p.median_depth.size() != n) {
    *why = "proposals of seq " + std::to_string(p.seq) + ": arrays disagree with num_boxes";
    return false;
  }
  proposals_[p.seq] = p;
  trimTo(proposals_, options_.seq_buffer);
  return true;
}

std::vector<int> ObjectMapEngine::mapClasses(const std::vector<std::string>& names) {
  std::vector<std::string> list = classes_;
  bool added = false;
  for (const auto& name : names) {
    if (std::find(list.begin(), list.end(), name) != list.end()) continue;
    // "background" stays last, as in DETECTIONS.
    auto bg = std::find(list.begin(), list.end(), std::string(kBackgroundClass));
    if (name != kBackgroundClass && bg != list.end())
      list.insert(bg, name);
    else
      list.push_back(name);
    added = true;
  }
  if (added) {
    std::vector<int> old_to_new(classes_.size());
    for (size_t i = 0; i < classes_.size(); ++i)
      old_to_new[i] =
          static_cast<int>(std::find(list.begin(), list.end(), classes_[i]) - list.begin());
    const auto old_bg = std::find(classes_.begin(), classes_.end(), std::string(kBackgroundClass));
    const int old_background =
        old_bg == classes_.end() ? -1 : static_cast<int>(old_bg - classes_.begin());
    for (auto& [id, seg] : segments_) {
      seg->table.remapClasses(old_to_new, list.size(), old_background);
      seg->dirty = true;
    }
    classes_ = std::move(list);
    ++changes_;
  }
  return classIndices(names);
}

std::vector<int> ObjectMapEngine::classIndices(const std::vector<std::string>& names) const {
  std::vector<int> to_map(names.size(), -1);
  for (size_t k = 0; k < names.size(); ++k)
    if (auto it = std::find(classes_.begin(), classes_.end(), names[k]); it != classes_.end())
      to_map[k] = static_cast<int>(it - classes_.begin());
  return to_map;
}

namespace {

/// Whether a DETECTIONS message's arrays agree with its counts and its class names are usable;
/// otherwise `*why` says what is wrong.
bool consistentDetections(const detections_t& d, std::string* why) {
  const size_t nb = static_cast<size_t>(std::max(0, d.num_boxes));
  const size_t nc = static_cast<size_t>(std::max(0, d.num_classes));
  const std::string what = "detections of seq " + std::to_string(d.seq);
  if (d.num_boxes < 0 || d.num_classes < 0 || d.class_names.size() != nc || d.boxes.size() != nb ||
      d.candidate_ids.size() != nb || d.log_prob.size() != nb) {
    *why = what + ": arrays disagree with num_boxes / num_classes";
    return false;
  }
  for (const auto& row : d.log_prob)
    if (row.size() != nc) {
      *why = what + ": a log_prob row is not num_classes long";
      return false;
    }
  std::set<std::string> unique;
  for (const auto& name : d.class_names)
    if (name.empty() || !unique.insert(name).second) {
      *why = what + ": empty or repeated class name '" + name + "'";
      return false;
    }
  return true;
}

/// Why a frame's boxes cannot vote for voxels (empty: they can): its pose, proposals and the
/// camera must be there, localised, in the detections' map.
std::string whyNoGeometry(const detections_t& d, const pose_t* pose, const proposals_t* proposals,
                          bool have_camera) {
  if (!pose) return "no SLAM_POSE for seq " + std::to_string(d.seq);
  if (!localisedState(pose->state))
    return std::string("frame not localised (") + stateName(pose->state) + ")";
  if (pose->map_id != d.map_id)
    return "pose in map " + std::to_string(pose->map_id) + ", detections in map " +
           std::to_string(d.map_id);
  if (!proposals || proposals->map_id != d.map_id)
    return "no PROPOSALS of map " + std::to_string(d.map_id) + " for seq " + std::to_string(d.seq);
  if (!have_camera) return "no CAMERA_INFO yet";
  return std::string();
}

}  // namespace

bool ObjectMapEngine::onDetections(const detections_t& d, std::string* why, FrameReport* report) {
  if (!consistentDetections(d, why)) return false;
  const size_t nb = static_cast<size_t>(d.num_boxes);
  const size_t nc = static_cast<size_t>(d.num_classes);
  FrameReport r;
  last_utime_ = d.utime;
  last_seq_ = d.seq;
  if (nb == 0 || nc == 0) {
    if (!defer_regrouping_) regroup();  // occupancy may have changed since the last frame
    if (report) *report = r;
    return true;
  }
  const std::vector<int> to_map = mapClasses(d.class_names);
  const auto msg_bg =
      std::find(d.class_names.begin(), d.class_names.end(), std::string(kBackgroundClass));
  const int msg_background =
      msg_bg == d.class_names.end() ? -1 : static_cast<int>(msg_bg - d.class_names.begin());
  Segment& seg = segmentFor(d.map_id);
  r.segment = seg.id;
  current_segment_ = seg.id;

  // The join: the frame's pose and proposals (they arrive before its detections).
  const pose_t* pose = nullptr;
  const proposals_t* proposals = nullptr;
  if (auto it = poses_.find(d.seq); it != poses_.end() && it->second.utime == d.utime)
    pose = &it->second;
  if (auto it = proposals_.find(d.seq); it != proposals_.end() && it->second.utime == d.utime)
    proposals = &it->second;
  r.no_geometry = whyNoGeometry(d, pose, proposals, have_camera_);
  r.localised = r.no_geometry.empty();

  // One box per candidate and frame (the larger, if the recognizer sent two).
  std::map<int32_t, size_t> box_of;
  for (size_t i = 0; i < nb; ++i) {
    const box_t& b = d.boxes[i];
    bool ok = std::isfinite(b.x) && std::isfinite(b.y) && std::isfinite(b.w) &&
              std::isfinite(b.h) && b.w > 0 && b.h > 0;
    for (float lp : d.log_prob[i]) ok = ok && !std::isnan(lp) && lp <= kMaxLogProb;
    if (!ok) {
      ++r.boxes_rejected;
      continue;
    }
    auto [it, inserted] = box_of.emplace(d.candidate_ids[i], i);
    if (!inserted && b.w * b.h > d.boxes[it->second].w * d.boxes[it->second].h) it->second = i;
  }
  std::vector<VoteBox> vote_boxes;
  std::vector<int32_t> vote_candidates;
  const SE3 T_world_camera =
      r.localised ? se3FromArrays(pose->position, pose->orientation) : SE3::Identity();
  for (const auto& [cid, i] : box_of) {
    const box_t& b = d.boxes[i];
    View v;
    v.utime = d.utime;
    v.seq = d.seq;
    v.area = b.w * b.h;
    const auto& row = d.log_prob[i];
    // A class of the map that the message's model lacks was part of that model's background: it
    // gets the box's background log-probability (no evidence for or against it beside background).
    const float missing =
        std::max(kMinLogProb, msg_background >= 0 ? row[static_cast<size_t>(msg_background)]
                                                  : *std::min_element(row.begin(), row.end()));
    v.log_prob.assign(classes_.size(), missing);
    for (size_t k = 0; k < nc; ++k)
      v.log_prob[static_cast<size_t>(to_map[k])] = std::max(kMinLogProb, row[k]);
    seg.table.addView(cid, std::move(v));
    ++r.boxes;
    if (!r.localised) continue;
    float depth = -1;
    for (size_t j = 0; j < proposals->candidate_ids.size(); ++j)
      if (proposals->candidate_ids[j] == cid) depth = proposals->median_depth[j];
    if (!(depth > 0) || !std::isfinite(depth)) continue;
    VoteBox vb{b.x, b.y, b.w, b.h, depth};
    vote_boxes.push_back(vb);
    vote_candidates.push_back(cid);
    // Where the box says the candidate is, for as long as it has no voxels.
    const Eigen::Vector3d ray =
        camera_.unproject(Eigen::Vector2d(b.x + 0.5 * b.w, b.y + 0.5 * b.h));
    const double f = 0.5 * (camera_.fx() + camera_.fy());
    seg.table.addBoxPosition(cid, T_world_camera * (ray * depth), std::max(b.w, b.h) / f * depth);
  }
  if (!vote_boxes.empty()) {
    const auto voxels = voxelsInBoxes(seg.occupancy.occupied(), camera_, T_world_camera, vote_boxes,
                                      options_.voting);
    for (size_t k = 0; k < vote_boxes.size(); ++k)
      seg.table.addVotes(vote_candidates[k], voxels[k], options_.voting);
    r.boxes_voted = static_cast<int>(vote_boxes.size());
  }
  seg.dirty = true;
  ++changes_;
  // Objects are regrouped here and only here (and after a restore): what the map shows then
  // depends only on the messages fused so far, never on when it is read, saved or queried.
  // Deferred (real time): at the node's regroup().
  if (!defer_regrouping_) regroup();
  if (report) *report = r;
  return true;
}

void ObjectMapEngine::regroup() {
  for (auto& [id, seg] : segments_) {
    if (!seg->dirty) continue;
    Segment& s = *seg;
    s.table.update([&s](VoxelKey k) { return s.occupancy.isOccupied(k); }, options_.voting,
                   options_.grouping, classes_.size(), [this] { return next_object_id_++; },
                   options_.fusion());
    s.dirty = false;
    ++regroupings_;
  }
}

bool ObjectMapEngine::regroupPending() const {
  for (const auto& [id, seg] : segments_)
    if (seg->dirty) return true;
  return false;
}

const Object* ObjectMapEngine::objectOfCandidate(int32_t slam_map_id, int32_t candidate) const {
  const auto it = session_maps_.find(slam_map_id);
  if (it == session_maps_.end()) return nullptr;
  return segments_.at(it->second)->table.objectOfCandidate(candidate);
}

size_t ObjectMapEngine::numObjects() const {
  size_t n = 0;
  for (const auto& [id, seg] : segments_) n += seg->table.objects().size();
  return n;
}

size_t ObjectMapEngine::numCandidates() const {
  size_t n = 0;
  for (const auto& [id, seg] : segments_) n += seg->table.candidates().size();
  return n;
}

size_t ObjectMapEngine::numViews() const {
  size_t n = 0;
  for (const auto& [id, seg] : segments_)
    for (const auto& [cid, c] : seg->table.candidates()) n += c.views.size();
  return n;
}

size_t ObjectMapEngine::numOccupiedVoxels() const {
  size_t n = 0;
  for (const auto& [id, seg] : segments_) n += seg->occupancy.occupied().size();
  return n;
}

namespace {

object_t objectMessage(const Object& o, int32_t segment, const std::vector<std::string>& classes,
                       double views_exponent) {
  object_t m;
  m.id = o.id;
  m.map_id = segment;
  m.label = o.label >= 0 ? classes[static_cast<size_t>(o.label)] : "";
  m.num_classes = static_cast<int32_t>(classes.size());
  m.posterior.resize(classes.size(), 0.f);
  m.log_evidence.resize(classes.size(), 0.f);
  m.log_posterior.resize(classes.size(), 0.f);
  const std::vector<double> log_posterior =
      logPosteriorFromLogEvidence(o.log_evidence, o.evidence_weight, views_exponent);
  for (size_t c = 0; c < classes.size() && c < o.posterior.size(); ++c) {
    m.posterior[c] = static_cast<float>(o.posterior[c]);
    m.log_evidence[c] = static_cast<float>(o.log_evidence[c]);
    if (c < log_posterior.size()) m.log_posterior[c] = static_cast<float>(log_posterior[c]);
  }
  m.num_views = o.num_views;
  for (int i = 0; i < 3; ++i) {
    // Never seen from a localised frame: the position is unknown (NaN), not the origin.
    m.centroid[i] = o.has_position ? o.centroid[i] : kNaN;
    m.extent[i] = o.has_position ? o.extent[i] : kNaN;
  }
  m.num_voxels = o.num_voxels;
  m.first_seen_utime = o.first_seen_utime;
  m.last_seen_utime = o.last_seen_utime;
  m.candidate_ids = o.candidates;
  m.num_candidates = static_cast<int32_t>(o.candidates.size());
  m.user_label = o.user_label;
  return m;
}

/// A reply to `q` with the map's classes and no objects yet.
object_query_reply_t emptyReply(const object_query_t& q, const std::vector<std::string>& classes) {
  object_query_reply_t reply;
  reply.utime = 0;
  reply.request_id = q.request_id;
  reply.class_names = classes;
  reply.num_classes = static_cast<int32_t>(classes.size());
  reply.num_objects = 0;
  return reply;
}

/// A user's class name must be usable as a category folder of an object set.
bool validUserLabel(const std::string& l) {
  return !l.empty() && l.size() <= 64 && std::all_of(l.begin(), l.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-';
  });
}

}  // namespace

object_detections_t ObjectMapEngine::frameDetections(const detections_t& d) const {
  object_detections_t m;
  m.utime = d.utime;
  m.seq = d.seq;
  m.map_id = d.map_id;
  m.class_names = classes_;
  m.num_classes = static_cast<int32_t>(classes_.size());
  const size_t nc = classes_.size();
  const size_t nb = std::min({d.boxes.size(), d.candidate_ids.size(), d.log_prob.size()});
  // The message's classes in the map's order (a message the map refused may name others: those
  // are left at the floor).
  const std::vector<int> to_map = classIndices(d.class_names);
  std::vector<FrameBox> boxes(nb);
  for (size_t i = 0; i < nb; ++i) {
    const box_t& b = d.boxes[i];
    FrameBox& f = boxes[i];
    f.x = b.x, f.y = b.y, f.w = b.w, f.h = b.h;
    f.candidate = d.candidate_ids[i];
    f.log_p.assign(nc, kMinLogProb);
    for (size_t k = 0; k < d.log_prob[i].size() && k < to_map.size(); ++k) {
      const float v = d.log_prob[i][k];
      if (to_map[k] >= 0 && !std::isnan(v))
        f.log_p[static_cast<size_t>(to_map[k])] = std::clamp(v, kMinLogProb, 0.f);
    }
  }
  const ObjectTable* table = nullptr;
  if (auto it = session_maps_.find(d.map_id); it != session_maps_.end())
    table = &segments_.at(it->second)->table;
  const ObjectTable empty(1.0);
  const std::vector<FrameBoxLabel> labels =
      labelFrameBoxes(boxes, table ? *table : empty, nc, options_.fusion());
  m.num_boxes = static_cast<int32_t>(nb);
  for (size_t i = 0; i < nb; ++i) {
    const FrameBoxLabel& l = labels[i];
    m.boxes.push_back(d.boxes[i]);
    m.candidate_ids.push_back(d.candidate_ids[i]);
    m.object_ids.push_back(l.object);
    m.roles.push_back(static_cast<int8_t>(l.role));
    m.labels.push_back(l.label >= 0 ? classes_[static_cast<size_t>(l.label)] : "");
    auto floats = [](const std::vector<double>& v) {
      return std::vector<float>(v.begin(), v.end());
    };
    m.log_posterior.push_back(floats(l.log_posterior));
    m.log_weight.push_back(floats(l.log_weight));
    m.log_score.push_back(floats(l.log_score));
  }
  return m;
}

object_map_t ObjectMapEngine::objectMap() const {
  object_map_t m;
  m.utime = last_utime_;
  m.seq = last_seq_;
  m.map_id = current_segment_;
  m.saved_map_path = "";
  m.saved_utime = 0;
  m.class_names = classes_;
  m.num_classes = static_cast<int32_t>(classes_.size());
  std::map<int32_t, object_t> by_id;
  for (const auto& [sid, seg] : segments_)
    for (const auto& [oid, o] : seg->table.objects())
      by_id.emplace(oid, objectMessage(o, sid, classes_, options_.fusion().views_exponent));
  for (auto& [id, o] : by_id) m.objects.push_back(std::move(o));
  m.num_objects = static_cast<int32_t>(m.objects.size());
  return m;
}

object_query_reply_t ObjectMapEngine::answer(const object_query_t& q) const {
  object_query_reply_t reply = emptyReply(q, classes_);
  auto fail = [&](const std::string& why) {
    reply.error = why;
    return reply;
  };
  if (q.kind != object_query_t::KIND_ALL && q.kind != object_query_t::KIND_BY_LABEL &&
      q.kind != object_query_t::KIND_BY_REGION)
    return fail("unknown query kind " + std::to_string(q.kind) +
                " (0: all, 1: by label, 2: by region)");
  if (q.map_id != -1 && !segments_.count(q.map_id)) {
    std::string ids;
    for (const auto& [id, seg] : segments_) ids += (ids.empty() ? "" : ", ") + std::to_string(id);
    return fail("no map segment " + std::to_string(q.map_id) +
                " (segments: " + (ids.empty() ? "none" : ids) + ")");
  }
  int label = -1;
  if (q.kind == object_query_t::KIND_BY_LABEL) {
    auto it = std::find(classes_.begin(), classes_.end(), q.label);
    if (it == classes_.end()) {
      std::string names;
      for (const auto& c : classes_) names += (names.empty() ? "" : ", ") + c;
      return fail("unknown label '" + q.label +
                  "' (classes: " + (names.empty() ? "none yet" : names) + ")");
    }
    label = static_cast<int>(it - classes_.begin());
  }
  if (q.kind == object_query_t::KIND_BY_REGION) {
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(q.region_min[i]) || !std::isfinite(q.region_max[i]) ||
          q.region_min[i] > q.region_max[i])
        return fail("bad region: every region_min must be finite and <= region_max");
  }
  std::map<int32_t, object_t> by_id;
  for (const auto& [sid, seg] : segments_) {
    if (q.map_id != -1 && sid != q.map_id) continue;
    for (const auto& [oid, o] : seg->table.objects()) {
      if (q.kind == object_query_t::KIND_BY_LABEL && o.label != label) continue;
      if (q.kind == object_query_t::KIND_BY_REGION) {
        if (!o.has_position) continue;
        bool overlaps = true;
        for (int i = 0; i < 3; ++i)
          overlaps = overlaps && o.centroid[i] - 0.5 * o.extent[i] <= q.region_max[i] &&
                     o.centroid[i] + 0.5 * o.extent[i] >= q.region_min[i];
        if (!overlaps) continue;
      }
      by_id.emplace(oid, objectMessage(o, sid, classes_, options_.fusion().views_exponent));
    }
  }
  for (auto& [id, o] : by_id) reply.objects.push_back(std::move(o));
  reply.num_objects = static_cast<int32_t>(reply.objects.size());
  return reply;
}

object_query_reply_t ObjectMapEngine::label(const object_query_t& q) {
  object_query_reply_t reply = emptyReply(q, classes_);
  const bool unlabel = q.kind == object_query_t::KIND_UNLABEL;
  if (!unlabel && q.kind != object_query_t::KIND_LABEL) {
    reply.error = "not a labelling request (kind " + std::to_string(q.kind) + ")";
    return reply;
  }
  if (!unlabel && !validUserLabel(q.label)) {
    reply.error = "bad class name '" + q.label + "': 1 to 64 letters, digits, _ or -";
    return reply;
  }
  regroup();
  for (auto& [sid, seg] : segments_) {
    if (!seg->table.setUserLabel(q.object_id, unlabel ? std::string() : q.label)) continue;
    ++changes_;
    reply.objects.push_back(objectMessage(seg->table.objects().at(q.object_id), sid, classes_,
                                          options_.fusion().views_exponent));
    reply.num_objects = 1;
    return reply;
  }
  reply.error = "no object " + std::to_string(q.object_id) + " in the map (" +
                std::to_string(numObjects()) + " objects; slamaware-ctl query lists them)";
  return reply;
}

MapSnapshot ObjectMapEngine::snapshot() const {
  MapSnapshot snap;
  json& c = snap.content;
  c["classes"] = classes_;
  json colours = json::object();
  for (const auto& name : classes_) {
    const Rgb rgb = labelColour(name);
    colours[name] = {rgb.r, rgb.g, rgb.b};
  }
  colours["(unassigned)"] = {kUnassignedColour.r, kUnassignedColour.g, kUnassignedColour.b};
  c["colours"] = colours;
  c["next_object_id"] = next_object_id_;
  c["sessions"] = sessions_;
  json maps = json::array();
  for (const auto& [slam, seg] : session_maps_) maps.push_back({slam, seg});
  c["session"] = {
      {"last_pose_utime", last_pose_utime_}, {"last_pose_seq", last_pose_seq_}, {"maps", maps}};
  c["last_frame"] = {{"utime", last_utime_}, {"seq", last_seq_}};
  c["current_segment"] = current_segment_;
  c["segments"] = json::array();
  c["objects"] = json::array();
  for (auto& [sid, seg] : segments_) {
    // Colours of the .ot: each object's voxels in its label's colour (the lower id wins a voxel
    // two objects share), other occupied voxels grey.
    std::unordered_map<VoxelKey, Rgb> colour_of;
    for (const auto& [oid, o] : seg->table.objects()) {
      const Rgb rgb =
          o.label >= 0 ? labelColour(classes_[static_cast<size_t>(o.label)]) : kUnassignedColour;
      for (int32_t cid : o.candidates)
        for (VoxelKey k : seg->table.candidates().at(cid).voxels) colour_of.emplace(k, rgb);
    }
    snap.segment_files[sid] = seg->occupancy.serialize([&](VoxelKey k) {
      auto it = colour_of.find(k);
      return it == colour_of.end() ? kUnassignedColour : it->second;
    });
    c["segments"].push_back({{"id", sid},
                             {"slam_map_id", seg->slam_map_id},
                             {"resolution", seg->occupancy.resolution()},
                             {"occupied_voxels", seg->occupancy.occupied().size()}});
    for (const auto& [oid, o] : seg->table.objects()) {
      json jo;
      jo["id"] = oid;
      jo["segment"] = sid;
      // Summary for readers of the file; recomputed on load.
      jo["label"] = o.label >= 0 ? classes_[static_cast<size_t>(o.label)] : "";
      jo["num_views"] = o.num_views;
      jo["num_voxels"] = o.num_voxels;
      if (!o.user_label.empty()) jo["user_label"] = o.user_label;
      if (o.has_position) {
        jo["centroid"] = vec3(o.centroid);
        jo["extent"] = vec3(o.extent);
      }
      jo["candidates"] = json::array();
      for (int32_t cid : o.candidates) {
        const Candidate& cand = seg->table.candidates().at(cid);
        json jc;
        jc["id"] = cid;
        jc["voting_views"] = cand.voting_views;
        json flat = json::array();  // kx, ky, kz, votes per voxel
        for (const auto& [k, n] : cand.votes) {
          for (int a = 0; a < 3; ++a) flat.push_back(voxelKeyAxis(k, a));
          flat.push_back(n);
        }
        jc["votes"] = std::move(flat);
        jc["box_position_sum"] = vec3(cand.box_position_sum);
        jc["box_positions"] = cand.box_positions;
        jc["box_size"] = cand.box_size;
        if (!cand.user_label.empty()) jc["user_label"] = cand.user_label;
        // utime, seq, area, log p per class, then for a merged view the frames it stands for
        // and their objectness (a view kept from before merging: only its frames, if more than
        // one).
        json views = json::array();
        for (const auto& [key, v] : cand.views) {
          json jv = {v.utime, v.seq, compactFloat(v.area)};
          for (float lp : v.log_prob) jv.push_back(compactFloat(lp));
          if (v.frames > 1 || v.objectness >= 0) jv.push_back(v.frames);
          if (v.objectness >= 0) jv.push_back(compactFloat(v.objectness));
          views.push_back(std::move(jv));
        }
        jc["views"] = std::move(views);
        jo["candidates"].push_back(std::move(jc));
      }
      c["objects"].push_back(std::move(jo));
    }
  }
  return snap;
}

void ObjectMapEngine::restore(const MapSnapshot& snap) {
  ObjectMapEngine fresh(options_);
  const json& c = snap.content;
  std::string where = "object table";
  try {
    where = "classes";
    fresh.classes_ = c.at("classes").get<std::vector<std::string>>();
    std::set<std::string> unique(fresh.classes_.begin(), fresh.classes_.end());
    if (unique.size() != fresh.classes_.size() || unique.count(""))
      throw std::runtime_error("empty or repeated class names");
    const size_t nc = fresh.classes_.size();
    where = "header fields";
    fresh.next_object_id_ = jsonInt<int32_t>(c.at("next_object_id"));
    fresh.sessions_ = jsonInt<int64_t>(c.at("sessions"));
    fresh.last_pose_utime_ = jsonInt<int64_t>(c.at("session").at("last_pose_utime"));
    fresh.last_pose_seq_ = jsonInt<int32_t>(c.at("session").at("last_pose_seq"));
    fresh.last_utime_ = jsonInt<int64_t>(c.at("last_frame").at("utime"));
    fresh.last_seq_ = jsonInt<int32_t>(c.at("last_frame").at("seq"));
    fresh.current_segment_ = jsonInt<int32_t>(c.at("current_segment"));
    for (const auto& s : c.at("segments")) {
      const int32_t id = jsonInt<int32_t>(s.at("id"));
      where = "segment " + std::to_string(id);
      auto bytes = snap.segment_files.find(id);
      if (bytes == snap.segment_files.end()) throw std::runtime_error("no .ot file");
      if (fresh.segments_.count(id)) throw std::runtime_error("listed twice");
      OccupancyMap map =
          OccupancyMap::deserialize(bytes->second, options_.occupancy, "its .ot file");
      fresh.segments_.emplace(
          id, std::make_unique<Segment>(id, jsonInt<int32_t>(s.at("slam_map_id")), std::move(map),
                                        options_.views_full_rate_s));
    }
    where = "session maps";
    for (const auto& m : c.at("session").at("maps")) {
      const int32_t seg = jsonInt<int32_t>(m.at(1));
      if (!fresh.segments_.count(seg))
        throw std::runtime_error("unknown segment " + std::to_string(seg));
      fresh.session_maps_[jsonInt<int32_t>(m.at(0))] = seg;
    }
    std::set<int32_t> object_ids;
    for (const auto& jo : c.at("objects")) {
      const int32_t oid = jsonInt<int32_t>(jo.at("id"));
      where = "object " + std::to_string(oid);
      if (!object_ids.insert(oid).second) throw std::runtime_error("listed twice");
      if (oid >= fresh.next_object_id_) throw std::runtime_error("id not below next_object_id");
      auto seg = fresh.segments_.find(jsonInt<int32_t>(jo.at("segment")));
      if (seg == fresh.segments_.end()) throw std::runtime_error("unknown segment");
      ObjectTable& table = seg->second->table;
      std::vector<int32_t> cids;
      for (const auto& jc : jo.at("candidates")) {
        const int32_t cid = jsonInt<int32_t>(jc.at("id"));
        where = "object " + std::to_string(oid) + " candidate " + std::to_string(cid);
        if (table.findCandidate(cid)) throw std::runtime_error("listed twice");
        Candidate& cand = table.restoreCandidate(cid);
        cand.id = cid;
        cand.voting_views = jsonInt<int32_t>(jc.at("voting_views"));
        const auto flat = jsonInts<int64_t>(jc.at("votes"));
        if (flat.size() % 4) throw std::runtime_error("votes are not groups of 4");
        for (size_t i = 0; i < flat.size(); i += 4) {
          for (size_t a = 0; a < 3; ++a)
            if (flat[i + a] < 0 || flat[i + a] > 0xffff)
              throw std::runtime_error("voxel key out of range");
          cand.votes.emplace_back(
              packVoxelKey(static_cast<uint32_t>(flat[i]), static_cast<uint32_t>(flat[i + 1]),
                           static_cast<uint32_t>(flat[i + 2])),
              static_cast<int32_t>(flat[i + 3]));
        }
        std::sort(cand.votes.begin(), cand.votes.end());
        if (std::adjacent_find(cand.votes.begin(), cand.votes.end(),
                               [](const auto& a, const auto& b) { return a.first == b.first; }) !=
            cand.votes.end())
          throw std::runtime_error("a voxel's votes listed twice");
        cand.box_position_sum = vec3From(jc.at("box_position_sum"));
        cand.box_positions = jsonInt<int32_t>(jc.at("box_positions"));
        cand.box_size = jsonFloat<double>(jc.at("box_size"));
        cand.user_label = jc.value("user_label", std::string());
        if (!cand.user_label.empty() && !validUserLabel(cand.user_label))
          throw std::runtime_error("bad user_label '" + cand.user_label + "'");
        for (const auto& jv : jc.at("views")) {
          if (!jv.is_array() || jv.size() < 3 + nc || jv.size() > 5 + nc)
            throw std::runtime_error("a view is not 3 + classes (+ 1 or 2) numbers");
          View v;
          v.utime = jsonInt<int64_t>(jv[0]);
          v.seq = jsonInt<int32_t>(jv[1]);
          v.area = jsonFloat<float>(jv[2]);
          for (size_t k = 0; k < nc; ++k) v.log_prob.push_back(jsonFloat<float>(jv[3 + k]));
          if (jv.size() >= 4 + nc) {
            v.frames = jsonInt<int32_t>(jv[3 + nc]);
            if (v.frames < 1) throw std::runtime_error("a view stands for fewer than 1 frame");
          }
          if (jv.size() == 5 + nc) {
            v.objectness = jsonFloat<float>(jv[4 + nc]);
            if (!(v.objectness >= 0 && v.objectness <= 1))
              throw std::runtime_error("a merged view's objectness is not in [0, 1]");
          }
          const ViewKey key{v.utime, v.seq};
          cand.views[key] = std::move(v);
        }
        cids.push_back(cid);
      }
      table.restoreObject(oid, std::move(cids));
    }
  } catch (const json::exception& e) {
    throw std::runtime_error(where + ": " + e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(where + ": " + e.what());
  }
  fresh.camera_ = camera_;
  fresh.have_camera_ = have_camera_;
  fresh.regroup();
  fresh.changes_ = 0;
  fresh.defer_regrouping_ = defer_regrouping_;
  *this = std::move(fresh);
}

void LockstepInputs::add(int32_t seq, Input input, const Handler& handle) {
  if (std::holds_alternative<pose_t>(input)) {
    poses_.push_back(seq);
    if (poses_.size() > kMaxWaiting) poses_.pop_front();
  } else if (std::holds_alternative<proposals_t>(input)) {
    if (newest_proposals_ && seq < *newest_proposals_) {
      for (const int32_t p : poses_)
        if (p > *newest_proposals_) {
          released_by_[seq] = p;
          break;
        }
      while (released_by_.size() > kMaxWaiting) released_by_.erase(released_by_.begin());
    } else {
      newest_proposals_ = seq;
    }
  }
  waiting_.emplace_back(seq, std::move(input));
  while (waiting_.size() > kMaxWaiting) {
    handle(waiting_.front().second);
    waiting_.pop_front();
  }
}

void LockstepInputs::releaseUpTo(int32_t seq, const Handler& handle) {
  int32_t upto = seq;
  if (const auto it = released_by_.find(seq); it != released_by_.end()) {
    upto = std::max(upto, it->second);
    released_by_.erase(it);
  }
  std::deque<std::pair<int32_t, Input>> later;
  for (auto& [s, input] : waiting_) {
    if (s <= upto)
      handle(input);
    else
      later.emplace_back(s, std::move(input));
  }
  waiting_ = std::move(later);
}

}  // namespace slamaware::objectmap
