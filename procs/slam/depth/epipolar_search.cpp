#include "procs/slam/depth/epipolar_search.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace slamaware::slam {

namespace {

constexpr int kHalf = 2;  // samples each side of the centre
constexpr int kSamples = 2 * kHalf + 1;

// Bilinear sample of an 8-bit image; false outside [0, w-1) x [0, h-1).
inline bool sample(const cv::Mat& img, float x, float y, float* value) {
  if (!(x >= 0.f && y >= 0.f && x < img.cols - 1.f && y < img.rows - 1.f)) return false;
  const int ix = static_cast<int>(x), iy = static_cast<int>(y);
  const float dx = x - ix, dy = y - iy;
  const uint8_t* r0 = img.ptr<uint8_t>(iy) + ix;
  const uint8_t* r1 = r0 + img.step[0];
  *value = (1 - dy) * ((1 - dx) * r0[0] + dx * r0[1]) + dy * ((1 - dx) * r1[0] + dx * r1[1]);
  return true;
}

// The host's patch along its epipolar line, `scale` host pixels per frame pixel, less its mean;
// false when it leaves the image or has too little gradient along the line to match.
bool referencePatch(const cv::Mat& host, const Eigen::Vector2f& u, const Eigen::Vector2f& dir_host,
                    float scale, float min_gradient, float ref[kSamples]) {
  for (int k = 0; k < kSamples; ++k) {
    const Eigen::Vector2f s = u + (float(k - kHalf) / scale) * dir_host;
    if (!sample(host, s.x(), s.y(), &ref[k])) return false;
  }
  float grad2 = 0, ref_mean = 0;
  for (int k = 0; k < kSamples; ++k) ref_mean += ref[k];
  ref_mean /= kSamples;
  for (int k = 0; k + 1 < kSamples; ++k) grad2 += (ref[k + 1] - ref[k]) * (ref[k + 1] - ref[k]);
  if (grad2 < (kSamples - 1) * min_gradient * min_gradient) return false;
  for (int k = 0; k < kSamples; ++k) ref[k] -= ref_mean;
  return true;
}

// cost[c] = the SSD of the `ref` patch (zero mean) and x[c .. c + kSamples) less its mean, for
// c < count. A loop without branches that the compiler vectorises; each position's sums run in
// the order of one position at a time, so the costs have the same bits as computed one by one
// (the same fused multiply-adds too). Not inlined: GCC judged the loop cold inside
// searchEpipolar and left it scalar.
[[gnu::noinline]] void windowCosts(const float* x, const float ref[kSamples], int count,
                                   float* cost) {
  for (int c = 0; c < count; ++c) {
    float mean = 0;
    for (int k = 0; k < kSamples; ++k) mean += x[c + k];
    mean /= kSamples;
    float ssd = 0;
    for (int k = 0; k < kSamples; ++k) {
      const float d = x[c + k] - mean - ref[k];
      ssd += d * d;
    }
    cost[c] = ssd;
  }
}

// Sub-pixel position of the best cost: the vertex of the parabola through its neighbours.
float subPixelOffset(const float* costs, int best, int steps) {
  const float inf = std::numeric_limits<float>::max();
  if (best <= 0 || best >= steps || !(costs[best - 1] < inf) || !(costs[best + 1] < inf)) return 0;
  const float a = costs[best - 1], b = costs[best], cc = costs[best + 1];
  const float denom = a - 2 * b + cc;
  return denom > 1e-6f ? std::clamp(0.5f * (a - cc) / denom, -0.5f, 0.5f) : 0.f;
}

}  // namespace

