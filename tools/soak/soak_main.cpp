// slamaware-soak: the whole system under its supervisor for a long time, on a recording played in
// real time in a loop, watched from the bus: memory and CPU of every process (PROC_STATUS),
// frames, latency camera -> DETECTIONS, restarts. With --chaos it also attacks the system as a
// robot's life would: SIGKILL of a random pipeline process every 20-40 s, one SIGSTOP longer than
// the heartbeat timeout, and once the object map's newest save damaged while the map process is
// stopped. Writes report.json, report.md and rss.png (tools/soak/README.md).
#include <signal.h>
#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <random>
#include <regex>
#include <set>

#include "common/bus/bus.h"
#include "common/bus/frame_stamp.h"
#include "common/bus/log_reader.h"
#include "common/bus/system_config.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "slamaware/object_map_t.hpp"
#include "slamaware/proc_command_t.hpp"
#include "slamaware/proc_status_t.hpp"
#include "slamaware/status_t.hpp"
#include "tools/eval/child_process.h"
#include "tools/eval/plot.h"
#include "tools/eval/stats.h"

namespace fs = std::filesystem;
using namespace slamaware;
using json = nlohmann::json;

namespace {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Frames of one pass over the source (the camera's seq goes on counting when it loops).
int64_t framesOfSource(const std::string& source) {
  if (fs::is_directory(source)) return static_cast<int64_t>(SequenceFolder::open(source).size());
  int64_t n = 0;
  LogReader reader(source);
  while (auto r = reader.next()) n += r->channel == "CAMERA";
  return n;
}

/// The system file the soak runs: the given one with the camera looping its source and the
/// process logs in the soak's folder.
std::string writeSoakSystem(const std::string& system, const std::string& out_dir) {
  YAML::Node root = YAML::LoadFile(system);
  bool camera = false;
  for (auto p : root["processes"])
    if (p["name"].as<std::string>() == "camera") {
      p["command"].push_back("--loop");
      camera = true;
    }
  if (!camera) throw std::runtime_error(system + ": no process named camera to loop");
  root["supervisor"]["log_dir"] = out_dir + "/logs";
  const std::string path = out_dir + "/system.yaml";
  std::ofstream(path) << YAML::Dump(root) << "\n";
  return path;
}

struct Sample {
  double t;
  int64_t rss_kb;
  double cpu_pct;
  double rssMb() const { return static_cast<double>(rss_kb) / 1024.0; }
};

/// The heap a process reports in its status (common/bus/status.h): in use and kept free by glibc.
struct HeapSample {
  double t;
  int64_t used_kb, free_kb;
};

/// The names of the processes of a system.yaml.
std::vector<std::string> processNames(const std::string& system) {
  std::vector<std::string> names;
  for (auto p : YAML::LoadFile(system)["processes"]) names.push_back(p["name"].as<std::string>());
  return names;
}

struct ChaosEvent {
  std::string kind;  ///< "kill", "stop", "corrupt"
  std::string process;
  double t = 0;
  int old_pid = 0;
  double back_s = -1;  ///< until it runs again with a new pid (-1: not back)
  double limit_s = 0;  ///< the target for back_s
  std::string detail;
  /// Objects in the save it must reload, each with its candidates.
  std::map<int32_t, std::set<int32_t>> saved_objects;
  /// Of those, in its first OBJECT_MAP after the restart: merged (the id gone, its candidates in
  /// another object: id -> that object) and lost (neither the id nor any of its candidates).
  std::map<int32_t, int32_t> merged_objects;
  std::set<int32_t> lost_objects;
  bool map_checked = false;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

/// Object ids of a saved generation's JSON (the content's "objects") with their candidates' ids;
/// empty if unreadable.
std::map<int32_t, std::set<int32_t>> savedObjects(const std::string& path) {
  std::ifstream in(path);
  std::map<int32_t, std::set<int32_t>> ids;
  try {
    const json doc = json::parse(in);
    // What the map calls background it forgets once out of view (procs/objectmap/README.md), at
    // the first regrouping after a load as at any other: only objects must come back.
    const json& content = doc.at("content");
    const std::string background = content.at("classes").back().get<std::string>();
    for (const auto& o : content.at("objects"))
      if (o.value("label", std::string()) != background || o.contains("user_label")) {
        auto& candidates = ids[o.at("id").get<int32_t>()];
        for (const auto& c : o.at("candidates")) candidates.insert(c.at("id").get<int32_t>());
      }
  } catch (const std::exception&) {
  }
  return ids;
}

/// The newest objectmap-<generation>.json of a folder ("" if none).
std::string newestSave(const std::string& dir, const std::string& skip = "") {
  static const std::regex pattern(R"(objectmap-(\d+)\.json)");
  std::string best;
  long long best_g = -1;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::smatch m;
    const std::string name = e.path().filename().string();
    if (std::regex_match(name, m, pattern) && std::stoll(m[1]) > best_g &&
        e.path().string() != skip) {
      best_g = std::stoll(m[1]);
      best = e.path().string();
    }
  }
  return best;
}

// What the soak sees on the bus: the processes' rows of PROC_STATUS, frames, latency camera ->
// DETECTIONS, the newest OBJECT_MAP. Times in s since t0.
struct Watch {
  double t0 = now_s();
  std::map<std::string, proc_info_t> procs;  // latest PROC_STATUS row per process
  std::map<std::string, std::vector<Sample>> samples;
  std::map<std::string, std::vector<HeapSample>> heap;  // from each process's <NAME>_STATUS
  std::map<int32_t, double> camera_at;                  // seq -> wall time of reception
  std::vector<std::pair<double, double>> latency;       // (t, s) camera -> DETECTIONS
  int64_t camera_frames = 0, poses = 0, detections = 0, fused = 0, max_seq = -1;
  std::optional<object_map_t> last_map;
  double last_map_t = -1;

  double t() const { return now_s() - t0; }

  void subscribe(Bus& bus, const SystemConfig& sys, const std::vector<std::string>& processes) {
    const Channels& ch = sys.channels;
    for (const std::string& name : processes)
      bus.subscribe<status_t>(ch.statusOf(name), [this, name](const status_t& s) {
        HeapSample h{t(), -1, -1};
        for (size_t i = 0; i < s.counter_names.size() && i < s.counter_values.size(); ++i) {
          if (s.counter_names[i] == "heap.used_kb") h.used_kb = s.counter_values[i];
          if (s.counter_names[i] == "heap.free_kb") h.free_kb = s.counter_values[i];
        }
        auto& v = heap[name];
        if (h.used_kb >= 0 && (v.empty() || h.t - v.back().t >= 0.9)) v.push_back(h);
      });
    bus.subscribe<proc_status_t>(ch.proc_status, [this](const proc_status_t& s) {
      for (const auto& p : s.procs) {
        procs[p.name] = p;
        auto& v = samples[p.name];
        if (v.empty() || t() - v.back().t >= 0.9) v.push_back({t(), p.rss_kb, p.cpu_pct});
      }
    });
    bus.subscribeRaw(
        ch.camera,
        [this](const Bus::RawMessage& m) {
          if (auto st = peekFrameStamp(m.data, m.size)) {
            camera_at[st->seq] = now_s();
            max_seq = std::max<int64_t>(max_seq, st->seq);
            ++camera_frames;
          }
        },
        static_cast<size_t>(sys.bus.max_image_bytes));
    bus.subscribeRaw(ch.slam_pose, [this](const Bus::RawMessage&) { ++poses; });
    bus.subscribeRaw(ch.detections, [this](const Bus::RawMessage& m) {
      if (auto st = peekFrameStamp(m.data, m.size)) {
        ++detections;
        auto it = camera_at.find(st->seq);
        if (it != camera_at.end()) latency.emplace_back(t(), now_s() - it->second);
      }
    });
    bus.subscribeRaw(ch.object_detections, [this](const Bus::RawMessage&) { ++fused; });
    bus.subscribe<object_map_t>(ch.object_map, [this](const object_map_t& m) {
      last_map = m;
      last_map_t = t();
    });
  }

  /// True when `name` runs under another pid than old_pid.
  bool running(const std::string& name, int old_pid) const {
    auto it = procs.find(name);
    return it != procs.end() && it->second.state == proc_info_t::STATE_RUNNING &&
           it->second.pid != old_pid && it->second.pid > 0;
  }
  int pidOf(const std::string& name) const { return procs.count(name) ? procs.at(name).pid : 0; }
};

// The attacks of --chaos (top of this file), one at a time: each waits until its process is back.
class Chaos {
 public:
  Chaos(Bus& bus, const Channels& ch, Watch& watch, std::function<void(double)> pump, uint32_t seed,
        double duration, std::string map_dir)
      : bus_(bus),
        ch_(ch),
        watch_(watch),
        pump_(std::move(pump)),
        rng_(seed),
        map_dir_(std::move(map_dir)),
        stop_at_(duration * 0.35),
        corrupt_at_(duration * 0.65) {
    next_kill_ = 30 + std::uniform_real_distribution<double>(0, 10)(rng_);
  }

  /// Called between two pumps of the bus, at t s.
  void step(double t) {
    if (pending_)
      checkPending(t);
    else if (!stopped_once_ && t >= stop_at_)
      stopProposals(t);
    else if (!corrupted_once_ && t >= corrupt_at_)
      damageNewestSave();
    else if (t >= next_kill_)
      killOne(t);
  }

  const std::vector<ChaosEvent>& events() const { return events_; }

 private:
  void checkPending(double t) {
    ChaosEvent& e = *pending_;
    if (watch_.running(e.process, e.old_pid)) {
      e.back_s = t - e.t;
      if (e.process == "objectmap" && !e.saved_objects.empty()) checkReloaded(t, &e);
      spdlog::info("chaos: {} {} back after {:.2f} s", e.kind, e.process, e.back_s);
    } else if (t - e.t > e.limit_s + 30) {
      spdlog::warn("chaos: {} {} not back after {:.0f} s", e.kind, e.process, t - e.t);
    } else {
      return;
    }
    events_.push_back(e);
    pending_.reset();
  }

  // Its first OBJECT_MAP after the restart must hold every object of the save it loaded (its
  // heartbeat goes on while it loads: the map may come some seconds later), by its id or, if the
  // first regrouping merged it into another object, by its candidates.
  void checkReloaded(double since, ChaosEvent* e) {
    while (watch_.t() < since + 60 && !(watch_.last_map && watch_.last_map_t > since)) pump_(0.05);
    if (!(watch_.last_map && watch_.last_map_t > since)) return;
    std::set<int32_t> now_ids;
    std::map<int32_t, int32_t> object_of_candidate;
    for (const auto& o : watch_.last_map->objects) {
      now_ids.insert(o.id);
      for (int32_t c : o.candidate_ids) object_of_candidate[c] = o.id;
    }
    for (const auto& [id, candidates] : e->saved_objects) {
      if (now_ids.count(id)) continue;
      const auto into = std::find_if(candidates.begin(), candidates.end(),
                                     [&](int32_t c) { return object_of_candidate.count(c) > 0; });
      if (into != candidates.end())
        e->merged_objects[id] = object_of_candidate[*into];
      else
        e->lost_objects.insert(id);
    }
    e->map_checked = true;
  }

  void stopProposals(double t) {
    stopped_once_ = true;
    ChaosEvent e;
    e.kind = "stop", e.process = "proposals", e.t = t, e.old_pid = watch_.pidOf("proposals");
    if (e.old_pid > 0 && kill(e.old_pid, SIGSTOP) == 0) {
      e.limit_s = 10 + 2;  // heartbeat_timeout_s of config/system.yaml + 2 s
      e.detail = "SIGSTOP; the supervisor must find it hung and restart it";
      spdlog::info("chaos: SIGSTOP proposals (pid {})", e.old_pid);
      pending_ = e;
    }
  }

  void command(const std::string& target, int8_t what) {
    proc_command_t c{};
    c.utime = wallUtime();
    c.target = target;
    c.command = what;
    bus_.publish(ch_.proc_command, c);
  }

  void damageNewestSave() {
    corrupted_once_ = true;
    ChaosEvent e;
    e.kind = "corrupt", e.process = "objectmap", e.old_pid = watch_.pidOf("objectmap");
    e.limit_s = 2;
    command("objectmap", proc_command_t::COMMAND_STOP);
    const double asked = now_s();
    while (now_s() - asked < 15 && watch_.procs["objectmap"].state != proc_info_t::STATE_STOPPED)
      pump_(0.05);
    const std::string newest = newestSave(map_dir_);
    const std::string previous = newestSave(map_dir_, newest);
    if (!newest.empty()) {
      std::fstream f(newest, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(static_cast<std::streamoff>(fs::file_size(newest) / 2));
      f.put('#');
      e.saved_objects = savedObjects(previous);
      e.detail = "damaged " + fs::path(newest).filename().string() + " while stopped; must load " +
                 fs::path(previous).filename().string();
    } else {
      e.detail = "no save to damage yet";
    }
    spdlog::info("chaos: {}", e.detail);
    command("objectmap", proc_command_t::COMMAND_START);
    e.t = watch_.t();
    pending_ = e;
  }

  void killOne(double t) {
    static const std::vector<std::string> pipeline = {"slam", "proposals", "recognizer",
                                                      "objectmap"};
    const std::string name = pipeline[rng_() % pipeline.size()];
    ChaosEvent e;
    e.kind = "kill", e.process = name, e.t = t, e.old_pid = watch_.pidOf(name);
    if (name == "objectmap") e.saved_objects = savedObjects(newestSave(map_dir_));
    if (e.old_pid > 0 && kill(e.old_pid, SIGKILL) == 0) {
      e.limit_s = 2;
      spdlog::info("chaos: SIGKILL {} (pid {})", name, e.old_pid);
      pending_ = e;
    }
    next_kill_ = t + std::uniform_real_distribution<double>(20, 40)(rng_);
  }

  Bus& bus_;
  const Channels& ch_;
  Watch& watch_;
  std::function<void(double)> pump_;
  std::mt19937 rng_;
  std::string map_dir_;
  double stop_at_, corrupt_at_, next_kill_ = 0;
  bool stopped_once_ = false, corrupted_once_ = false;
  std::optional<ChaosEvent> pending_;  // waiting for its process to come back
  std::vector<ChaosEvent> events_;
};

// Per process: RSS after the first loop, at half time and at the end, heap in use, CPU, restarts.
json processFigures(const Watch& w, const std::map<std::string, proc_info_t>& final_procs,
                    double base_from, double duration) {
  json out = json::object();
  for (const auto& [name, v] : w.samples) {
    auto median_between = [&](double a, double b) {
      std::vector<double> r;
      for (const auto& s : v)
        if (s.t >= a && s.t < b) r.push_back(s.rssMb());
      return r.empty() ? 0.0 : median(r);
    };
    const double after_first = median_between(base_from, base_from + 30);
    const double at_end = median_between(duration - 30, duration + 1);
    std::vector<double> cpu;
    for (const auto& s : v)
      if (s.t >= base_from) cpu.push_back(s.cpu_pct);
    json p;
    p["rss_mb_after_first_loop"] = after_first;
    p["rss_mb_at_end"] = at_end;
    p["rss_growth_pct"] = after_first > 0 ? 100.0 * (at_end - after_first) / after_first : 0.0;
    // A leak grows in the second half as in the first; filling maps up (the first passes over a
    // looped recording) does not.
    const double at_half = median_between(duration / 2, duration / 2 + 30);
    p["rss_mb_at_half"] = at_half;
    p["rss_growth_second_half_pct"] = at_half > 0 ? 100.0 * (at_end - at_half) / at_half : 0.0;
    // What the process holds (heap in use), apart from what glibc keeps of what it freed: RSS
    // can grow with the second alone.
    if (auto h = w.heap.find(name); h != w.heap.end()) {
      auto heap_between = [&](double a, double b, bool used) {
        std::vector<double> r;
        for (const auto& s : h->second)
          if (s.t >= a && s.t < b) r.push_back(static_cast<double>(used ? s.used_kb : s.free_kb));
        return r.empty() ? 0.0 : median(r) / 1024.0;
      };
      const double first = heap_between(base_from, base_from + 30, true);
      const double end = heap_between(duration - 30, duration + 1, true);
      p["heap_used_mb_after_first_loop"] = first;
      p["heap_used_mb_at_end"] = end;
      p["heap_used_growth_pct"] = first > 0 ? 100.0 * (end - first) / first : 0.0;
      p["heap_free_mb_at_end"] = heap_between(duration - 30, duration + 1, false);
    }
    p["cpu_pct_mean"] = cpu.empty() ? 0.0
                                    : std::accumulate(cpu.begin(), cpu.end(), 0.0) /
                                          static_cast<double>(cpu.size());
    p["restarts"] = final_procs.count(name) ? final_procs.at(name).restarts : -1;
    out[name] = p;
  }
  return out;
}

// Latency p95 and median per window, and the spread of the p95 of the whole windows.
void addLatencyWindows(const Watch& w, double window, double duration, json* report) {
  std::vector<double> p95s;
  for (double a = 0; a < duration; a += window) {
    std::vector<double> l;
    for (const auto& [t, s] : w.latency)
      if (t >= a && t < a + window) l.push_back(s * 1000);
    if (l.empty()) continue;
    const double p95 = percentile(l, 0.95);
    (*report)["latency_windows"].push_back(
        {{"from_s", a}, {"frames", l.size()}, {"p95_ms", p95}, {"median_ms", percentile(l, 0.5)}});
    if (a + window <= duration + 1) p95s.push_back(p95);
  }
  const double spread = p95s.size() > 1 ? *std::max_element(p95s.begin(), p95s.end()) /
                                                  *std::min_element(p95s.begin(), p95s.end()) -
                                              1
                                        : 0;
  (*report)["latency_p95_spread_pct"] = 100 * spread;
}

json eventsJson(const std::vector<ChaosEvent>& events) {
  json out = json::array();
  for (const auto& e : events) {
    json j = {{"kind", e.kind},     {"process", e.process}, {"at_s", e.t},
              {"back_s", e.back_s}, {"limit_s", e.limit_s}, {"detail", e.detail}};
    if (!e.saved_objects.empty()) {
      j["saved_objects"] = e.saved_objects.size();
      j["map_checked"] = e.map_checked;
      j["lost_objects"] = std::vector<int32_t>(e.lost_objects.begin(), e.lost_objects.end());
      json merged = json::object();
      for (const auto& [id, into] : e.merged_objects) merged[std::to_string(id)] = into;
      j["merged_objects"] = merged;
    }
    out.push_back(j);
  }
  return out;
}

// The 1 Hz samples behind the plot, for a user's own analysis: t_s,process,rss_mb,cpu_pct.
void writeSamplesCsv(const Watch& w, const std::string& path) {
  std::ofstream out(path);
  out << "t_s,process,rss_mb,cpu_pct\n";
  for (const auto& [name, v] : w.samples)
    for (const auto& s : v)
      out << s.t << ',' << name << ',' << s.rssMb() << ',' << s.cpu_pct << '\n';
  if (!out) throw std::runtime_error(path + ": cannot write");
}

// RSS over time, one curve per process.
void plotRss(const Watch& w, double duration, const std::string& path) {
  double max_mb = 1;
  for (const auto& [name, v] : w.samples)
    for (const auto& s : v) max_mb = std::max(max_mb, s.rssMb());
  cv::Mat canvas(480, 900, CV_8UC3, cv::Scalar(255, 255, 255));
  PlotAxis x{0, duration / 60, false, {}, "minutes"},
      y{0, max_mb * 1.1, false, {}, "resident memory, MB"};
  for (double m = 0; m <= duration / 60; m += std::max(1.0, std::round(duration / 600)))
    x.ticks.push_back(m);
  for (double m = 0; m <= max_mb * 1.1; m += std::max(50.0, std::round(max_mb / 500) * 100))
    y.ticks.push_back(m);
  PlotPanel panel(canvas, cv::Rect(0, 0, 900, 480), x, y, "RSS per process (PROC_STATUS, 1 Hz)");
  const cv::Scalar colours[] = {{200, 80, 0},  {0, 140, 255},  {60, 160, 60},
                                {40, 40, 220}, {160, 60, 160}, {90, 90, 90}};
  int c = 0;
  for (const auto& [name, v] : w.samples) {
    std::vector<cv::Point2d> pts;
    for (const auto& s : v) pts.emplace_back(s.t / 60, s.rssMb());
    panel.curve(pts, colours[c++ % 6], name);
  }
  writeImage(path, canvas);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-soak: the supervised system for a long time on a looping recording (and --chaos)"};
  double minutes = 30;
  bool chaos = false;
  std::string source = "logs/sample.lcm", system = "config/system.yaml", out_dir,
              bin_dir = "build/bin";
  uint32_t seed = 1;
  double window_min = 5;
  app.add_option("--minutes", minutes, "duration")->check(CLI::PositiveNumber);
  app.add_flag("--chaos", chaos,
               "kill, stop and damage as described at the top of tools/soak/soak_main.cpp");
  app.add_option("--source", source, "recording or sequence folder, played in real time in a loop");
  app.add_option("--system", system, "system.yaml of the supervisor");
  app.add_option("--bin-dir", bin_dir, "where slamaware-supervisor is");
  app.add_option("--out-dir", out_dir,
                 "report, logs, object map (default build/soak or build/chaos)");
  app.add_option("--seed", seed, "seed of the chaos schedule");
  app.add_option("--window-min", window_min, "minutes per latency window")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  if (out_dir.empty()) out_dir = chaos ? "build/chaos" : "build/soak";
  try {
    fs::remove_all(out_dir);
    fs::create_directories(out_dir + "/logs");
    const int64_t loop_frames = framesOfSource(source);
    if (loop_frames <= 0) throw std::runtime_error(source + ": no camera frames");
    const SystemConfig sys = loadSystemConfig(system, false);
    const std::string soak_system = writeSoakSystem(system, out_dir);
    const std::string map_dir = out_dir + "/objectmap";
    setenv("SLAMAWARE_SOURCE", source.c_str(), 1);
    setenv("SLAMAWARE_MAP_DIR", map_dir.c_str(), 1);

    Bus bus(sys.bus.url);
    Watch watch;
    watch.subscribe(bus, sys, processNames(soak_system));
    auto pump = [&](double seconds) {
      const double end = now_s() + seconds;
      while (now_s() < end) bus.handle(20);
      while (watch.camera_at.size() > 2000) watch.camera_at.erase(watch.camera_at.begin());
    };

    spdlog::info("soak{}: {} min on {} ({} frames per loop), reports in {}",
                 chaos ? " with chaos" : "", minutes, source, loop_frames, out_dir);
    ChildProcess supervisor(
        {bin_dir + "/slamaware-supervisor", "--system", soak_system, "--log-level", "warn"},
        out_dir + "/supervisor.log");
    const double duration = minutes * 60;
    Chaos attacks(bus, sys.channels, watch, pump, seed, duration, map_dir);
    double first_loop_end = -1;
    while (watch.t() < duration) {
      pump(0.05);
      const double t = watch.t();
      if (first_loop_end < 0 && watch.max_seq >= loop_frames) first_loop_end = t;
      if (chaos) attacks.step(t);
    }
    // Still producing detections at the end?
    const int64_t detections_before = watch.detections;
    pump(5);
    const int64_t detections_at_end = watch.detections - detections_before;
    const std::map<std::string, proc_info_t> final_procs = watch.procs;
    supervisor.stop(std::chrono::milliseconds(20000));

    json report;
    report["minutes"] = minutes;
    report["chaos"] = chaos;
    report["source"] = source;
    report["frames_per_loop"] = loop_frames;
    report["loops"] = static_cast<double>(watch.max_seq + 1) / static_cast<double>(loop_frames);
    report["first_loop_end_s"] = first_loop_end;
    report["frames"] = {{"camera", watch.camera_frames},
                        {"slam_pose", watch.poses},
                        {"detections", watch.detections},
                        {"object_detections", watch.fused},
                        {"frames_without_pose", watch.camera_frames - watch.poses},
                        {"frames_without_detections", watch.camera_frames - watch.detections},
                        {"detections_in_last_5_s", detections_at_end}};
    report["processes"] = processFigures(
        watch, final_procs, first_loop_end > 0 ? first_loop_end : duration / 3, duration);
    addLatencyWindows(watch, window_min * 60, duration, &report);
    if (!attacks.events().empty()) report["chaos_events"] = eventsJson(attacks.events());
    std::ofstream(out_dir + "/report.json") << report.dump(2) << "\n";
    plotRss(watch, duration, out_dir + "/rss.png");
    writeSamplesCsv(watch, out_dir + "/samples.csv");
    std::printf("%s\n", report.dump(2).c_str());
    return 0;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
