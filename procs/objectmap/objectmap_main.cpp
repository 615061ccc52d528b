// slamaware-objectmap: the object map server. Reads SLAM_MAP (occupancy), CAMERA_INFO, SLAM_POSE,
// PROPOSALS and DETECTIONS (joined on seq: per-object evidence fusion) and OBJECT_QUERY; publishes
// OBJECT_DETECTIONS (each DETECTIONS message's boxes with their objects' fused labels, always one
// per DETECTIONS), OBJECT_MAP and OBJECT_QUERY_REPLY; saves the map (OctoMap .ot + JSON object
// table) every save_period_s and at shutdown, and loads it at start (procs/objectmap/README.md).
//
// Lockstep: exactly one OBJECT_MAP per DETECTIONS message, whose content depends only on the
// inputs (no wall-clock or save information). SLAM_MAP, SLAM_POSE and PROPOSALS wait until a
// DETECTIONS message of their seq or a later one comes, so that with several frames in the
// pipeline (bus.lockstep_window) a later frame's map is never fused into an earlier frame's
// detections: the order of the work is that of the frames, whatever the order of arrival. Real
// time: the objects are regrouped at most every regroup_period_s (and before a query's answer and
// the last save), and OBJECT_MAP goes out whenever they were and every publish_period_s. Bad input
// is counted in OBJECTMAP_STATUS and never stops the process; a damaged map file is refused with a
// message naming it, and the previous good generation is used.
#include <malloc.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

#include "common/atomic_file.h"
#include "common/bus/bus.h"
#include "common/bus/busy_heartbeat.h"
#include "common/bus/node.h"
#include "common/bus/shutdown.h"
#include "common/bus/status.h"
#include "common/config.h"
#include "common/thread_priority.h"
#include "procs/objectmap/map_store.h"
#include "procs/objectmap/object_map.h"
#include "procs/objectmap/objectmap_options.h"

using namespace slamaware;
using namespace slamaware::objectmap;
using Clock = std::chrono::steady_clock;

namespace {

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

/// The newest generation of `store` that passes the file checks and restores into an engine
/// (refused generations are logged and listed in the report); nullopt when none does.
struct LoadedMap {
  LoadReport report;
  std::optional<ObjectMapEngine> engine;
  MapSnapshot snapshot;
};
LoadedMap loadNewestMap(MapStore& store, const ObjectMapOptions& options) {
  LoadedMap l;
  l.report = store.load([&](const MapSnapshot& s) {
    ObjectMapEngine e(options);
    e.restore(s);  // throws on inconsistent content: the generation is refused
    l.engine = std::move(e);
    l.snapshot = s;
  });
  for (const auto& f : l.report.failures) spdlog::error("refused {}", f);
  return l;
}

/// s a heartbeat goes on during one long piece of work (load, insertion, regrouping, save) before
/// it stops and the supervisor may take the process for hung.
constexpr double kBusyLimitS = 120;

class ObjectMapNode {
 public:
  ObjectMapNode(Bus& bus, StatusReporter& status, const SystemConfig& sys,
                const ObjectMapOptions& options)
      : bus_(bus),
        status_(status),
        ch_(sys.channels),
        lockstep_(sys.bus.lockstep),
        options_(options),
        engine_(options),
        store_(options.persistence.dir) {
    deferRegrouping();
    const size_t max_msg = static_cast<size_t>(sys.bus.max_message_bytes);
    bus_.subscribe<camera_info_t>(
        ch_.camera_info,
        [this](const camera_info_t& m) {
          std::string why;
          if (!engine_.onCameraInfo(m, &why)) bus_.reject(ch_.camera_info, why);
        },
        max_msg);
    bus_.subscribe<point_cloud_t>(
        ch_.slam_map, [this](const point_cloud_t& m) { frameInput(m.seq, m); },
        static_cast<size_t>(sys.bus.max_map_bytes));
    bus_.subscribe<pose_t>(
        ch_.slam_pose, [this](const pose_t& m) { frameInput(m.seq, m); }, max_msg);
    bus_.subscribe<proposals_t>(
        ch_.proposals, [this](const proposals_t& m) { frameInput(m.seq, m); }, max_msg);
    bus_.subscribe<detections_t>(
        ch_.detections, [this](const detections_t& m) { onDetections(m); }, max_msg);
    bus_.subscribe<object_query_t>(
        ch_.object_query, [this](const object_query_t& m) { onQuery(m); }, max_msg);
  }

