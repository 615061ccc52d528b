#include "procs/slam/features/orb_extractor.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <thread>

namespace slamaware::slam {

namespace {

constexpr int kBorder =
    OrbExtractor::kPatchRadius + 2;  // px a keypoint keeps from the level's edge

// A quadtree node: a region of the level image and the keypoints inside it.
struct QuadNode {
  float x0, y0, x1, y1;
  std::vector<int> members;
};

// Keeps at most `n` keypoints spread over the region: nodes are split in four until there are
// n of them (largest first when only some can still be split), then each keeps its strongest.
std::vector<cv::KeyPoint> distributeQuadtree(const std::vector<cv::KeyPoint>& kps, float x0,
                                             float y0, float x1, float y1, int n) {
  if (static_cast<int>(kps.size()) <= n || n <= 0)
    return n <= 0 ? std::vector<cv::KeyPoint>{} : kps;
  // Roughly square initial nodes along the longer side.
  const int roots = std::max(1, static_cast<int>(std::lround((x1 - x0) / std::max(1.f, y1 - y0))));
  std::vector<QuadNode> nodes;
  const float w = (x1 - x0) / roots;
  for (int i = 0; i < roots; ++i) nodes.push_back({x0 + i * w, y0, x0 + (i + 1) * w, y1, {}});
  for (int i = 0; i < static_cast<int>(kps.size()); ++i) {
    const int r = std::clamp(static_cast<int>((kps[i].pt.x - x0) / w), 0, roots - 1);
    nodes[r].members.push_back(i);
  }
  nodes.erase(std::remove_if(nodes.begin(), nodes.end(),
                             [](const QuadNode& q) { return q.members.empty(); }),
              nodes.end());

  auto split = [&](const QuadNode& q, std::vector<QuadNode>* out) {
    const float mx = 0.5f * (q.x0 + q.x1), my = 0.5f * (q.y0 + q.y1);
    QuadNode c[4] = {{q.x0, q.y0, mx, my, {}},
                     {mx, q.y0, q.x1, my, {}},
                     {q.x0, my, mx, q.y1, {}},
                     {mx, my, q.x1, q.y1, {}}};
    for (int i : q.members) {
      const cv::Point2f& p = kps[i].pt;
      c[(p.x >= mx ? 1 : 0) + (p.y >= my ? 2 : 0)].members.push_back(i);
    }
    for (auto& child : c)
      if (!child.members.empty()) out->push_back(std::move(child));
  };
  auto splittable = [](const QuadNode& q) { return q.members.size() > 1 && (q.x1 - q.x0) > 1.f; };

  while (static_cast<int>(nodes.size()) < n) {
    std::vector<int> candidates;
    for (int i = 0; i < static_cast<int>(nodes.size()); ++i)
      if (splittable(nodes[i])) candidates.push_back(i);
    if (candidates.empty()) break;
    std::vector<QuadNode> next;
    if (nodes.size() + 3 * candidates.size() <= static_cast<size_t>(n)) {
      for (auto& q : nodes) {
        if (splittable(q))
          split(q, &next);
        else
          next.push_back(std::move(q));
      }
      nodes = std::move(next);
      continue;
    }
    // Last round: split the most crowded nodes first until there are enough.
    std::stable_sort(candidates.begin(), candidates.end(), [&](int a, int b) {
      return nodes[a].members.size() > nodes[b].members.size();
    });
    std::vector<bool> do_split(nodes.size(), false);
    size_t count = nodes.size();
    for (int c : candidates) {
      if (count >= static_cast<size_t>(n)) break;
      do_split[c] = true;
      count += 3;  // at most; empty children are dropped
    }
    for (size_t i = 0; i < nodes.size(); ++i) {
      if (do_split[i])
        split(nodes[i], &next);
      else
        next.push_back(std::move(nodes[i]));
    }
    nodes = std::move(next);
    break;
  }

  std::vector<cv::KeyPoint> out;
  out.reserve(nodes.size());
  for (const auto& q : nodes) {
    int best = q.members.front();
    for (int i : q.members)
      if (kps[i].response > kps[best].response) best = i;
    out.push_back(kps[best]);
  }
  if (static_cast<int>(out.size()) > n) {
    std::stable_sort(out.begin(), out.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
      return a.response > b.response;
    });
    out.resize(n);
  }
  return out;
}

// Orientation by the intensity centroid of the disk around the keypoint (Rosin 1999).
float intensityCentroidAngle(const cv::Mat& image, cv::Point2f pt, const std::vector<int>& umax) {
  const int r = OrbExtractor::kPatchRadius;
  const uint8_t* center = image.ptr<uint8_t>(cvRound(pt.y), cvRound(pt.x));
  const int step = static_cast<int>(image.step1());
  int m01 = 0, m10 = 0;
  for (int u = -r; u <= r; ++u) m10 += u * center[u];
  for (int v = 1; v <= r; ++v) {
    int v_sum = 0;
    const int d = umax[v];
    for (int u = -d; u <= d; ++u) {
      const int plus = center[u + v * step], minus = center[u - v * step];
      v_sum += plus - minus;
      m10 += u * (plus + minus);
    }
    m01 += v * v_sum;
  }
  float angle = static_cast<float>(std::atan2(static_cast<double>(m01), static_cast<double>(m10)) *
                                   180.0 / M_PI);
  if (angle < 0) angle += 360.f;
  return angle;
}

}  // namespace

