#include "procs/slam/optimization/bundle_adjustment.h"

#include <ceres/ceres.h>
#include <ceres/product_manifold.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

namespace slamaware::slam {

namespace {

// Cost of one observation: reprojectionResidual with its derivatives. Blocks: the camera's pose
// (7: the quaternion's x, y, z, w, on Ceres' EigenQuaternionManifold, then the translation) and the
// point (3). One pose block rather than two: the Schur elimination then works on 6 x 6 cells, a
// quarter as many as with separate 3-dof rotation and translation blocks, each locked on its own.
class ReprojectionCost : public ceres::SizedCostFunction<2, 7, 3> {
 public:
  ReprojectionCost(const BaProblem& problem, const BaObservation& obs)
      : problem_(problem), obs_(obs) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    double* j_pose = jacobians ? jacobians[0] : nullptr;
    double jq[8], jt[6];
    const double* pose = parameters[0];
    reprojectionResidual(problem_, obs_, pose, pose + 4, parameters[1], residuals,
                         j_pose ? jq : nullptr, j_pose ? jt : nullptr,
                         jacobians ? jacobians[1] : nullptr);
    if (j_pose) {
      for (int row = 0; row < 2; ++row) {
        std::copy(jq + 4 * row, jq + 4 * row + 4, j_pose + 7 * row);
        std::copy(jt + 3 * row, jt + 3 * row + 3, j_pose + 7 * row + 4);
      }
    }
    return true;
  }

 private:
  const BaProblem& problem_;
  BaObservation obs_;
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

void reprojectionResidual(const BaProblem& problem, const BaObservation& obs, const double* q,
                          const double* t, const double* p, double residual[2], double* jq,
                          double* jt, double* jp) {
  // R p as Eigen rotates by a quaternion: p + w uv + v x uv, uv = 2 v x p (exact for |q| = 1; its
  // derivatives below are those of this expression, as automatic differentiation would take them).
  const Eigen::Map<const Eigen::Vector3d> v(q), translation(t), point(p);
  const double w = q[3];
  const Eigen::Vector3d uv = 2.0 * v.cross(point);
  const Eigen::Vector3d pc = point + w * uv + v.cross(uv) + translation;
  const bool in_front = pc.z() > 1e-6;
  const double z = in_front ? pc.z() : 1e-6;
  const double s = std::sqrt(obs.inv_sigma2);
  residual[0] = s * (problem.fx * pc.x() / z + problem.cx - obs.px.x());
  residual[1] = s * (problem.fy * pc.y() / z + problem.cy - obs.px.y());
  if (!jq && !jt && !jp) return;
  // d residual / d pc (the clamped depth is a constant).
  Eigen::Matrix<double, 2, 3> d_pc;
  d_pc << s * problem.fx / z, 0, in_front ? -s * problem.fx * pc.x() / (z * z) : 0,  //
      0, s * problem.fy / z, in_front ? -s * problem.fy * pc.y() / (z * z) : 0;
  using RowMajor23 = Eigen::Matrix<double, 2, 3, Eigen::RowMajor>;
  if (jt) RowMajor23::Map(jt) = d_pc;
  auto cross = [](const Eigen::Vector3d& a) {
    Eigen::Matrix3d m;
    m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    return m;
  };
  if (jp) {
    const Eigen::Matrix3d vx = cross(v);
    RowMajor23::Map(jp) = d_pc * (Eigen::Matrix3d::Identity() + 2.0 * w * vx + 2.0 * vx * vx);
  }
  if (jq) {
    Eigen::Matrix<double, 3, 4> d_q;
    d_q.leftCols<3>() =
        -2.0 * w * cross(point) + 2.0 * (v.dot(point) * Eigen::Matrix3d::Identity() +
                                         v * point.transpose() - 2.0 * point * v.transpose());
    d_q.col(3) = uv;
    Eigen::Matrix<double, 2, 4, Eigen::RowMajor>::Map(jq) = d_pc * d_q;
  }
}

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
  // A camera's pose as one block, the cameras in their order: the Schur ordering below keeps
  // blocks of a group in the order of their addresses, which is then the same in every run.
  std::vector<std::array<double, 7>> cam(nc);
  for (size_t i = 0; i < nc; ++i) {
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(problem->cameras[i].T_camera_world.linear()).normalized();
    Eigen::Map<Eigen::Vector4d>(cam[i].data()) = q.coeffs();
    Eigen::Map<Eigen::Vector3d>(cam[i].data() + 4) =
        problem->cameras[i].T_camera_world.translation();
  }
  std::vector<Eigen::Vector3d> p(np);
  for (size_t i = 0; i < np; ++i) p[i] = problem->points[i].p_world;

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>> pose_manifold;
  ceres::HuberLoss huber(std::sqrt(options.huber_chi2));
  std::vector<bool> camera_used(nc, false), point_used(np, false);
  for (const auto& o : problem->observations) {
    if (!o.enabled) continue;
    ceres_problem.AddResidualBlock(new ReprojectionCost(*problem, o),
                                   options.robust ? &huber : nullptr, cam[o.camera].data(),
                                   p[o.point].data());
    camera_used[o.camera] = true;
    point_used[o.point] = true;
  }
  if (ceres_problem.NumResidualBlocks() == 0) return summary;
  for (size_t i = 0; i < nc; ++i) {
    if (!camera_used[i]) continue;
    ceres_problem.SetManifold(cam[i].data(), &pose_manifold);
    if (problem->cameras[i].fixed) ceres_problem.SetParameterBlockConstant(cam[i].data());
  }
  for (size_t i = 0; i < np; ++i)
    if (point_used[i] && problem->points[i].fixed)
      ceres_problem.SetParameterBlockConstant(p[i].data());

  ceres::Solver::Options solver;
  // Points are eliminated first, leaving a system over the free cameras (at most 6 x
  // ba_local_keyframes unknowns): small enough to be solved dense, without a sparse ordering. The
  // elimination order is given, not searched for (7 % of the solver's time went to finding it).
  solver.linear_solver_type = ceres::DENSE_SCHUR;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (size_t i = 0; i < np; ++i)
    if (point_used[i]) ordering->AddElementToGroup(p[i].data(), 0);
  for (size_t i = 0; i < nc; ++i) {
    if (!camera_used[i]) continue;
    ordering->AddElementToGroup(cam[i].data(), 1);
  }
  solver.linear_solver_ordering = ordering;
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
  for (size_t i = 0; i < nc && finite; ++i)
    finite = Eigen::Map<const Eigen::Matrix<double, 7, 1>>(cam[i].data()).allFinite();
  for (size_t i = 0; i < np && finite; ++i) finite = p[i].allFinite();
  if (!finite) return summary;  // keep the input estimates
  for (size_t i = 0; i < nc; ++i) {
    if (problem->cameras[i].fixed || !camera_used[i]) continue;
    problem->cameras[i].T_camera_world.linear() =
        Eigen::Quaterniond(cam[i].data()).normalized().toRotationMatrix();
    problem->cameras[i].T_camera_world.translation() = Eigen::Vector3d(cam[i].data() + 4);
  }
  for (size_t i = 0; i < np; ++i)
    if (!problem->points[i].fixed && point_used[i]) problem->points[i].p_world = p[i];
  summary.usable = true;
  summary.final_rms_px = rms(*problem);
  return summary;
}

}  // namespace slamaware::slam
