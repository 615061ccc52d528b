#include "procs/slam/geometry/pnp.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <random>

#include "procs/slam/optimization/pose_optimizer.h"

namespace slamaware::slam {

namespace {

int countInliers(const SE3& T, const std::vector<Eigen::Vector3d>& pw,
                 const std::vector<Eigen::Vector2d>& px, const std::vector<double>& sigma2,
                 double fx, double fy, double cx, double cy, double chi2,
                 std::vector<bool>* inliers) {
  int n = 0;
  inliers->assign(pw.size(), false);
  for (size_t i = 0; i < pw.size(); ++i) {
    const Eigen::Vector3d pc = T * pw[i];
    if (pc.z() <= 0) continue;
    const Eigen::Vector2d r(fx * pc.x() / pc.z() + cx - px[i].x(),
                            fy * pc.y() / pc.z() + cy - px[i].y());
    if (r.squaredNorm() / sigma2[i] < chi2) {
      (*inliers)[i] = true;
      ++n;
    }
  }
  return n;
}

}  // namespace

PnpResult solvePnpRansac(const std::vector<Eigen::Vector3d>& pw,
                         const std::vector<Eigen::Vector2d>& px, const std::vector<double>& sigma2,
                         double fx, double fy, double cx, double cy, const PnpOptions& opt,
                         uint64_t seed) {
  PnpResult result;
  const int n = static_cast<int>(pw.size());
  if (n < 4 || static_cast<int>(px.size()) != n || static_cast<int>(sigma2.size()) != n)
    return result;
  const cv::Matx33d K(fx, 0, cx, 0, fy, cy, 0, 0, 1);
  std::mt19937_64 rng(seed);
  std::vector<int> idx(n);
  std::vector<bool> inl;
  int best = -1;
  SE3 best_T = SE3::Identity();
  int needed = opt.iterations;
  for (int it = 0; it < needed && it < opt.iterations; ++it) {
    for (int i = 0; i < n; ++i) idx[i] = i;
    std::vector<cv::Point3d> obj(4);
    std::vector<cv::Point2d> img(4);
    for (int k = 0; k < 4; ++k) {
      const int j = k + static_cast<int>(rng() % static_cast<uint64_t>(n - k));
      std::swap(idx[k], idx[j]);
      obj[k] = cv::Point3d(pw[idx[k]].x(), pw[idx[k]].y(), pw[idx[k]].z());
      img[k] = cv::Point2d(px[idx[k]].x(), px[idx[k]].y());
    }
    cv::Vec3d rvec, tvec;
    bool solved = false;
    try {
      solved = cv::solvePnP(obj, img, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_AP3P);
    } catch (const cv::Exception&) {
      solved = false;
    }
    if (!solved || !std::isfinite(tvec[0])) continue;
    SE3 T = SE3::Identity();
    T.linear() = expSO3(Eigen::Vector3d(rvec[0], rvec[1], rvec[2]));
    T.translation() = Eigen::Vector3d(tvec[0], tvec[1], tvec[2]);
    const int count = countInliers(T, pw, px, sigma2, fx, fy, cx, cy, opt.chi2, &inl);
    if (count > best) {
      best = count;
      best_T = T;
      // Iterations for 99% confidence of one all-inlier sample at this inlier ratio.
      const double w = double(count) / n;
      const double denom = std::log(std::max(1e-12, 1.0 - std::pow(w, 4)));
      if (denom < 0)
        needed = std::min(opt.iterations, static_cast<int>(std::ceil(std::log(0.01) / denom)) + 1);
    }
  }
  if (best < opt.min_inliers) return result;
  // Refine on all correspondences: the optimiser's outlier rounds start from the RANSAC inliers.
  std::vector<PoseObservation> obs(n);
  countInliers(best_T, pw, px, sigma2, fx, fy, cx, cy, opt.chi2, &inl);
  for (int i = 0; i < n; ++i) obs[i] = {pw[i], px[i], 1.0 / sigma2[i], !inl[i]};
  SE3 T = best_T;
  PoseOptimizerOptions po;
  po.chi2 = opt.chi2;
  const int refined = optimizePose(&T, obs, fx, fy, cx, cy, po);
  if (refined >= best) best_T = T;
  result.num_inliers =
      countInliers(best_T, pw, px, sigma2, fx, fy, cx, cy, opt.chi2, &result.inliers);
  result.T_camera_world = best_T;
  result.ok = result.num_inliers >= opt.min_inliers;
  return result;
}

}  // namespace slamaware::slam
