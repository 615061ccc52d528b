// slamaware-eval: runs the pipeline (the processes that exist: camera -> slam -> ...) lockstep on
// each sequence folder, records the bus, and computes the report sections of the stages from the
// recording and the ground truth (docs/architecture.md §7): the "slam", "proposals", "single_view",
// "multi_view_online" and "multi_view_final" sections of every sequence, and "overall" over the
// synthetic suite, plus plots per sequence (trajectory, recall against boxes, precision-recall per
// class). Only what the processes published is scored. Runs inside a private network namespace
// (scripts/eval). --offline runs the SLAM library in-process instead (no bus; for development);
// --from-logs scores earlier recordings, and --proposals-config / --objectmap-config re-run the
// proposals stage / the object map on them with other options.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "common/bus/log_reader.h"
#include "common/bus/system_config.h"
#include "common/config.h"
#include "common/dataset.h"
#include "procs/proposals/proposal_options.h"
#include "procs/slam/slam_options.h"
#include "tools/eval/offline_run.h"
#include "tools/eval/pipeline_run.h"
#include "tools/eval/proposal_metrics.h"
#include "tools/eval/recognition_metrics.h"
#include "tools/eval/scene_spread.h"
#include "tools/eval/slam_metrics.h"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

std::string selfDir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

// Every box of a recording with its single-view and multi-view log-probabilities, one CSV row per
// box (frame, candidate, object, role, box, then log p single, online, final per class).
void writeBoxesCsv(const RecognitionRecording& rr, const std::string& path) {
  std::ofstream f(path);
  f << "frame,map_id,candidate,object,role,x,y,w,h";
  for (const char* kind : {"single", "online", "final"})
    for (const auto& c : rr.classes) f << "," << kind << ":" << c;
  f << "\n";
  for (const auto& [frame, boxes] : rr.frames)
    for (const auto& b : boxes) {
      f << frame << "," << b.map_id << "," << b.candidate << "," << b.object << "," << b.role << ","
        << b.single.box.x << "," << b.single.box.y << "," << b.single.box.w << ","
        << b.single.box.h;
      for (const auto* lp : {&b.single.log_p, &b.online.log_p, &b.final.log_p})
        for (double v : *lp) f << "," << v;
      f << "\n";
    }
  if (!f) throw std::runtime_error("cannot write " + path);
}

// The single_view, multi_view_online and multi_view_final sections of a sequence (into `out`) and
// its precision-recall plot, from the DETECTIONS of its recording and the object map's outputs
// (recorded, or re-run with `objectmap_options` when given); no classes in the result when the
// sequence has none to evaluate.
RecognitionResult recognitionSections(const std::string& name, const SequenceFolder& seq,
                                      const std::string& log, const Channels& channels,
                                      const objectmap::ObjectMapOptions* objectmap_options,
                                      const std::string& out_dir, bool dump_boxes,
                                      nlohmann::json& out) {
  const ObjectMapOutputs outputs = objectmap_options
                                       ? rerunObjectMap(log, channels, *objectmap_options)
                                       : readObjectMapOutputs(log, channels);
  const RecognitionRecording rr = readRecognitionRecording(log, channels, outputs);
  if (rr.empty()) {
    spdlog::info("{}: no DETECTIONS in the recording: no single_view / multi_view", name);
    return {};
  }
  if (dump_boxes) {
    const fs::path d = fs::path(out_dir) / "boxes";
    fs::create_directories(d);
    writeBoxesCsv(rr, (d / (name + ".csv")).string());
  }
  out["object_map"] = rr.object_map;
  spdlog::info(
      "{}: object map: {} objects; in its main segment the largest holds {} of the {} object "
      "voxels",
      name, rr.object_map["objects"].dump(), rr.object_map["largest_object_voxels"].dump(),
      rr.object_map["main_segment_object_voxels"].dump());
  if (!seq.hasBoxes()) {
    spdlog::info("{}: no ground-truth boxes: no single_view / multi_view", name);
    return {};
  }
  RecognitionResult res = scoreRecognition(rr, seq, RecognitionEvalOptions{});
  if (res.classes.empty()) {
    spdlog::info("{}: none of the model's classes is in the sequence: no single_view / multi_view",
                 name);
    return res;
  }
  out["single_view"] = recognitionSection(res.single);
  // The recognizer's work: the published boxes classified in their own frame (the others carried
  // an earlier view's scores: procs/recognizer/view_selector.h).
  int64_t published = 0, carried = 0;
  for (const auto& [seq, boxes] : rr.frames)
    for (const auto& b : boxes) ++published, carried += b.carried;
  out["single_view"]["boxes_classified_pct"] =
      published > 0
          ? 100.0 * static_cast<double>(published - carried) / static_cast<double>(published)
          : 0.0;
  out["multi_view_online"] = recognitionSection(res.online);
  out["multi_view_final"] = recognitionSection(res.final);
  out["multi_view_final"]["hindsight"] =
      "each box's object labelled by the last OBJECT_MAP (evidence of the whole sequence, later "
      "frames included)";
  nlohmann::json roles;
  const char* names[] = {"primary", "duplicate", "part", "no_object"};
  for (const auto& [role, n] : rr.roles) roles[role >= 0 && role < 4 ? names[role] : "unknown"] = n;
  out["multi_view_online"]["boxes_by_role"] = roles;
  out["multi_view_online"]["frames_without_object_detections"] =
      rr.frames_without_object_detections;
  out["multi_view_final"]["objects"] = rr.objects;
  out["multi_view_final"]["boxes_whose_object_is_gone"] = rr.final_without_object;
  const std::string plot = (fs::path(out_dir) / "plots" / (name + "_pr.png")).string();
  drawPrCurves(res.single, res.online, res.final,
               name + ": precision-recall at IoU 0.5, every 5th frame", plot);
  out["single_view"]["plot"] = out["multi_view_online"]["plot"] = out["multi_view_final"]["plot"] =
      plot;
  auto pct = [](const nlohmann::json& v) { return v.is_number() ? v.get<double>() : NAN; };
  spdlog::info(
      "{}: mAP single view {:.1f}%, multi-view online {:.1f}%, final {:.1f}% ({} boxes, {} "
      "objects)",
      name, pct(out["single_view"]["mAP"]), pct(out["multi_view_online"]["mAP"]),
      pct(out["multi_view_final"]["mAP"]), res.single.boxes, rr.objects);
  return res;
}

