#include "tools/eval/proposal_metrics.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/segmentation.hpp>

#include "common/bus/log_reader.h"
#include "common/geometry.h"
#include "common/image_codec.h"
#include "procs/proposals/proposal_engine.h"
#include "tools/eval/plot.h"
#include "tools/eval/stats.h"

namespace slamaware {

using namespace proposals;

double iou(const Box2& a, const Box2& b) { return rectIou(a.x, a.y, a.w, a.h, b.x, b.y, b.w, b.h); }

namespace {

bool isLocalized(const pose_t& p) {
  return p.state == pose_t::STATE_TRACKING || p.state == pose_t::STATE_RELOCALIZED;
}

void addProposals(ProposalRecording* run, const proposals_t& m) {
  auto& boxes = run->boxes[m.seq];
  boxes.clear();
  for (const auto& b : m.boxes) boxes.push_back({b.x, b.y, b.w, b.h});
}

// The ground-truth boxes of every `stride`-th frame, by frame.
std::map<int, std::vector<Box2>> truthByFrame(const SequenceFolder& seq, int stride) {
  std::map<int, std::vector<Box2>> truth;
  for (const auto& b : seq.boxes())
    if (stride <= 1 || b.frame % stride == 0) truth[b.frame].push_back({b.x, b.y, b.w, b.h});
  return truth;
}

// The rank (1-based) of the first box covering `truth` at `threshold`, 0 if none.
int rankOf(const std::vector<Box2>& ranked, const Box2& truth, double threshold) {
  for (size_t i = 0; i < ranked.size(); ++i)
    if (iou(ranked[i], truth) >= threshold) return static_cast<int>(i) + 1;
  return 0;
}

double recallAt(const std::vector<int>& ranks, int k) {
  if (ranks.empty()) return 0.0;
  const auto n = std::count_if(ranks.begin(), ranks.end(), [k](int r) { return r > 0 && r <= k; });
  return 100.0 * static_cast<double>(n) / static_cast<double>(ranks.size());
}

void drawPlot(const ProposalScores& sc, const std::string& path) {
  const int W = 640, H = 420;
  const double kmax = 2000;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  {
    PlotPanel panel(img, cv::Rect(0, 0, W, H),
                    PlotAxis{1, kmax, true, {1, 10, 100, 1000}, "boxes per frame (log)"},
                    PlotAxis{0, 100, false, {0, 20, 40, 60, 80, 100}, ""},
                    "recall of ground-truth boxes at IoU 0.5 (%)");
    auto curve = [&](const std::vector<int>& ranks, const cv::Scalar& colour,
                     const std::string& label) {
      if (ranks.empty()) return;
      std::vector<cv::Point2d> points{{1, recallAt(ranks, 1)}};
      for (int k = 2; k <= kmax; k = std::max(k + 1, static_cast<int>(k * 1.05)))
        points.emplace_back(k, recallAt(ranks, k));
      panel.curve(points, colour, label);
    };
    curve(sc.rank50, plot_colour::kBlue, "multi-view (SLAM map), every 5th frame");
    curve(sc.ours_on_baseline_frames, plot_colour::kLightBlue, "multi-view, the baseline's frames");
    curve(sc.baseline_rank50, plot_colour::kRed, "selective search (single view)");
  }  // the legend is drawn here
  writeImage(path, img);
}

}  // namespace

std::vector<Box2> selectiveSearch(const cv::Mat& bgr, int width, int max_boxes) {
  const double s = width > 0 && bgr.cols > width ? static_cast<double>(width) / bgr.cols : 1.0;
  cv::Mat small;
  cv::resize(bgr, small, cv::Size(), s, s, cv::INTER_AREA);
  auto ss = cv::ximgproc::segmentation::createSelectiveSearchSegmentation();
  ss->setBaseImage(small);
  ss->switchToSelectiveSearchFast();
  std::vector<cv::Rect> rects;
  ss->process(rects);
  std::vector<Box2> out;
  for (const auto& r : rects) {
    if (static_cast<int>(out.size()) >= max_boxes) break;
    out.push_back({r.x / s, r.y / s, r.width / s, r.height / s});
  }
  return out;
}

ProposalRecording readProposalRecording(const std::string& log_path, const Channels& ch) {
  ProposalRecording run;
  LogReader reader(log_path);
  while (auto r = reader.next()) {
    if (r->channel == ch.proposals) {
      proposals_t m;
      if (decodeRecord(*r, &m)) addProposals(&run, m);
    } else if (r->channel == ch.slam_pose) {
      pose_t m;
      if (decodeRecord(*r, &m)) run.localized[m.seq] = isLocalized(m);
    }
  }
  return run;
}

namespace {

Box2 toBox2(const ProposalBox& b) { return {b.x, b.y, b.w, b.h}; }

double bestIou(const std::vector<Box2>& boxes, const Box2& truth) {
  double best = 0;
  for (const auto& b : boxes) best = std::max(best, iou(b, truth));
  return best;
}

// The cause of each uncovered ground-truth box of one frame (ProposalMisses).
void countMisses(const ProposalEngine& engine, const ProposalOptions& options, const pose_t& pose,
                 const std::vector<Box2>& published, bool any_before,
                 const std::vector<Box2>& truth, ProposalMisses* m) {
  std::vector<Box2> without_nms, without_culling;
  const CameraModel* camera = engine.camera();
  const bool localized = isLocalized(pose);
  const bool any_uncovered = std::any_of(
      truth.begin(), truth.end(), [&](const Box2& t) { return bestIou(published, t) < 0.5; });
  if (any_uncovered && localized && camera && engine.map().mapId() == pose.map_id) {
    const SE3 T_world_camera = se3FromArrays(pose.position, pose.orientation);
    ProposalOptions o = options;
    o.nms_iou = 2;  // nothing is suppressed
    o.max_boxes = std::numeric_limits<int>::max();
    for (const auto& b : projectCandidates(engine.map().candidates(), *camera, T_world_camera, o))
      without_nms.push_back(toBox2(b));
    o.occluded_fraction = 2;  // nothing is culled either
    for (const auto& b : projectCandidates(engine.map().candidates(), *camera, T_world_camera, o))
      without_culling.push_back(toBox2(b));
  }
  for (const auto& t : truth) {
    ++m->boxes;
    if (bestIou(published, t) >= 0.5)
      ++m->covered;
    else if (!any_before)
      ++m->before_first;
    else if (!localized)
      ++m->not_localized;
    else if (bestIou(without_nms, t) >= 0.5)
      ++m->suppressed;
    else if (bestIou(without_culling, t) >= 0.5)
      ++m->occluded;
    else if (bestIou(without_culling, t) >= 0.3)
      ++m->partial;
    else
      ++m->no_candidate;
  }
}

}  // namespace

ProposalRecording rerunProposals(const std::string& log_path, const Channels& ch,
                                 const ProposalOptions& options, const SequenceFolder* sequence,
                                 int stride, ProposalMisses* misses) {
  std::map<int, std::vector<Box2>> truth;
  if (sequence && misses) truth = truthByFrame(*sequence, stride);
  bool any_proposals = false;                  // a frame so far had proposals
  std::map<int, bool> unlocated_before_first;  // frame not located -> it came before any proposals
  ProposalRecording run;
  ProposalEngine engine(options);
  LogReader reader(log_path);
  std::string why;
  while (auto r = reader.next()) {
    if (r->channel == ch.camera_info) {
      camera_info_t m;
      if (decodeRecord(*r, &m) && !engine.onCameraInfo(m, &why)) spdlog::warn("{}", why);
    } else if (r->channel == ch.slam_map) {
      point_cloud_t m;
      if (decodeRecord(*r, &m) && !engine.onMap(m, &why)) spdlog::warn("{}", why);
    } else if (r->channel == ch.slam_keyframe) {
      keyframe_t m;
      if (decodeRecord(*r, &m)) engine.onKeyframe(m);
    } else if (r->channel == ch.slam_pose) {
      pose_t m;
      if (!decodeRecord(*r, &m)) continue;
      run.localized[m.seq] = isLocalized(m);
      bool reclustered = false;
      const proposals_t p = engine.onPose(m, &why, &reclustered);
      for (const proposals_t& late : engine.takeLateProposals()) addProposals(&run, late);
      addProposals(&run, p);
      any_proposals = any_proposals || p.num_boxes > 0;
      // A frame not located may still get proposals late (a map's reference keyframe): counted
      // at the end.
      if (const auto t = truth.find(m.seq); t != truth.end() && isLocalized(m)) {
        countMisses(engine, options, m, run.boxes[m.seq], any_proposals, t->second, misses);
        truth.erase(t);
      } else if (t != truth.end()) {
        unlocated_before_first[m.seq] = !any_proposals;
      }
      if (reclustered) {
        const ClusterStats& s = engine.map().stats();
        ++run.reclusters;
        run.recluster_ms += s.ms;
        spdlog::debug(
            "frame {}: map {} points{} ({} cropped, {} single-view, voxel {:.4f}), {} planes with "
            "{} points, "
            "support {}, scale {:.3f}, {} clustered -> {} candidates ({} of {} band points taken), "
            "{:.0f} ms",
            m.seq, s.input_points, s.young ? " (young)" : "", s.cropped, s.single_view, s.voxel,
            s.planes, s.plane_points, s.support, s.scene_scale, s.clustered_points, s.clusters,
            s.band_taken, s.band_points, s.ms);
      }
    }
  }
  // Frames not located or SLAM never gave a pose for: covered only by late proposals.
  for (const auto& [frame, boxes] : truth) {
    if (frame < 0 || static_cast<size_t>(frame) >= sequence->size()) continue;
    const auto posed = unlocated_before_first.find(frame);
    const bool before_first =
        posed != unlocated_before_first.end() ? posed->second : !any_proposals;
    const auto late = run.boxes.find(frame);
    for (const auto& t : boxes) {
      ++misses->boxes;
      if (late != run.boxes.end() && bestIou(late->second, t) >= 0.5)
        ++misses->covered;
      else
        ++(before_first ? misses->before_first : misses->not_localized);
    }
  }
  return run;
}

nlohmann::json missesSection(const ProposalMisses& m) {
  nlohmann::json j;
  ProposalMisses::forEach(m, [&](const char* key, int n) { j[key] = n; });
  return j;
}

void mergeMisses(ProposalMisses* into, const ProposalMisses& more) {
  std::vector<int> counts;
  ProposalMisses::forEach(more, [&](const char*, int n) { counts.push_back(n); });
  size_t i = 0;
  ProposalMisses::forEach(*into, [&](const char*, int& n) { n += counts[i++]; });
}

ProposalScores scoreProposals(const ProposalRecording& run, const SequenceFolder& seq,
                              const ProposalEvalOptions& o) {
  ProposalScores sc;
  std::map<int, std::vector<Box2>> truth = truthByFrame(seq, o.stride);
  std::vector<int> frames;
  for (const auto& [f, boxes] : truth) {
    if (f < 0 || static_cast<size_t>(f) >= seq.size()) continue;
    const auto loc = run.localized.find(f);
    const bool localized = loc != run.localized.end() && loc->second;
    frames.push_back(f);
    ++sc.frames;
    const auto it = run.boxes.find(f);
    static const std::vector<Box2> none;
    const std::vector<Box2>& ours = it == run.boxes.end() ? none : it->second;
    if (localized) {
      ++sc.localized_frames;
      sc.boxes_per_frame.push_back(static_cast<int>(ours.size()));
    }
    for (const auto& t : boxes) {
      sc.rank50.push_back(rankOf(ours, t, 0.5));
      sc.rank70.push_back(rankOf(ours, t, 0.7));
      if (localized) sc.rank50_localized.push_back(sc.rank50.back());
    }
  }
  if (!o.baseline || frames.empty() || o.baseline_frames <= 0) return sc;
  // The baseline on frames spread evenly over the evaluated ones.
  const size_t n = std::min(frames.size(), static_cast<size_t>(o.baseline_frames));
  double ms = 0;
  for (size_t i = 0; i < n; ++i) {
    const int f = frames[i * frames.size() / n];
    const cv::Mat bgr = readImage(seq.framePath(static_cast<size_t>(f)));
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<Box2> base = selectiveSearch(bgr, o.baseline_width, o.baseline_max_boxes);
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const auto it = run.boxes.find(f);
    static const std::vector<Box2> none;
    const std::vector<Box2>& ours = it == run.boxes.end() ? none : it->second;
    for (const auto& t : truth[f]) {
      sc.baseline_rank50.push_back(rankOf(base, t, 0.5));
      sc.ours_on_baseline_frames.push_back(rankOf(ours, t, 0.5));
    }
  }
  sc.baseline_frames = static_cast<int>(n);
  sc.baseline_ms_per_frame = ms / static_cast<double>(n);
  return sc;
}

void mergeScores(ProposalScores* into, const ProposalScores& more) {
  auto append = [](std::vector<int>& a, const std::vector<int>& b) {
    a.insert(a.end(), b.begin(), b.end());
  };
  append(into->rank50, more.rank50);
  append(into->rank70, more.rank70);
  append(into->rank50_localized, more.rank50_localized);
  append(into->boxes_per_frame, more.boxes_per_frame);
  append(into->ours_on_baseline_frames, more.ours_on_baseline_frames);
  append(into->baseline_rank50, more.baseline_rank50);
  into->baseline_ms_per_frame = (into->baseline_ms_per_frame * into->baseline_frames +
                                 more.baseline_ms_per_frame * more.baseline_frames) /
                                std::max(1, into->baseline_frames + more.baseline_frames);
  into->frames += more.frames;
  into->localized_frames += more.localized_frames;
  into->baseline_frames += more.baseline_frames;
}

nlohmann::json proposalSection(const ProposalScores& sc, const std::string& plot_path) {
  constexpr int kAll = 1 << 30;
  nlohmann::json j;
  j["frames_evaluated"] = sc.frames;
  j["localized_frames"] = sc.localized_frames;
  j["ground_truth_boxes"] = sc.rank50.size();
  j["recall_iou50"] = recallAt(sc.rank50, kAll);
  j["recall_iou70"] = recallAt(sc.rank70, kAll);
  j["recall_iou50_localized_frames"] = recallAt(sc.rank50_localized, kAll);
  for (int k : {5, 10, 15, 20, 30})
    j["recall_iou50_at_boxes"][std::to_string(k)] = recallAt(sc.rank50, k);
  const double per_frame = median(sc.boxes_per_frame);
  j["boxes_per_frame"] = per_frame;
  j["boxes_per_frame_max"] =
      sc.boxes_per_frame.empty()
          ? 0
          : *std::max_element(sc.boxes_per_frame.begin(), sc.boxes_per_frame.end());
  if (!sc.baseline_rank50.empty()) {
    nlohmann::json b;
    b["name"] = "OpenCV selective search (ximgproc, fast mode)";
    b["frames"] = sc.baseline_frames;
    b["ms_per_frame"] = sc.baseline_ms_per_frame;
    const int k = std::max(1, static_cast<int>(std::lround(per_frame)));
    b["boxes_per_frame"] = k;
    b["recall_iou50"] = recallAt(sc.baseline_rank50, k);
    b["recall_iou50_all_boxes"] = recallAt(sc.baseline_rank50, kAll);
    const double ours = recallAt(sc.ours_on_baseline_frames, kAll);
    b["ours_recall_iou50_same_frames"] = ours;
    // Boxes the baseline needs per frame to reach our recall on its frames (null: never).
    int need = 0;
    const int most = sc.baseline_rank50.empty()
                         ? 0
                         : *std::max_element(sc.baseline_rank50.begin(), sc.baseline_rank50.end());
    for (int kk = 1; kk <= most; ++kk)
      if (recallAt(sc.baseline_rank50, kk) >= ours) {
        need = kk;
        break;
      }
    b["boxes_for_our_recall"] = need > 0 ? nlohmann::json(need) : nlohmann::json(nullptr);
    j["baseline"] = b;
  }
  if (!plot_path.empty()) {
    drawPlot(sc, plot_path);
    j["plot"] = plot_path;
  }
  return j;
}

void writeProposalBoxes(const ProposalRecording& run, const std::string& path) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream out(path);
  out << "frame,rank,x,y,w,h\n";
  for (const auto& [frame, boxes] : run.boxes)
    for (size_t r = 0; r < boxes.size(); ++r)
      out << frame << ',' << r << ',' << boxes[r].x << ',' << boxes[r].y << ',' << boxes[r].w << ','
          << boxes[r].h << '\n';
  if (!out) throw std::runtime_error(path + ": cannot write the proposal boxes");
}