  /// Takes the folder, removes what interrupted saves left, and loads the newest good map.
  void start(bool load) {
    std::string why;
    can_save_ = store_.lock(&why);
    status_.setState(StatusReporter::State::kRunning);
    if (!can_save_) {
      spdlog::error("{}: the map will not be saved", why);
      status_.setMessage(why + ": not saving");
      status_.setState(StatusReporter::State::kDegraded);
    } else if (const size_t n = store_.removeTemporaryFiles()) {
      spdlog::info("{}: removed {} temporary file(s) of an interrupted save", store_.dir(), n);
    }
    if (!load) {
      spdlog::info("starting from an empty map; saving into {}", store_.dir());
      return;
    }
    const auto t0 = Clock::now();
    LoadedMap loaded;
    {
      BusyHeartbeat busy(status_, kBusyLimitS);  // a large map takes seconds to load
      loaded = loadNewestMap(store_, options_);
    }
    const LoadReport& report = loaded.report;
    if (!report.failures.empty()) {
      status_.count("load_failures", static_cast<int64_t>(report.failures.size()));
      status_.setMessage("refused " + report.failures.front());
    }
    if (report.generation < 0) {
      spdlog::info("no usable map in {}: starting from an empty map", store_.dir());
      return;
    }
    engine_ = std::move(*loaded.engine);
    deferRegrouping();
    saved_changes_ = engine_.changes();
    status_.setCounter("loaded_generation", report.generation);
    status_.setCounter("load_ms", static_cast<int64_t>(secondsSince(t0) * 1000));
    spdlog::info("loaded {} in {:.0f} ms: {} objects in {} segment(s), {} occupied voxels{}",
                 report.json_path, secondsSince(t0) * 1000, engine_.numObjects(),
                 engine_.segments().size(), engine_.numOccupiedVoxels(),
                 report.failures.empty() ? "" : " (newer generations were refused, see above)");
  }

  /// Periodic work: regrouping and OBJECT_MAP (real time), saving, counters.
  void tick() {
    if (secondsSince(last_regroup_) >= options_.regroup_period_s) regroup();
    if (!lockstep_ && (engine_.regroupings() != published_regroupings_ ||
                       secondsSince(last_publish_) >= options_.publish_period_s))
      publishMap();
    if (options_.persistence.save_period_s > 0 &&
        secondsSince(last_save_) >= options_.persistence.save_period_s &&
        engine_.changes() != saved_changes_)
      save("periodic");
    if (secondsSince(last_counters_) >= 1.0) updateCounters();
  }

  /// Saves what changed since the last save (at shutdown).
  void finish() {
    regroup();
    if (engine_.changes() != saved_changes_) save("shutdown");
    updateCounters();
  }

 private:
  /// A SLAM_MAP, SLAM_POSE or PROPOSALS message: handled at once in real time; in lockstep just
  /// before a DETECTIONS message of its frame or a later one (LockstepInputs).
  template <class Msg>
  void frameInput(int32_t seq, const Msg& m) {
    if (lockstep_)
      lockstep_inputs_.add(seq, m, handle_input_);
    else
      handle(m);
  }

  void handle(const pose_t& m) {
    std::string why;
    if (!engine_.onPose(m, &why)) bus_.reject(ch_.slam_pose, why);
  }

  void handle(const proposals_t& m) {
    std::string why;
    if (!engine_.onProposals(m, &why)) bus_.reject(ch_.proposals, why);
  }

  void handle(const point_cloud_t& m) {
    std::string why;
    CloudReport r;
    bool inserted;
    {
      BusyHeartbeat busy(status_, kBusyLimitS);  // a full cloud of a large map takes seconds
      inserted = engine_.onMap(m, &why, &r);
    }
    if (!inserted) {
      bus_.reject(ch_.slam_map, why);
      return;
    }
    status_.count("clouds");
    if (r.full) status_.count("clouds_full");
    status_.count("cloud_points", static_cast<int64_t>(r.insert.points));
    status_.setCounter("map_insert_ms", static_cast<int64_t>(r.ms));
    spdlog::debug(
        "{} cloud of seq {} (map {} -> segment {}): {} points ({} dropped, {} inserted before; "
        "keyframes {} unchanged, {} replaced, {} removed) in {:.0f} ms",
        r.full ? "full" : "incremental", m.seq, m.map_id, r.segment, r.insert.points,
        r.insert.dropped, r.repeated, r.keyframes_unchanged, r.keyframes_changed,
        r.keyframes_removed, r.ms);
  }

