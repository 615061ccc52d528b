#include "procs/slam/map/keyframe.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "procs/slam/map/map_point.h"

namespace slamaware::slam {

KeyFrame::KeyFrame(int64_t id_, int map_id_, const Frame& frame)
    : id(id_),
      map_id(map_id_),
      frame_id(frame.id),
      utime(frame.utime),
      seq(frame.seq),
      features(frame.features),
      grey(frame.grey),
      bgr(frame.bgr),
      thumbnail(makeThumbnail(frame.grey)),
      T_camera_world(frame.T_camera_world),
      points(frame.points) {
  for (int i = 0; i < size(); ++i)
    if (points[i] && (frame.outlier[i] || points[i]->bad)) points[i] = nullptr;
}

int KeyFrame::trackedPoints(int min_observations) const {
  int n = 0;
  for (const auto& p : points)
    if (p && !p->bad && p->numObservations() >= min_observations) ++n;
  return n;
}

double KeyFrame::medianDepth() const {
  std::vector<double> depths;
  for (const auto& p : points)
    if (p && !p->bad) depths.push_back((T_camera_world * p->p_world).z());
  if (depths.empty()) return -1;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  return depths[depths.size() / 2];
}

bool KeyFrame::depthRange(double* min_depth, double* mean_depth) const {
  double min_z = 1e30, inv_sum = 0;
  int n = 0;
  for (const auto& p : points) {
    if (!p || p->bad) continue;
    const double z = (T_camera_world * p->p_world).z();
    if (z <= 0) continue;
    min_z = std::min(min_z, z);
    inv_sum += 1.0 / z;
    ++n;
  }
  if (n == 0) return false;
  *min_depth = min_z;
  *mean_depth = n / inv_sum;
  return true;
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::bestCovisible(int n) const {
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (const auto& [w, kf] : ordered_) {
    if (static_cast<int>(out.size()) >= n) break;
    if (!kf->bad) out.push_back(kf);
  }
  return out;
}

void KeyFrame::updateConnections(int min_weight) {
  std::map<int64_t, std::pair<int, std::shared_ptr<KeyFrame>>> counts;
  for (const auto& p : points) {
    if (!p || p->bad) continue;
    for (const auto& [kf_id, obs] : p->observations) {
      if (kf_id == id || obs.keyframe->bad) continue;
      auto& c = counts[kf_id];
      ++c.first;
      c.second = obs.keyframe;
    }
  }
  std::map<int64_t, std::pair<int, std::shared_ptr<KeyFrame>>> kept;
  int64_t best_id = -1;
  int best_weight = 0;
  for (const auto& [kf_id, c] : counts) {
    if (c.first > best_weight) {
      best_weight = c.first;
      best_id = kf_id;
    }
    if (c.first >= min_weight) kept[kf_id] = c;
  }
  if (kept.empty() && best_id >= 0) kept[best_id] = counts[best_id];
  auto self = shared_from_this();
  for (const auto& [kf_id, c] : connections_)
    if (!kept.count(kf_id)) c.second->eraseConnection(id);
  for (const auto& [kf_id, c] : kept) c.second->addConnection(self, c.first);
  connections_ = std::move(kept);
  sortConnections();
}

void KeyFrame::addConnection(const std::shared_ptr<KeyFrame>& kf, int w) {
  connections_[kf->id] = {w, kf};
  sortConnections();
}

void KeyFrame::eraseConnection(int64_t keyframe_id) {
  if (connections_.erase(keyframe_id)) sortConnections();
}

void KeyFrame::clearConnections() {
  for (const auto& [kf_id, c] : connections_) c.second->eraseConnection(id);
  connections_.clear();
  ordered_.clear();
}

void KeyFrame::sortConnections() {
  ordered_.clear();
  for (const auto& [kf_id, c] : connections_) ordered_.push_back(c);
  // Heaviest first; equal weights by id (connections_ is ordered by id and the sort is stable).
  std::stable_sort(ordered_.begin(), ordered_.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
}

cv::Mat KeyFrame::makeThumbnail(const cv::Mat& grey) {
  cv::Mat small, f;
  cv::resize(grey, small, cv::Size(80, 60), 0, 0, cv::INTER_AREA);
  small.convertTo(f, CV_32F);
  cv::GaussianBlur(f, f, cv::Size(0, 0), 1.5);
  f -= cv::mean(f)[0];
  const double n = cv::norm(f);
  if (n > 1e-6) f /= n;
  return f;
}

double KeyFrame::thumbnailSimilarity(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty() || a.size() != b.size()) return -1;
  return a.dot(b);
}

}  // namespace slamaware::slam