void drawProposalFrames(const ProposalRecording& run, const SequenceFolder& seq,
                        const std::string& dir, int stride, int max_frames, int top_k) {
  std::map<int, std::vector<GroundTruthBox>> truth;
  for (const auto& b : seq.boxes())
    if (stride <= 1 || b.frame % stride == 0) truth[b.frame].push_back(b);
  std::vector<int> frames;
  for (const auto& [f, boxes] : truth)
    if (f >= 0 && static_cast<size_t>(f) < seq.size()) frames.push_back(f);
  const size_t n = std::min(frames.size(), static_cast<size_t>(std::max(0, max_frames)));
  for (size_t i = 0; i < n; ++i) {
    const int f = frames[i * frames.size() / n];
    cv::Mat img = readImage(seq.framePath(static_cast<size_t>(f)));
    for (const auto& t : truth[f])
      cv::rectangle(img, cv::Rect2d(t.x, t.y, t.w, t.h), cv::Scalar(0, 200, 0), 2);
    const auto it = run.boxes.find(f);
    if (it != run.boxes.end())
      for (int k = 0; k < std::min<int>(top_k, static_cast<int>(it->second.size())); ++k) {
        const Box2& b = it->second[static_cast<size_t>(k)];
        cv::rectangle(img, cv::Rect2d(b.x, b.y, b.w, b.h), cv::Scalar(0, 140, 255), 1);
        cv::putText(img, std::to_string(k + 1),
                    cv::Point(static_cast<int>(b.x) + 2, static_cast<int>(b.y) + 12),
                    cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 140, 255), 1, cv::LINE_AA);
      }
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", f);
    writeImage(dir + "/" + name, img);
  }
}

}  // namespace slamaware