// Everything the scoring of one sequence needs, from the command line and the config files.
struct EvalContext {
  SystemConfig system;
  PipelineRunOptions pipeline;
  std::string out_dir;
  bool from_logs = false, offline = false, verbose = false;
  slam::SlamOptions slam_options;               // offline
  proposals::ProposalOptions proposal_options;  // of the recorded run, or the ones to try
  bool rerun_proposals = false;  // score proposal_options' boxes, not the recorded ones
  ProposalEvalOptions peo;
  int draw_frames = 0;
  bool dump_proposals = false, dump_boxes = false;
  std::optional<objectmap::ObjectMapOptions> objectmap_options;  // re-run the object map with these
};

// The figures of the synthetic sequences, pooled.
struct SuiteTotals {
  std::vector<nlohmann::json> slam;
  std::vector<SceneFolder> scenes;
  ProposalScores proposals;
  ProposalMisses misses;
  bool any_proposals = false;
  RecognitionScores single, online, final;
  bool any_recognition = false;
};

// The proposals section of one sequence (its recording's boxes, or those of a re-run).
void proposalsOfSequence(const std::string& name, const SequenceFolder& seq, const std::string& log,
                         const EvalContext& c, nlohmann::json* report, SuiteTotals* totals) {
  const fs::path out(c.out_dir);
  ProposalMisses misses;
  const ProposalRecording rerun_pr =
      rerunProposals(log, c.system.channels, c.proposal_options, &seq, c.peo.stride, &misses);
  const ProposalRecording pr =
      c.rerun_proposals ? rerun_pr : readProposalRecording(log, c.system.channels);
  const ProposalScores sc = scoreProposals(pr, seq, c.peo);
  if (c.draw_frames > 0) {
    const fs::path d = out / "proposals" / name;
    fs::create_directories(d);
    drawProposalFrames(pr, seq, d.string(), c.peo.stride, c.draw_frames, 20);
  }
  if (c.dump_proposals) writeProposalBoxes(pr, (out / "proposal_boxes" / (name + ".csv")).string());
  nlohmann::json p = proposalSection(sc, (out / "plots" / (name + "_proposals.png")).string());
  p["misses"] = missesSection(misses);
  (*report)["sequences"][name]["proposals"] = p;
  if (isSyntheticSequence(seq)) {
    mergeScores(&totals->proposals, sc);
    mergeMisses(&totals->misses, misses);
    totals->any_proposals = true;
  }
  spdlog::info("{}: proposals recall {:.1f}% at IoU 0.5 ({:.1f}% at 0.7), {} boxes per frame", name,
               p.value("recall_iou50", 0.0), p.value("recall_iou70", 0.0),
               p.value("boxes_per_frame", 0.0));
}