EpipolarMatch searchEpipolar(const cv::Mat& host, const cv::Mat& frame, const Eigen::Matrix3f& R,
                             const Eigen::Vector3f& t, const DepthSeed& seed,
                             const EpipolarSearchParams& p) {
  EpipolarMatch m;
  auto project = [&](const Eigen::Vector3f& q) {
    return Eigen::Vector2f(p.fx * q.x() / q.z() + p.cx, p.fy * q.y() / q.z() + p.cy);
  };
  const float sigma = std::sqrt(seed.sigma2);
  const float rho_near = seed.mu + 2 * sigma;
  const float rho_far = std::max(seed.mu - 2 * sigma, 1e-3f * seed.z_range);
  const Eigen::Vector3f q_near = R * (seed.f / rho_near) + t, q_far = R * (seed.f / rho_far) + t;
  const Eigen::Vector3f q_mean = R * (seed.f / seed.mu) + t;
  if (q_near.z() < 1e-4f || q_far.z() < 1e-4f || q_mean.z() < 1e-4f) return m;
  const Eigen::Vector2f px_near = project(q_near), px_far = project(q_far),
                        px_mean = project(q_mean);
  const float length = (px_near - px_far).norm();
  if (length > p.max_search_px) return m;
  // Direction of increasing inverse depth in the frame (defined even for a tiny segment).
  const Eigen::Vector3f q_nearer = R * (seed.f / (seed.mu * 1.01f)) + t;
  Eigen::Vector2f dir = project(q_nearer) - px_mean;
  if (q_nearer.z() < 1e-4f || dir.norm() < 1e-6f) return m;  // no baseline along this ray
  dir.normalize();

  // The host image's epipolar direction: points X + e c (c = the frame's centre in the host
  // frame) stay in the epipolar plane, so their pixels stay on the host's epipolar line.
  const Eigen::Vector3f X = seed.f / seed.mu;
  const Eigen::Vector3f c = -(R.transpose() * t);
  const Eigen::Vector3f X2 = X + 0.01f * X.norm() * c.normalized();
  if (X2.z() < 1e-4f) return m;
  const Eigen::Vector2f u(seed.u, seed.v);
  Eigen::Vector2f dir_host = project(X2) - u;
  if (dir_host.norm() < 1e-6f) return m;
  dir_host.normalize();
  // Frame pixels per host pixel along the lines, and the sign that aligns the two directions.
  const Eigen::Vector3f X3((u.x() + dir_host.x() - p.cx) / p.fx * X.z(),
                           (u.y() + dir_host.y() - p.cy) / p.fy * X.z(), X.z());
  const Eigen::Vector3f q3 = R * X3 + t;
  if (q3.z() < 1e-4f) return m;
  float scale = (project(q3) - px_mean).dot(dir);
  if (scale < 0) {
    scale = -scale;
    dir_host = -dir_host;
  }
  if (scale < 0.3f || scale > 3.f) return m;  // strong foreshortening: the patch would not match

  float ref[kSamples];
  if (!referencePatch(host, u, dir_host, scale, p.min_epipolar_gradient, ref)) return m;

  // Samples along the segment at one-pixel steps, from the far end (plus the margins).
  const int steps = static_cast<int>(std::ceil(length));
  const int n = steps + 1 + 2 * kHalf;
  // Scratch buffers reused across calls (one set per thread).
  thread_local std::vector<float> cur_buf, costs;
  thread_local std::vector<uint8_t> ok_buf;
  if (static_cast<int>(cur_buf.size()) < n) {
    cur_buf.resize(n);
    costs.resize(n);
    ok_buf.resize(n);
  }
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2f s = px_far + float(k - kHalf) * dir;
    ok_buf[k] = sample(frame, s.x(), s.y(), &cur_buf[k]);
  }
  // The costs of all positions first (a sample outside the frame holds an earlier call's value, a
  // finite grey level), then those positions set aside.
  windowCosts(cur_buf.data(), ref, steps + 1, costs.data());
  const float inf = std::numeric_limits<float>::max();
  int best = -1;
  float best_cost = inf;
  int outside = 0;  // samples outside the frame among the window's five
  for (int k = 0; k < kSamples - 1; ++k) outside += !ok_buf[k];
  for (int c = 0; c <= steps; ++c) {
    outside += !ok_buf[c + kSamples - 1];
    if (outside > 0) costs[c] = inf;
    outside -= !ok_buf[c];
    if (costs[c] < best_cost) {
      best_cost = costs[c];
      best = c;
    }
  }
  if (best < 0) return m;  // the whole segment is outside the frame
  m.result = EpipolarMatch::kNoMatch;
  if (best_cost > p.max_ssd_per_sample * kSamples) return m;
  // The best cost away from the best position and its neighbours (by value: std::min's reference
  // kept `second` in memory, a chain of loads and stores through the stack).
  float second = inf;
  for (int c = 0; c < best - 1; ++c) second = costs[c] < second ? costs[c] : second;
  for (int c = best + 2; c <= steps; ++c) second = costs[c] < second ? costs[c] : second;
  if (second < inf && best_cost > p.uniqueness_ratio * second) return m;

  const Eigen::Vector2f px =
      px_far + (float(best) + subPixelOffset(costs.data(), best, steps)) * dir;
  // Triangulation along the host ray: z_h R f + t = z_c f_cur, least squares in (z_h, z_c).
  const Eigen::Vector3f f_cur =
      Eigen::Vector3f((px.x() - p.cx) / p.fx, (px.y() - p.cy) / p.fy, 1.f).normalized();
  Eigen::Matrix<float, 3, 2> A;
  A.col(0) = R * seed.f;
  A.col(1) = f_cur;
  const Eigen::Matrix2f AtA = A.transpose() * A;
  if (AtA.determinant() < 1e-6f) return m;
  const Eigen::Vector2f z = -AtA.inverse() * A.transpose() * t;
  if (!(z.x() > 0) || !std::isfinite(z.x())) return m;
  m.result = EpipolarMatch::kFound;
  m.distance = z.x();
  m.px = px;
  return m;
}

}  // namespace slamaware::slam