ScalePyramid::ScalePyramid(double factor, int levels)
    : scale_factor(factor), log_scale(std::log(factor)) {
  scale.resize(levels);
  sigma2.resize(levels);
  inv_sigma2.resize(levels);
  for (int l = 0; l < levels; ++l) {
    scale[l] = std::pow(factor, l);
    sigma2[l] = scale[l] * scale[l];
    inv_sigma2[l] = 1.0 / sigma2[l];
  }
}

int ScalePyramid::predictLevel(double max_distance, double distance) const {
  if (distance <= 0) return levels() - 1;
  const int level = static_cast<int>(std::ceil(std::log(max_distance / distance) / log_scale));
  return std::clamp(level, 0, levels() - 1);
}

OrbExtractor::OrbExtractor(const OrbOptions& options)
    : options_(options), pyramid_(options.scale_factor, std::max(1, options.num_levels)) {
  const int levels = pyramid_.levels();
  // Features per level in proportion to the level's linear size (ORB-SLAM's geometric series).
  const double f = 1.0 / options_.scale_factor;
  double per_level = options_.num_features * (1 - f) / (1 - std::pow(f, levels));
  int assigned = 0;
  features_per_level_.resize(levels);
  for (int l = 0; l < levels - 1; ++l) {
    features_per_level_[l] = static_cast<int>(std::lround(per_level));
    assigned += features_per_level_[l];
    per_level *= f;
  }
  features_per_level_[levels - 1] = std::max(0, options_.num_features - assigned);

  umax_.resize(kPatchRadius + 1);
  for (int v = 0; v <= kPatchRadius; ++v)
    umax_[v] =
        static_cast<int>(std::lround(std::sqrt(double(kPatchRadius * kPatchRadius - v * v))));

  // BRIEF test pairs drawn i.i.d. from an isotropic Gaussian (sigma = patch / 5, Calonder et al.'s
  // "G II"), kept inside the disk so that any rotation stays inside the patch.
  // Box-Muller over mt19937_64 (whose output the standard fixes, unlike its distributions).
  std::mt19937_64 rng(options_.pattern_seed);
  const double sigma = (2 * kPatchRadius + 1) / 5.0;
  auto gauss = [&]() {
    const double u1 = (static_cast<double>(rng() >> 11) + 1.0) * 0x1.0p-53,
                 u2 = static_cast<double>(rng() >> 11) * 0x1.0p-53;
    return sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2 * M_PI * u2);
  };
  auto draw = [&](int8_t* x, int8_t* y) {
    while (true) {
      const int a = static_cast<int>(std::lround(gauss())),
                b = static_cast<int>(std::lround(gauss()));
      if (a * a + b * b <= (kPatchRadius - 1) * (kPatchRadius - 1)) {
        *x = static_cast<int8_t>(a);
        *y = static_cast<int8_t>(b);
        return;
      }
    }
  };
  pattern_.resize(kDescriptorBytes * 8);
  for (auto& p : pattern_) {
    do {
      draw(&p[0], &p[1]);
      draw(&p[2], &p[3]);
    } while (p[0] == p[2] && p[1] == p[3]);
  }
}

void OrbExtractor::detectLevel(const cv::Mat& image, int level,
                               std::vector<cv::KeyPoint>* out) const {
  const int x_min = kBorder, y_min = kBorder, x_max = image.cols - kBorder,
            y_max = image.rows - kBorder;
  if (x_max - x_min < 8 || y_max - y_min < 8) return;
  const int cell = std::max(8, options_.cell_size_px);
  const int cols = std::max(1, (x_max - x_min) / cell), rows = std::max(1, (y_max - y_min) / cell);
  const float cw = float(x_max - x_min) / cols, ch = float(y_max - y_min) / rows;
  std::vector<cv::KeyPoint> all, cell_kps;
  for (int r = 0; r < rows; ++r) {
    const int y0 = y_min + static_cast<int>(r * ch),
              y1 = r + 1 == rows ? y_max : y_min + static_cast<int>((r + 1) * ch);
    for (int c = 0; c < cols; ++c) {
      const int x0 = x_min + static_cast<int>(c * cw),
                x1 = c + 1 == cols ? x_max : x_min + static_cast<int>((c + 1) * cw);
      // FAST ignores 3 px at the edge of what it is given: widen the ROI by 3 so that it tests
      // exactly the cell's own pixels.
      const cv::Rect roi(x0 - 3, y0 - 3, x1 - x0 + 6, y1 - y0 + 6);
      cell_kps.clear();
      cv::FAST(image(roi), cell_kps, options_.fast_threshold, true);
      if (cell_kps.empty() && options_.fast_threshold_min < options_.fast_threshold)
        cv::FAST(image(roi), cell_kps, options_.fast_threshold_min, true);
      for (auto& kp : cell_kps) {
        kp.pt.x += roi.x;
        kp.pt.y += roi.y;
        if (kp.pt.x >= x0 && kp.pt.x < x1 && kp.pt.y >= y0 && kp.pt.y < y1) all.push_back(kp);
      }
    }
  }
  std::vector<cv::KeyPoint> kept = distributeQuadtree(all, float(x_min), float(y_min), float(x_max),
                                                      float(y_max), features_per_level_[level]);
  for (auto& kp : kept) {
    kp.octave = level;
    kp.angle = intensityCentroidAngle(image, kp.pt, umax_);
    out->push_back(kp);
  }
}

