// slamaware-bench-proposals (make bench): the proposals stage's two costs on a synthetic
// semi-dense map of ~100k points (a table with a dozen objects, 2 mm noise): re-clustering the
// whole map at every density scale (what a new keyframe costs) and projecting the candidates
// into a frame with occlusion culling and suppression (what every frame costs). Medians. With
// --replay, also the stage's whole lockstep work on a recording of SLAM's messages (the
// lockstep.lcm that slamaware-bench-system leaves): a real map as it grows, keyframe by keyframe.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "common/bus/system_config.h"
#include "common/config.h"
#include "procs/proposals/projector.h"
#include "procs/proposals/synthetic_map.h"
#include "tools/eval/proposal_metrics.h"

using namespace slamaware;
using namespace slamaware::proposals;
using namespace slamaware::synthmap;

namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"slamaware-bench-proposals: clustering and projection times of the proposals stage"};
  std::string out = "build/bench/parts/proposals.json", config;
  std::string replay_log;
  int repeats = 5, frames = 200;
  app.add_option("--out", out, "JSON fragment to write");
  app.add_option("--config", config,
                 "proposals options (default: built-in, as config/proposals.yaml)");
  app.add_option("--repeats", repeats, "re-clusterings timed");
  app.add_option("--frames", frames, "frames projected");
  app.add_option("--replay", replay_log,
                 "also replay the SLAM messages of this recording through the stage (lockstep)");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_pattern("[%H:%M:%S.%e] [bench-proposals] [%^%l%$] %v");
  try {
    const ProposalOptions options = loadConfig<ProposalOptions>(config, "proposals", false);
    // The map: a 1.2 m table and 12 objects, every point jittered by 2 mm.
    std::vector<MapPoint> map = table(1.2f, 0.005f);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    for (int i = 0; i < 12; ++i) {
      const float a = static_cast<float>(2 * M_PI * i / 12), rr = 0.2f + 0.25f * (i % 2);
      map = join(map, cylinder(rr * std::cos(a), rr * std::sin(a), 0.03f + 0.03f * u(rng),
                               0.06f + 0.14f * u(rng), 0.003f, static_cast<uint8_t>(40 + 15 * i)));
    }
    std::normal_distribution<float> noise(0, 0.002f);
    for (auto& p : map) p.p += Eigen::Vector3f(noise(rng), noise(rng), noise(rng));

    CandidateMap candidates(options);
    std::vector<double> cluster_ms;
    for (int r = 0; r < repeats; ++r) {
      candidates.update(1, true, 0, std::vector<int32_t>(map.size(), 0), map);
      for (int v = 0; v < 36; ++v) {  // views circling the table
        const double a = 2 * M_PI * v / 36;
        candidates.addView(1, lookAt(Eigen::Vector3d(0.8 * std::cos(a), 0.8 * std::sin(a), 0.55),
                                     Eigen::Vector3d::Zero()));
      }
      const auto t0 = std::chrono::steady_clock::now();
      candidates.recluster();
      cluster_ms.push_back(msSince(t0));
    }
    const ClusterStats& st = candidates.stats();

    const CameraModel camera(640, 480, 525, 525, 319.5, 239.5);
    std::vector<double> project_ms;
    size_t boxes = 0;
    for (int f = 0; f < frames; ++f) {
      const double a = 2 * M_PI * f / frames;
      const SE3 T = lookAt(Eigen::Vector3d(0.8 * std::cos(a), 0.8 * std::sin(a), 0.55),
                           Eigen::Vector3d::Zero());
      const auto t0 = std::chrono::steady_clock::now();
      boxes += projectCandidates(candidates.candidates(), camera, T, options).size();
      project_ms.push_back(msSince(t0));
    }
    nlohmann::json j;
    j["proposals_cluster_ms_100k"] = median(cluster_ms);
    j["proposals_cluster_points"] = static_cast<int64_t>(map.size());
    j["proposals_cluster_points_after_downsampling"] =
        st.clustered_points + st.plane_points + st.seen_through;
    j["proposals_candidates"] = st.clusters;
    j["proposals_cluster_parts_ms"] = {
        {"filter", st.filter_ms}, {"structure", st.structure_ms}, {"clustering", st.cluster_ms}};
    j["proposals_project_ms_per_frame"] = median(project_ms);
    j["proposals_boxes_per_frame_mean"] = static_cast<double>(boxes) / std::max(1, frames);
    if (!replay_log.empty()) {
      // The evaluator's re-run of the stage (tools/eval): every SLAM message of the recording,
      // clustering in step; timed with reading the recording.
      const Channels channels =
          loadSystemConfig(
              std::filesystem::exists("config/system.yaml") ? "config/system.yaml" : "", false)
              .channels;
      std::vector<double> total, recluster;
      ProposalRecording run;
      for (int k = 0; k < 3; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        run = rerunProposals(replay_log, channels, options, nullptr, 1, nullptr);
        total.push_back(msSince(t0));
        recluster.push_back(run.recluster_ms);
      }
      j["proposals_replay"] = {{"log", replay_log},
                               {"poses", static_cast<int64_t>(run.localized.size())},
                               {"reclusters", run.reclusters},
                               {"total_ms", median(total)},
                               {"recluster_ms", median(recluster)}};
      spdlog::info("replay of {}: {} poses, {} re-clusterings, {:.0f} ms ({:.0f} re-clustering)",
                   replay_log, run.localized.size(), run.reclusters, median(total),
                   median(recluster));
    }
    std::ofstream(out) << j.dump(2) << "\n";
    spdlog::info("last recluster: filter {:.0f} ms, structure {:.0f} ms, clustering {:.0f} ms",
                 st.filter_ms, st.structure_ms, st.cluster_ms);
    spdlog::info(
        "{} points ({} after downsampling): clustering at {} scales {:.1f} ms median -> {} "
        "candidates; "
        "projection {:.3f} ms per frame median, {:.1f} boxes per frame",
        map.size(), st.clustered_points + st.plane_points + st.seen_through, options.scales,
        median(cluster_ms), st.clusters, median(project_ms),
        static_cast<double>(boxes) / std::max(1, frames));
    return 0;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
