#include "procs/slam/geometry/triangulation.h"

#include <Eigen/SVD>
#include <cmath>

namespace slamaware::slam {

bool triangulateDlt(const SE3& T1, const SE3& T2, const Eigen::Vector3d& ray1,
                    const Eigen::Vector3d& ray2, Eigen::Vector3d* p_world) {
  const Eigen::Matrix<double, 3, 4> P1 = T1.matrix().topRows<3>(), P2 = T2.matrix().topRows<3>();
  Eigen::Matrix4d A;
  A.row(0) = ray1.x() * P1.row(2) - P1.row(0);
  A.row(1) = ray1.y() * P1.row(2) - P1.row(1);
  A.row(2) = ray2.x() * P2.row(2) - P2.row(0);
  A.row(3) = ray2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (std::abs(X(3)) < 1e-12) return false;
  *p_world = X.head<3>() / X(3);
  return p_world->allFinite();
}

double parallaxCos(const Eigen::Vector3d& p, const Eigen::Vector3d& c1, const Eigen::Vector3d& c2) {
  const Eigen::Vector3d a = p - c1, b = p - c2;
  const double n = a.norm() * b.norm();
  return n > 0 ? a.dot(b) / n : 1.0;
}

}  // namespace slamaware::slam
