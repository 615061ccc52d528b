#include "procs/slam/optimization/pose_optimizer.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace slamaware::slam {

namespace {

struct Accumulated {
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  double cost = 0;
};

// Robust cost, normal equations and gradient at pose T over the observations not marked outlier.
// The pose is perturbed on the left (T <- exp(xi) T, xi = (rho, phi)), so for p_c = T p_w the
// Jacobian of p_c is [I, -[p_c]x].
Accumulated accumulate(const SE3& T, const std::vector<PoseObservation>& obs, double fx, double fy,
                       double cx, double cy, bool robust, double delta, bool with_jacobians) {
  Accumulated a;
  for (const auto& o : obs) {
    if (o.outlier) continue;
    const Eigen::Vector3d pc = T * o.p_world;
    if (pc.z() <= 1e-6) {
      a.cost += delta * delta;  // behind the camera: a bounded penalty
      continue;
    }
    const double iz = 1.0 / pc.z();
    const Eigen::Vector2d r(fx * pc.x() * iz + cx - o.px.x(), fy * pc.y() * iz + cy - o.px.y());
    const double e2 = r.squaredNorm() * o.inv_sigma2;
    double w = 1.0;
    if (robust && e2 > delta * delta) {
      const double e = std::sqrt(e2);
      w = delta / e;
      a.cost += 2 * delta * e - delta * delta;
    } else {
      a.cost += e2;
    }
    if (!with_jacobians) continue;
    Eigen::Matrix<double, 2, 3> Jp;
    Jp << fx * iz, 0, -fx * pc.x() * iz * iz, 0, fy * iz, -fy * pc.y() * iz * iz;
    Eigen::Matrix<double, 3, 6> Jt;
    Jt.leftCols<3>().setIdentity();
    Jt.rightCols<3>() = -skew(pc);
    const Eigen::Matrix<double, 2, 6> J = Jp * Jt;
    const double s = w * o.inv_sigma2;
    a.H.noalias() += s * J.transpose() * J;
    a.b.noalias() += s * J.transpose() * r;
  }
  return a;
}

}  // namespace

int optimizePose(SE3* T, std::vector<PoseObservation>& obs, double fx, double fy, double cx,
                 double cy, const PoseOptimizerOptions& opt) {
  const double delta = std::sqrt(opt.chi2);
  int inliers = 0;
  for (int round = 0; round < opt.rounds; ++round) {
    const bool robust = round < opt.robust_rounds;
    double lambda = 1e-4;
    Accumulated a = accumulate(*T, obs, fx, fy, cx, cy, robust, delta, true);
    for (int it = 0; it < opt.iterations; ++it) {
      Eigen::Matrix<double, 6, 6> H = a.H;
      H.diagonal() += lambda * a.H.diagonal() + Eigen::Matrix<double, 6, 1>::Constant(1e-9);
      const Vector6d step = H.ldlt().solve(-a.b);
      if (!step.allFinite()) break;
      const SE3 candidate = expSE3(step) * (*T);
      const Accumulated c = accumulate(candidate, obs, fx, fy, cx, cy, robust, delta, true);
      if (c.cost < a.cost) {
        *T = candidate;
        a = c;
        lambda = std::max(1e-7, lambda * 0.3);
        if (step.norm() < 1e-9) break;
      } else {
        lambda *= 10;
        if (lambda > 1e4) break;
      }
    }
    // Classify every observation again, including the ones left out of this round.
    inliers = 0;
    for (auto& o : obs) {
      const Eigen::Vector3d pc = (*T) * o.p_world;
      if (pc.z() <= 1e-6) {
        o.outlier = true;
        continue;
      }
      const Eigen::Vector2d r(fx * pc.x() / pc.z() + cx - o.px.x(),
                              fy * pc.y() / pc.z() + cy - o.px.y());
      o.outlier = r.squaredNorm() * o.inv_sigma2 > opt.chi2;
      inliers += !o.outlier;
    }
    if (inliers < 10) break;
  }
  return inliers;
}

}  // namespace slamaware::slam