// Runs the pipeline on one sequence folder (or reads its recording) and scores every stage into
// report["sequences"][name]; a synthetic sequence's figures also go to *totals. False when the run
// or the scoring failed (the section says why).
bool evaluateSequence(const std::string& dir, const EvalContext& c, nlohmann::json* report,
                      SuiteTotals* totals) {
  const std::string name = fs::path(dir).filename().string();
  const fs::path out(c.out_dir);
  nlohmann::json section;
  bool ok = true;
  try {
    const SequenceFolder seq = SequenceFolder::open(dir);
    SlamRecording run;
    const std::string log = (out / "logs" / (name + ".lcm")).string();
    bool have_proposals = c.rerun_proposals;
    if (c.from_logs) {
      run = readSlamRecording(log, c.system.channels);
      have_proposals = true;
    } else if (c.offline) {
      run = runSlamOffline(seq, c.slam_options, c.verbose);
    } else {
      spdlog::info("{}: running the pipeline, recording {}", name, log);
      PipelineRunOptions po = c.pipeline;
      po.objectmap_dir = (out / "objectmap" / name).string();
      fs::remove_all(po.objectmap_dir);
      const PipelineRun pr = runPipeline(dir, log, c.system, po);
      section["pipeline_stages"] = pr.stages;
      for (const auto& st : pr.stages) have_proposals = have_proposals || st == "proposals";
      if (!pr.ok) {
        section["pipeline_error"] = pr.error;
        spdlog::error("{}: {}", name, pr.error);
        ok = false;
      }
      run = readSlamRecording(log, c.system.channels);
    }
    SlamEvalOptions eo;
    eo.plot_path = (out / "plots" / (name + "_trajectory.png")).string();
    nlohmann::json slam = evaluateSlam(run, seq, eo);
    for (auto it = slam.begin(); it != slam.end(); ++it) section[it.key()] = it.value();
    if (isSyntheticSequence(seq)) {
      totals->slam.push_back(slam);
      totals->scenes.push_back({name, dir});
    }
    spdlog::info("{}: tracked {}%, ATE {} m ({}% of path), {} maps", name,
                 slam.value("tracked_pct", 0.0), slam.value("ate_rmse", 0.0),
                 slam.value("ate_rmse_pct_of_path", 0.0), slam.value("maps", 0));
    if (have_proposals && !c.offline && seq.hasBoxes())
      proposalsOfSequence(name, seq, log, c, report, totals);
    if (!c.offline) {
      const RecognitionResult res = recognitionSections(
          name, seq, log, c.system.channels, c.objectmap_options ? &*c.objectmap_options : nullptr,
          c.out_dir, c.dump_boxes, (*report)["sequences"][name]);
      if (!res.classes.empty() && isSyntheticSequence(seq)) {
        mergeRecognition(&totals->single, res.single);
        mergeRecognition(&totals->online, res.online);
        mergeRecognition(&totals->final, res.final);
        totals->any_recognition = true;
      }
    }
  } catch (const std::exception& e) {
    section["error"] = e.what();
    spdlog::error("{}: {}", name, e.what());
    ok = false;
  }
  (*report)["sequences"][name]["slam"] = section;
  return ok;
}