  void onDetections(const detections_t& m) {
    lockstep_inputs_.releaseUpTo(m.seq, handle_input_);
    status_.noteInput(m.utime, m.seq);
    std::string why;
    FrameReport r;
    if (!engine_.onDetections(m, &why, &r)) {
      bus_.reject(ch_.detections, why);
    } else {
      status_.addProcessed();
      status_.count("boxes_fused", r.boxes);
      status_.count("boxes_voted", r.boxes_voted);
      if (r.boxes_rejected) status_.count("boxes_rejected", r.boxes_rejected);
      if (r.boxes > 0 && !r.localised) {
        status_.count("frames_without_geometry");
        spdlog::debug("seq {}: boxes fused without geometry: {}", m.seq, r.no_geometry);
      }
    }
    // Every DETECTIONS gets its OBJECT_DETECTIONS (the boxes with their fused labels), before the
    // lockstep OBJECT_MAP that the source waits for: one answer each, whatever it held.
    bus_.publish(ch_.object_detections, engine_.frameDetections(m));
    if (lockstep_) publishMap(m.utime, m.seq);
  }

  void onQuery(const object_query_t& q) {
    regroup();  // the answer holds everything fused so far
    const bool labelling =
        q.kind == object_query_t::KIND_LABEL || q.kind == object_query_t::KIND_UNLABEL;
    object_query_reply_t reply = labelling ? engine_.label(q) : engine_.answer(q);
    if (labelling && reply.error.empty()) {
      // A user's label is saved before the reply: once answered, it survives a SIGKILL.
      save("label");
      if (!can_save_ || save_failed_)
        reply.error = std::string("object ") + std::to_string(q.object_id) +
                      " labelled in memory but not saved: " +
                      (can_save_ ? "the save failed (see the status message)"
                                 : "this object map has no map folder");
      else
        spdlog::info(
            "object {} {}", q.object_id,
            q.kind == object_query_t::KIND_LABEL ? "labelled '" + q.label + "'" : "unlabelled");
    }
    reply.utime = wallUtime();
    status_.count("queries");
    if (!reply.error.empty()) {
      status_.count("query_errors");
      spdlog::info("query {}: {}", q.request_id, reply.error);
    }
    bus_.publish(ch_.object_query_reply, reply);
  }

  void publishMap(std::optional<int64_t> utime = std::nullopt,
                  std::optional<int32_t> seq = std::nullopt) {
    object_map_t m = engine_.objectMap();
    if (utime) m.utime = *utime;
    if (seq) m.seq = *seq;
    // Lockstep outputs carry nothing that depends on the wall clock or on when saves happened, so
    // that a log replayed twice gives the same bytes.
    if (!lockstep_) {
      m.saved_map_path = saved_path_;
      m.saved_utime = saved_utime_;
    }
    bus_.publish(ch_.object_map, m);
    published_regroupings_ = engine_.regroupings();
    last_publish_ = Clock::now();
  }

  /// Real time, deferred: regroups what the inputs since the last regrouping changed.
  void deferRegrouping() {
    deferred_ = !lockstep_ && options_.regroup_period_s > 0;
    engine_.deferRegrouping(deferred_);
  }
  void regroup() {
    if (!deferred_ || !engine_.regroupPending()) return;
    const auto t0 = Clock::now();
    {
      BusyHeartbeat busy(status_, kBusyLimitS);
      engine_.regroup();
    }
    last_regroup_ = Clock::now();
    status_.setCounter("regroup_ms", static_cast<int64_t>(secondsSince(t0) * 1000));
  }