OrbFeatures OrbExtractor::extract(const cv::Mat& grey) const {
  CV_Assert(grey.type() == CV_8UC1);
  OrbFeatures result;
  const int levels = pyramid_.levels();
  std::vector<cv::Mat> images(levels);
  images[0] = grey;
  for (int l = 1; l < levels; ++l) {
    const cv::Size size(static_cast<int>(std::lround(grey.cols / pyramid_.scale[l])),
                        static_cast<int>(std::lround(grey.rows / pyramid_.scale[l])));
    if (size.width < 2 * kBorder + 8 || size.height < 2 * kBorder + 8) break;
    cv::resize(images[l - 1], images[l], size, 0, 0, cv::INTER_LINEAR);
  }
  // Levels are independent: with threads > 1 they are shared out (largest first, each to the
  // least loaded thread) and the results joined in level order, so the output does not depend
  // on the threads.
  std::vector<std::vector<cv::KeyPoint>> level_kps(levels);
  std::vector<cv::Mat> level_desc(levels);
  auto runLevels = [&](const std::vector<int>& mine) {
    for (int l : mine) describeLevel(images[l], l, &level_kps[l], &level_desc[l]);
  };
  const int threads = std::max(1, std::min(options_.threads, levels));
  std::vector<std::vector<int>> share(threads);
  std::vector<double> load(threads, 0);
  for (int l = 0; l < levels; ++l) {
    if (images[l].empty()) break;
    const int t = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    share[t].push_back(l);
    load[t] += images[l].total();
  }
  std::vector<std::thread> helpers;
  for (int t = 1; t < threads; ++t) helpers.emplace_back(runLevels, share[t]);
  runLevels(share[0]);
  for (auto& h : helpers) h.join();

  std::vector<cv::Mat> descriptors;
  for (int l = 0; l < levels; ++l) {
    if (level_kps[l].empty()) continue;
    result.keypoints.insert(result.keypoints.end(), level_kps[l].begin(), level_kps[l].end());
    descriptors.push_back(level_desc[l]);
  }
  if (!descriptors.empty())
    cv::vconcat(descriptors, result.descriptors);
  else
    result.descriptors = cv::Mat(0, kDescriptorBytes, CV_8U);
  return result;
}

void OrbExtractor::describeLevel(const cv::Mat& image, int l, std::vector<cv::KeyPoint>* out,
                                 cv::Mat* out_desc) const {
  std::vector<cv::KeyPoint>& kps = *out;
  detectLevel(image, l, &kps);
  if (kps.empty()) return;
  // Descriptors are computed on a smoothed image: BRIEF's single-pixel tests are noise-sensitive.
  cv::Mat blurred;
  cv::GaussianBlur(image, blurred, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
  cv::Mat desc(static_cast<int>(kps.size()), kDescriptorBytes, CV_8U);
  const int step = static_cast<int>(blurred.step1());
  for (size_t i = 0; i < kps.size(); ++i) {
    const double a = kps[i].angle * M_PI / 180.0;
    const float ca = static_cast<float>(std::cos(a)), sa = static_cast<float>(std::sin(a));
    const uint8_t* center = blurred.ptr<uint8_t>(cvRound(kps[i].pt.y), cvRound(kps[i].pt.x));
    auto sample = [&](int x, int y) {
      return center[cvRound(x * sa + y * ca) * step + cvRound(x * ca - y * sa)];
    };
    uint8_t* d = desc.ptr<uint8_t>(static_cast<int>(i));
    for (int byte = 0; byte < kDescriptorBytes; ++byte) {
      uint8_t value = 0;
      for (int bit = 0; bit < 8; ++bit) {
        const auto& p = pattern_[byte * 8 + bit];
        value |= static_cast<uint8_t>((sample(p[0], p[1]) < sample(p[2], p[3])) << bit);
      }
      d[byte] = value;
    }
    // Level-0 coordinates of the image this level was made from.
    kps[i].pt.x = static_cast<float>(kps[i].pt.x * pyramid_.scale[l]);
    kps[i].pt.y = static_cast<float>(kps[i].pt.y * pyramid_.scale[l]);
    kps[i].size = static_cast<float>((2 * kPatchRadius + 1) * pyramid_.scale[l]);
  }
  *out_desc = desc;
}

}  // namespace slamaware::slam