// report["overall"]: the synthetic sequences pooled, and the spread over scenes.
void addOverall(const SuiteTotals& t, const std::string& out_dir, nlohmann::json* report) {
  const fs::path plots = fs::path(out_dir) / "plots";
  nlohmann::json overall = nlohmann::json::object();
  if (!t.slam.empty()) overall["slam"] = summarizeSlam(t.slam);
  if (t.any_proposals) {
    overall["proposals"] = proposalSection(t.proposals, (plots / "suite_proposals.png").string());
    overall["proposals"]["misses"] = missesSection(t.misses);
  }
  if (t.any_recognition) {
    overall["single_view"] = recognitionSection(t.single);
    overall["multi_view_online"] = recognitionSection(t.online);
    overall["multi_view_final"] = recognitionSection(t.final);
    const std::string plot = (plots / "suite_pr.png").string();
    drawPrCurves(t.single, t.online, t.final,
                 "synthetic suite: precision-recall at IoU 0.5, every 5th frame", plot);
    overall["single_view"]["plot"] = overall["multi_view_online"]["plot"] =
        overall["multi_view_final"]["plot"] = plot;
  }
  if (t.scenes.size() >= 2) {
    nlohmann::json& spread = overall["per_scene"];
    spread = perSceneSection(*report, t.scenes, (plots / "per_scene_recall.png").string());
    for (const char* key :
         {"recall_iou50", "tracked_pct", "single_view_mAP", "multi_view_final_mAP"})
      if (spread.contains(key) && spread[key].contains("worst"))
        spdlog::info("per scene {}: median {:.1f}, worst {:.1f} ({})", key,
                     spread[key]["median"].get<double>(), spread[key]["min"].get<double>(),
                     spread[key]["worst"]["config"].get<std::string>());
  }
  if (!overall.empty()) (*report)["overall"] = overall;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "slamaware-eval: the pipeline on sequence folders, lockstep, scored against ground truth"};
  std::string out, system_path, slam_config, stages, log_level = "info";
  std::vector<std::string> sequences;
  std::string proposals_config, objectmap_config;
  EvalContext c;
  c.out_dir = "build/eval";
  PipelineRunOptions& pipeline = c.pipeline;
  pipeline.bin_dir = selfDir();
  app.add_option("sequences", sequences, "sequence folders")->required();
  app.add_option("--out", out, "JSON fragment to write")->required();
  app.add_option("--out-dir", c.out_dir, "folder for recordings and plots");
  app.add_option("--system", system_path, "system.yaml (bus URL, channels)");
  app.add_option("--lcm-url", pipeline.lcm_url, "bus URL (default: the system's)");
  app.add_option("--config-dir", pipeline.config_dir, "folder of the processes' <name>.yaml");
  app.add_option("--model", pipeline.recognizer_model,
                 "recognizer model (default: config/recognizer.yaml's)");
  app.add_option("--stages", stages, "comma-separated stages to run (default: every built stage)");
  app.add_flag("--offline", c.offline, "run the SLAM library in-process instead of the processes");
  app.add_option("--slam-config", slam_config,
                 "offline: SLAM options file (default: <config-dir>/slam.yaml)");
  app.add_flag("--verbose", c.verbose, "offline: a line per frame");
  app.add_flag("--from-logs", c.from_logs,
               "score the recordings already in <out-dir>/logs (no run)");
  app.add_option("--proposals-config", proposals_config,
                 "re-run the proposals stage on the recording with this options file");
  app.add_option(
      "--objectmap-config", objectmap_config,
      "re-run the object map on the recording with this options file (as the lockstep node) and "
      "score its outputs instead of the recorded ones");
  app.add_option(
      "--draw-proposals", c.draw_frames,
      "write this many frames with ground truth and proposals to <out-dir>/proposals/<seq>/");
  app.add_option("--baseline-frames", c.peo.baseline_frames,
                 "frames per sequence for the selective-search baseline (0: none)");
  app.add_option(
         "--proposals-stride", c.peo.stride,
         "proposals section: every n-th frame is scored (default 5; 1 for a sparse real sequence)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--dump-proposals", c.dump_proposals,
               "write every frame's proposal boxes to <out-dir>/proposal_boxes/<seq>.csv "
               "(slamaware-train --proposals)");
  app.add_flag("--dump-boxes", c.dump_boxes,
               "write every labelled box with its single-view and multi-view scores to "
               "<out-dir>/boxes/<seq>.csv");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::set_pattern("[%H:%M:%S.%e] [eval] [%^%l%$] %v");

  try {
    c.system = loadSystemConfig(system_path, false);
    if (pipeline.lcm_url.empty()) pipeline.lcm_url = c.system.bus.url;
    pipeline.system_path = system_path;
    pipeline.only = stageList(stages);
    fs::create_directories(fs::path(c.out_dir) / "plots");
    fs::create_directories(fs::path(c.out_dir) / "logs");
    if (c.offline) {
      if (slam_config.empty() && fs::exists(fs::path(pipeline.config_dir) / "slam.yaml"))
        slam_config = (fs::path(pipeline.config_dir) / "slam.yaml").string();
      c.slam_options = loadConfig<slam::SlamOptions>(slam_config, "slam", false);
    }
    if (!objectmap_config.empty())
      c.objectmap_options =
          loadConfig<objectmap::ObjectMapOptions>(objectmap_config, "objectmap", false);
    c.rerun_proposals = !proposals_config.empty();
    // The options the recorded run used (to find why boxes were missed), or the ones to try.
    std::string proposals_path = proposals_config;
    if (proposals_path.empty() && fs::exists(fs::path(pipeline.config_dir) / "proposals.yaml"))
      proposals_path = (fs::path(pipeline.config_dir) / "proposals.yaml").string();
    c.proposal_options = loadConfig<proposals::ProposalOptions>(proposals_path, "proposals", false);

    nlohmann::json report = nlohmann::json::object();
    SuiteTotals totals;
    int failures = 0;
    for (const auto& dir : sequences)
      failures += evaluateSequence(dir, c, &report, &totals) ? 0 : 1;
    addOverall(totals, c.out_dir, &report);
    std::ofstream(out) << report.dump(2) << "\n";
    return failures ? 1 : 0;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
}