  void save(const char* why) {
    last_save_ = Clock::now();
    if (!can_save_) return;
    const int64_t changes = engine_.changes();
    try {
      const auto t0 = Clock::now();
      BusyHeartbeat busy(status_, kBusyLimitS);
      const SaveReport r = store_.save(engine_.snapshot());
      const double ms = secondsSince(t0) * 1000;
      saved_changes_ = changes;
      auto seg = r.segment_paths.find(engine_.currentSegment());
      saved_path_ = seg != r.segment_paths.end() ? seg->second
                    : r.segment_paths.empty()    ? r.json_path
                                                 : r.segment_paths.rbegin()->second;
      saved_utime_ = wallUtime();
      status_.count("saves");
      status_.setCounter("save_ms", static_cast<int64_t>(ms));
      status_.setCounter("save_bytes", static_cast<int64_t>(r.bytes_written));
      status_.setCounter("generation", r.generation);
      spdlog::debug("{} save: {} ({} bytes written, {} old files removed) in {:.0f} ms", why,
                    r.json_path, r.bytes_written, r.files_removed, ms);
      if (save_failed_) {
        save_failed_ = false;
        status_.setMessage("");
        status_.setState(StatusReporter::State::kRunning);
      }
    } catch (const std::exception& e) {
      status_.count("save_failures");
      status_.setMessage(std::string("save failed: ") + e.what());
      status_.setState(StatusReporter::State::kDegraded);
      save_failed_ = true;
      spdlog::error("{} save failed (the previous generation stays): {}", why, e.what());
    }
    // A save builds the table's JSON tree and text, more than the table's own memory, and frees
    // them. glibc keeps freed pages mapped; handing them back keeps a long session's RSS at
    // the table's size instead of the largest save's peak.
    malloc_trim(0);
  }

  void updateCounters() {
    last_counters_ = Clock::now();
    status_.setCounter("objects", static_cast<int64_t>(engine_.numObjects()));
    status_.setCounter("regroupings", engine_.regroupings());
    status_.setCounter("segments", static_cast<int64_t>(engine_.segments().size()));
    status_.setCounter("candidates", static_cast<int64_t>(engine_.numCandidates()));
    status_.setCounter("views", static_cast<int64_t>(engine_.numViews()));
    status_.setCounter("voxels", static_cast<int64_t>(engine_.numOccupiedVoxels()));
    status_.setCounter("sessions", engine_.sessions());
    status_.setCounter("classes", static_cast<int64_t>(engine_.classes().size()));
  }

