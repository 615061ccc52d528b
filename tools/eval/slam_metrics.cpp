#include "tools/eval/slam_metrics.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <set>

#include "common/image_codec.h"
#include "common/tum.h"

namespace slamaware {

namespace {

constexpr int8_t kTracking = 1, kRelocalized = 3;

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double round3(double x) { return std::round(x * 1000.0) / 1000.0; }

struct MapAlignment {
  Sim3 sim;  ///< SLAM world -> ground-truth world
  std::vector<int32_t> seqs;
  std::vector<Eigen::Vector3d> aligned, truth;
};

// Top-down view in the plane of the two main axes of the ground-truth positions.
void drawPlot(const std::string& path, const std::string& title,
              const std::vector<Eigen::Vector3d>& gt_path,
              const std::map<int, MapAlignment>& maps) {
  std::vector<Eigen::Vector3d> all = gt_path;
  for (const auto& [id, m] : maps) all.insert(all.end(), m.aligned.begin(), m.aligned.end());
  if (all.empty()) return;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  const std::vector<Eigen::Vector3d>& basis_points = gt_path.size() >= 3 ? gt_path : all;
  for (const auto& p : basis_points) mean += p;
  mean /= double(basis_points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : basis_points) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d ax = eig.eigenvectors().col(2), ay = eig.eigenvectors().col(1);
  double min_x = 1e30, max_x = -1e30, min_y = 1e30, max_y = -1e30;
  for (const auto& p : all) {
    const double x = (p - mean).dot(ax), y = (p - mean).dot(ay);
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  }
  const int size = 800, margin = 60;
  const double span = std::max({max_x - min_x, max_y - min_y, 1e-6});
  const double scale = (size - 2 * margin) / span;
  auto toPixel = [&](const Eigen::Vector3d& p) {
    const double x = (p - mean).dot(ax), y = (p - mean).dot(ay);
    return cv::Point(static_cast<int>(margin + (x - min_x) * scale),
                     static_cast<int>(size - margin - (y - min_y) * scale));
  };
  cv::Mat img(size, size, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<cv::Point> line;
  for (const auto& p : gt_path) line.push_back(toPixel(p));
  if (line.size() > 1) cv::polylines(img, line, false, cv::Scalar(60, 160, 60), 2, cv::LINE_AA);
  const cv::Scalar colours[] = {
      {200, 80, 30}, {30, 30, 200}, {160, 40, 160}, {20, 140, 200}, {90, 90, 90}};
  int k = 0;
  for (const auto& [id, m] : maps) {
    const cv::Scalar c = colours[k++ % 5];
    for (size_t i = 0; i < m.aligned.size(); ++i) {
      const cv::Point a = toPixel(m.aligned[i]);
      cv::line(img, a, toPixel(m.truth[i]), cv::Scalar(200, 200, 200), 1, cv::LINE_AA);
      cv::circle(img, a, 3, c, cv::FILLED, cv::LINE_AA);
      if (i > 0 && m.seqs[i] == m.seqs[i - 1] + 1)
        cv::line(img, toPixel(m.aligned[i - 1]), a, c, 1, cv::LINE_AA);
    }
    cv::putText(img, "map " + std::to_string(id), cv::Point(margin, 20 + 18 * k),
                cv::FONT_HERSHEY_SIMPLEX, 0.5, c, 1, cv::LINE_AA);
  }
  cv::putText(img, title, cv::Point(margin, size - 20), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, "ground truth", cv::Point(size - 200, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(60, 160, 60), 1, cv::LINE_AA);
  writeImage(path, img);
}

}  // namespace

void SlamRecording::addCloud(int map_id, bool full, int64_t keyframe_id,
                             std::vector<Point> cloud_points) {
  auto& pts = points[map_id];
  if (full) {
    pts = std::move(cloud_points);
    return;
  }
  pts.erase(std::remove_if(pts.begin(), pts.end(),
                           [&](const Point& p) { return p.keyframe_id == keyframe_id; }),
            pts.end());
  pts.insert(pts.end(), cloud_points.begin(), cloud_points.end());
}

// Semi-dense depth against depth/ (16-bit PNG, mm): each point's depth in its keyframe, scaled
// by its map's Sim(3), against the true depth at the pixel it projects to; and points per keyframe.
void addDepthFigures(const SlamRecording& run, const SequenceFolder& sequence,
                     const std::map<int, MapAlignment>& maps, nlohmann::json& s) {
  const int frames = static_cast<int>(sequence.size());
  std::map<int64_t, int> points_per_keyframe;
  int64_t total_points = 0;
  for (const auto& [map_id, pts] : run.points) {
    total_points += static_cast<int64_t>(pts.size());
    for (const auto& p : pts) ++points_per_keyframe[p.keyframe_id];
  }
  std::vector<double> per_kf;
  for (const auto& [id, n] : points_per_keyframe) per_kf.push_back(n);
  s["semi_dense_points"] = total_points;
  if (!per_kf.empty()) {
    double sum = 0;
    for (double n : per_kf) sum += n;
    // Over the keyframes whose points were published (the last keyframes of a run, still
    // being filtered when it ended, have none).
    s["keyframes_with_points"] = static_cast<int64_t>(per_kf.size());
    s["points_per_keyframe_mean"] = round3(sum / per_kf.size());
    s["points_per_keyframe_median"] = median(per_kf);
  }
  const bool has_depth = frames > 0 && !sequence.depthPath(0).empty();
  if (!has_depth) return;
  std::vector<double> rel;
  std::map<int32_t, cv::Mat> depth_cache;
  const CameraModel& camera = sequence.info().camera;
  for (const auto& [map_id, pts] : run.points) {
    auto m = maps.find(map_id);
    if (m == maps.end()) continue;
    for (const auto& p : pts) {
      auto kf = run.keyframes.find(p.keyframe_id);
      if (kf == run.keyframes.end() || kf->second.seq < 0 || kf->second.seq >= frames) continue;
      const int32_t seq = kf->second.seq;
      auto d = depth_cache.find(seq);
      if (d == depth_cache.end()) {
        const std::string dp = sequence.depthPath(seq);
        d = depth_cache.emplace(seq, dp.empty() ? cv::Mat() : readImageUnchanged(dp)).first;
      }
      if (d->second.empty() || d->second.type() != CV_16UC1) continue;
      const Eigen::Vector3d pc = kf->second.T_world_camera.inverse() * p.p_world.cast<double>();
      Eigen::Vector2d px;
      if (!camera.project(pc, &px) || !camera.inImage(px)) continue;
      const uint16_t mm = d->second.at<uint16_t>(static_cast<int>(std::lround(px.y())),
                                                 static_cast<int>(std::lround(px.x())));
      if (mm == 0) continue;
      const double truth = mm / 1000.0, estimate = m->second.sim.s * pc.z();
      rel.push_back(std::abs(estimate - truth) / truth);
    }
  }
  s["depth_points_evaluated"] = static_cast<int64_t>(rel.size());
  if (!rel.empty()) {
    s["depth_rel_err_median_pct"] = round3(100.0 * median(rel));
    int within = 0;
    for (double r : rel) within += r <= 0.03;
    s["depth_within_3pct"] = round3(100.0 * within / rel.size());
  }
}

nlohmann::json evaluateSlam(const SlamRecording& run, const SequenceFolder& sequence,
                            const SlamEvalOptions& options) {
  nlohmann::json s;
  const int frames = static_cast<int>(sequence.size());
  std::vector<TimedPose> gt;
  if (sequence.hasGroundTruth()) gt = sequence.groundTruth();
  std::vector<const TimedPose*> gt_of(frames, nullptr);
  for (int i = 0; i < frames; ++i)
    gt_of[i] = closestPose(gt, sequence.timestamp(i), options.max_time_difference_s);

  // Ground-truth path length and extent (largest distance between two camera centres).
  std::vector<Eigen::Vector3d> gt_path;
  for (int i = 0; i < frames; ++i)
    if (gt_of[i]) gt_path.push_back(gt_of[i]->T_world_camera.translation());
  double path = 0, extent = 0;
  for (size_t i = 1; i < gt_path.size(); ++i) path += (gt_path[i] - gt_path[i - 1]).norm();
  for (size_t i = 0; i < gt_path.size(); ++i)
    for (size_t j = i + 1; j < gt_path.size(); ++j)
      extent = std::max(extent, (gt_path[i] - gt_path[j]).norm());

  int tracked = 0;
  std::set<int32_t> localized;
  std::set<int> map_ids;
  std::map<int, MapAlignment> maps;
  std::map<int, std::vector<Eigen::Vector3d>> estimates;
  for (const auto& [seq, pose] : run.poses) {
    if (pose.map_id > 0) map_ids.insert(pose.map_id);
    if (seq < 0 || seq >= frames) continue;
    if (pose.state != kTracking && pose.state != kRelocalized) continue;
    ++tracked;
    localized.insert(seq);
    if (!gt_of[seq]) continue;
    maps[pose.map_id].seqs.push_back(seq);
    estimates[pose.map_id].push_back(pose.T_world_camera.translation());
    maps[pose.map_id].truth.push_back(gt_of[seq]->T_world_camera.translation());
  }
  for (const auto& [id, kf] : run.keyframes)
    if (kf.seq >= 0 && kf.seq < frames) localized.insert(kf.seq);

  double sq = 0;
  int ate_frames = 0, excluded = 0;
  nlohmann::json per_map = nlohmann::json::object();
  for (auto it = maps.begin(); it != maps.end();) {
    MapAlignment& m = it->second;
    const auto& est = estimates[it->first];
    if (est.size() < 3) {
      excluded += static_cast<int>(est.size());
      it = maps.erase(it);
      continue;
    }
    m.sim = alignUmeyama(est, m.truth, true);
    double map_sq = 0;
    for (size_t i = 0; i < est.size(); ++i) {
      m.aligned.push_back(m.sim * est[i]);
      map_sq += (m.aligned.back() - m.truth[i]).squaredNorm();
      ++ate_frames;
    }
    sq += map_sq;
    per_map[std::to_string(it->first)] = {
        {"frames", est.size()}, {"ate_rmse", round3(std::sqrt(map_sq / est.size()) * 1000) / 1000}};
    ++it;
  }
  const double ate = ate_frames ? std::sqrt(sq / ate_frames) : 0;
  s["frames"] = frames;
  s["tracked_frames"] = tracked;
  s["tracked_pct"] = round3(frames ? 100.0 * tracked / frames : 0);
  s["localized_pct"] = round3(frames ? 100.0 * localized.size() / frames : 0);
  s["maps"] = static_cast<int>(map_ids.size());
  s["reinitializations"] = std::max(0, static_cast<int>(map_ids.size()) - 1);
  s["keyframes"] = static_cast<int>(run.keyframes.size());
  if (!gt.empty()) {
    s["ate_rmse"] = round3(ate * 1000) / 1000;
    s["ate_frames"] = ate_frames;
    s["ate_frames_excluded"] = excluded;
    s["maps_aligned"] = per_map;
    s["gt_path_length_m"] = round3(path);
    s["gt_extent_m"] = round3(extent);
    s["ate_rmse_pct_of_path"] = round3(path > 0 ? 100.0 * ate / path : 0);
    s["ate_rmse_pct_of_extent"] = round3(extent > 0 ? 100.0 * ate / extent : 0);
  }

  addDepthFigures(run, sequence, maps, s);
  if (!options.plot_path.empty()) {
    char title[160];
    std::snprintf(title, sizeof(title), "%s  ATE %.3f m (%.2f%% of path), tracked %.1f%%",
                  sequence.info().name.c_str(), ate, path > 0 ? 100 * ate / path : 0.0,
                  frames ? 100.0 * tracked / frames : 0.0);
    drawPlot(options.plot_path, title, gt_path, maps);
    s["plot"] = options.plot_path;
  }
  return s;
}

nlohmann::json summarizeSlam(const std::vector<nlohmann::json>& sections) {
  nlohmann::json o;
  double frames = 0, tracked = 0, ate_sq = 0, ate_n = 0, pct_path = 0, depth = 0, ppk = 0;
  int n = 0, n_ate = 0, n_depth = 0, n_ppk = 0, reinit = 0;
  for (const auto& s : sections) {
    ++n;
    frames += s.value("frames", 0);
    tracked += s.value("tracked_frames", 0);
    reinit += s.value("reinitializations", 0);
    if (s.contains("ate_rmse")) {
      const double a = s["ate_rmse"], k = s.value("ate_frames", 0);
      ate_sq += a * a * k;
      ate_n += k;
      pct_path += s.value("ate_rmse_pct_of_path", 0.0);
      ++n_ate;
    }
    if (s.contains("depth_rel_err_median_pct")) {
      depth += s["depth_rel_err_median_pct"].get<double>();
      ++n_depth;
    }
    if (s.contains("points_per_keyframe_mean")) {
      ppk += s["points_per_keyframe_mean"].get<double>();
      ++n_ppk;
    }
  }
  o["sequences"] = n;
  o["tracked_pct"] = round3(frames > 0 ? 100.0 * tracked / frames : 0);
  o["reinitializations"] = reinit;
  if (ate_n > 0) o["ate_rmse"] = round3(std::sqrt(ate_sq / ate_n) * 1000) / 1000;
  if (n_ate) o["ate_rmse_pct_of_path"] = round3(pct_path / n_ate);
  if (n_depth) o["depth_rel_err_median_pct"] = round3(depth / n_depth);
  if (n_ppk) o["points_per_keyframe_mean"] = round3(ppk / n_ppk);
  return o;
}

}  // namespace slamaware
