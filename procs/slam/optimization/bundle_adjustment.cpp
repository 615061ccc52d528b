#include "procs/slam/optimization/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <cmath>

namespace slamaware::slam {

namespace {

// Residual of one observation: sqrt(information) * (projection - pixel). Camera parameters are an
// Eigen quaternion (x, y, z, w) and a translation of T_camera_world.
struct ReprojectionError {
  ReprojectionError(const Eigen::Vector2d& px, double sqrt_info, double fx, double fy, double cx,
                    double cy)
      : px_(px), s_(sqrt_info), fx_(fx), fy_(fy), cx_(cx), cy_(cy) {}

  template <class T>
  bool operator()(const T* q, const T* t, const T* p, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> translation(t), point(p);
    const Eigen::Matrix<T, 3, 1> pc = rotation * point + translation;
    // A point at or behind the camera gets a large (bounded) residual instead of a division by ~0.
    const T z = pc.z() > T(1e-6) ? pc.z() : T(1e-6);
    residual[0] = T(s_) * (T(fx_) * pc.x() / z + T(cx_) - T(px_.x()));
    residual[1] = T(s_) * (T(fy_) * pc.y() / z + T(cy_) - T(px_.y()));
    return true;
  }

 private:
  Eigen::Vector2d px_;
  double s_, fx_, fy_, cx_, cy_;
};

class AbortCallback : public ceres::IterationCallback {
 public:
  explicit AbortCallback(const std::atomic<bool>* abort) : abort_(abort) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return abort_ && abort_->load() ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::atomic<bool>* abort_;
};

double rms(const BaProblem& problem) {
  double sum = 0;
  int n = 0;
  for (const auto& o : problem.observations) {
    if (!o.enabled) continue;
    bool front = true;
    sum += observationChi2(problem, o, &front);
    ++n;
  }
  return n ? std::sqrt(sum / n) : 0;
}

}  // namespace

double observationChi2(const BaProblem& problem, const BaObservation& o, bool* in_front) {
  const Eigen::Vector3d pc =
      problem.cameras[o.camera].T_camera_world * problem.points[o.point].p_world;
  *in_front = pc.z() > 0;
  if (!*in_front) return 1e9;
  const Eigen::Vector2d r(problem.fx * pc.x() / pc.z() + problem.cx - o.px.x(),
                          problem.fy * pc.y() / pc.z() + problem.cy - o.px.y());
  return r.squaredNorm() * o.inv_sigma2;
}

BaSummary bundleAdjust(BaProblem* problem, const BaOptions& options) {
  BaSummary summary;
  summary.initial_rms_px = rms(*problem);
  const size_t nc = problem->cameras.size(), np = problem->points.size();
  std::vector<Eigen::Quaterniond> q(nc);
  std::vector<Eigen::Vector3d> t(nc);
  for (size_t i = 0; i < nc; ++i) {
    q[i] = Eigen::Quaterniond(problem->cameras[i].T_camera_world.linear()).normalized();
    t[i] = problem->cameras[i].T_camera_world.translation();
  }
  std::vector<Eigen::Vector3d> p(np);
  for (size_t i = 0; i < np; ++i) p[i] = problem->points[i].p_world;

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  ceres::EigenQuaternionManifold quaternion_manifold;
  ceres::HuberLoss huber(std::sqrt(options.huber_chi2));
  std::vector<bool> camera_used(nc, false), point_used(np, false);
  for (const auto& o : problem->observations) {
    if (!o.enabled) continue;
    auto* cost =
        new ceres::AutoDiffCostFunction<ReprojectionError, 2, 4, 3, 3>(new ReprojectionError(
            o.px, std::sqrt(o.inv_sigma2), problem->fx, problem->fy, problem->cx, problem->cy));
    ceres_problem.AddResidualBlock(cost, options.robust ? &huber : nullptr,
                                   q[o.camera].coeffs().data(), t[o.camera].data(),
                                   p[o.point].data());
    camera_used[o.camera] = true;
    point_used[o.point] = true;
  }
  if (ceres_problem.NumResidualBlocks() == 0) return summary;
  for (size_t i = 0; i < nc; ++i) {
    if (!camera_used[i]) continue;
    ceres_problem.SetManifold(q[i].coeffs().data(), &quaternion_manifold);
    if (problem->cameras[i].fixed) {
      ceres_problem.SetParameterBlockConstant(q[i].coeffs().data());
      ceres_problem.SetParameterBlockConstant(t[i].data());
    }
  }
  for (size_t i = 0; i < np; ++i)
    if (point_used[i] && problem->points[i].fixed)
      ceres_problem.SetParameterBlockConstant(p[i].data());

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::SPARSE_SCHUR;
  solver.max_num_iterations = options.iterations;
  solver.num_threads =
      1;  // one thread: results do not depend on scheduling, and mapping shares 2 cores
  solver.minimizer_progress_to_stdout = false;
  solver.logging_type = ceres::SILENT;
  AbortCallback callback(options.abort);
  if (options.abort) solver.callbacks.push_back(&callback);
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver, &ceres_problem, &ceres_summary);
  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.aborted = options.abort && options.abort->load();

  bool finite = true;
  for (size_t i = 0; i < nc && finite; ++i) finite = q[i].coeffs().allFinite() && t[i].allFinite();
  for (size_t i = 0; i < np && finite; ++i) finite = p[i].allFinite();
  if (!finite) return summary;  // keep the input estimates
  for (size_t i = 0; i < nc; ++i) {
    if (problem->cameras[i].fixed || !camera_used[i]) continue;
    problem->cameras[i].T_camera_world.linear() = q[i].normalized().toRotationMatrix();
    problem->cameras[i].T_camera_world.translation() = t[i];
  }
  for (size_t i = 0; i < np; ++i)
    if (!problem->points[i].fixed && point_used[i]) problem->points[i].p_world = p[i];
  summary.usable = true;
  summary.final_rms_px = rms(*problem);
  return summary;
}

}  // namespace slamaware::slam