  Bus& bus_;
  StatusReporter& status_;
  Channels ch_;
  bool lockstep_;
  ObjectMapOptions options_;
  ObjectMapEngine engine_;
  MapStore store_;
  bool deferred_ = false;           ///< regrouping deferred to regroup() (real time)
  LockstepInputs lockstep_inputs_;  ///< lockstep: inputs of frames ahead of their DETECTIONS
  /// Hands an input LockstepInputs releases to handle() (made once, not per message).
  const LockstepInputs::Handler handle_input_ = [this](const LockstepInputs::Input& in) {
    std::visit([this](const auto& m) { handle(m); }, in);
  };
  bool can_save_ = false;
  bool save_failed_ = false;
  int64_t published_regroupings_ = -1;
  int64_t saved_changes_ = 0;
  std::string saved_path_;
  int64_t saved_utime_ = 0;
  Clock::time_point last_publish_{}, last_save_ = Clock::now(), last_counters_{}, last_regroup_{};
};

/// --export: the newest good generation of `dir` as `out`/map.ot (the segment with the most
/// labelled objects; octovis opens it) and `out`/objects.json (the object table as OBJECT_MAP
/// gives it). No bus.
int exportMap(const ObjectMapOptions& options, const std::string& dir, const std::string& out) {
  MapStore store(dir);
  LoadedMap loaded = loadNewestMap(store, options);
  const LoadReport& report = loaded.report;
  const std::optional<ObjectMapEngine>& engine = loaded.engine;
  const std::map<int32_t, std::string>& segment_files = loaded.snapshot.segment_files;
  if (!engine) {
    spdlog::error("{}: no usable map to export", dir);
    return 1;
  }
  const object_map_t map = engine->objectMap();
  std::map<int32_t, int> labelled;
  for (const auto& [sid, bytes] : segment_files) labelled[sid] = 0;
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& o : map.objects) {
    if (o.label != "background") ++labelled[o.map_id];
    nlohmann::json posterior;
    for (size_t c = 0; c < map.class_names.size(); ++c)
      posterior[map.class_names[c]] = o.posterior[c];
    nlohmann::json jo = {{"id", o.id},
                         {"segment", o.map_id},
                         {"label", o.label},
                         {"posterior", posterior},
                         {"num_views", o.num_views},
                         {"num_voxels", o.num_voxels}};
    if (!o.user_label.empty()) jo["user_label"] = o.user_label;
    if (std::isfinite(o.centroid[0])) {
      jo["centroid"] = {o.centroid[0], o.centroid[1], o.centroid[2]};
      jo["extent"] = {o.extent[0], o.extent[1], o.extent[2]};
    }
    objects.push_back(jo);
  }
  if (labelled.empty()) {
    spdlog::error("{}: the map has no segment to export", report.json_path);
    return 1;
  }
  const auto best =
      std::max_element(labelled.begin(), labelled.end(),
                       [](const auto& a, const auto& b) { return a.second < b.second; });
  const std::string& ot = segment_files.at(best->first);
  std::filesystem::create_directories(out);
  writeFileAtomic(out + "/map.ot", ot.data(), ot.size());
  const nlohmann::json table = {{"source", report.json_path},
                                {"segment_in_map_ot", best->first},
                                {"classes", map.class_names},
                                {"objects", objects}};
  const std::string text = table.dump(2) + "\n";
  writeFileAtomic(out + "/objects.json", text.data(), text.size());
  spdlog::info(
      "exported {}: {}/map.ot (segment {}, {} labelled objects), {}/objects.json ({} objects)",
      report.json_path, out, best->first, best->second, out, objects.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-objectmap: OctoMap occupancy + per-object evidence fusion (SLAM_MAP, SLAM_POSE, "
      "PROPOSALS, "
      "DETECTIONS -> OBJECT_MAP; OBJECT_QUERY -> OBJECT_QUERY_REPLY); saves and reloads the map"};
  NodeArgs node;
  addNodeOptions(app, node);
  std::string map_dir;
  std::string export_dir;
  bool fresh = false;
  app.add_option("--map-dir", map_dir,
                 "folder of the map files (overrides objectmap.persistence.dir)");
  app.add_flag(
      "--fresh", fresh,
      "start from an empty map, whatever the folder holds (its map is replaced at the first save)");
  app.add_option(
      "--export", export_dir,
      "write the newest good saved map as DIR/map.ot and DIR/objects.json, then exit (no bus)");
  addPrintConfigOption(app, [] { return defaultConfigFileText<ObjectMapOptions>("objectmap"); });
  CLI11_PARSE(app, argc, argv);

  if (!export_dir.empty()) {
    spdlog::set_level(spdlog::level::from_str(node.log_level));
    try {
      ObjectMapOptions options = loadConfig<ObjectMapOptions>(node.config, "objectmap");
      return exportMap(options, map_dir.empty() ? options.persistence.dir : map_dir, export_dir);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return 1;
    }
  }
  return runNode("objectmap", node, [&]() -> int {
    const SystemConfig sys = loadSystem(node);
    // No frame waits for the object map: all of it is background work.
    lowerThreadPriority(sys.scheduling.background_nice, "the object map");
    ObjectMapOptions options = loadConfig<ObjectMapOptions>(node.config, "objectmap");
    if (!map_dir.empty()) options.persistence.dir = map_dir;
    const std::string& load = options.persistence.load_at_start;
    if (load != "auto" && load != "always" && load != "never")
      throw ConfigError(
          (node.config.empty() ? std::string("defaults") : node.config) +
          ": key 'objectmap.persistence.load_at_start': expected auto, always or never, got '" +
          load + "'");
    const bool load_map = !fresh && (load == "always" || (load == "auto" && !sys.bus.lockstep));
    Bus bus(sys.bus.url);
    const std::string name = node.nameOr("objectmap");
    StatusReporter status(bus, name, sys.channels.statusOf(name));
    status.publish();  // starting: loading a large map may take a moment
    ObjectMapNode map(bus, status, sys, options);
    map.start(load_map);
    status.publish();
    spdlog::info("{}, {} -> {}; map folder {}",
                 sys.bus.lockstep ? "lockstep: one OBJECT_MAP per DETECTIONS" : "real time",
                 sys.channels.detections, sys.channels.object_map, options.persistence.dir);
    int lcm_failures = 0;
    int rc = 0;
    while (!shutdownRequested()) {
      if (bus.handle(20) < 0) {
        if (shutdownRequested()) break;
        if (++lcm_failures >= 50) {
          spdlog::error("LCM keeps failing; exiting");
          rc = 1;
          break;
        }
        continue;
      }
      lcm_failures = 0;
      // Drain what else is waiting before the periodic work. Each message may be a cloud that
      // takes a while to insert: a shutdown request is answered after the one in hand.
      for (int i = 0; i < 1000 && !shutdownRequested() && bus.handle(0) > 0; ++i) {
      }
      map.tick();
      status.tick();
    }
    status.setState(StatusReporter::State::kStopping);
    status.publish();
    map.finish();
    status.publish();
    return rc;
  });
}
