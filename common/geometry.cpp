#include "common/geometry.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace slamaware {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Matrix3d expSO3(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  if (theta < 1e-12) return Eigen::Matrix3d::Identity() + skew(w);
  return Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
}

Eigen::Vector3d logSO3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

namespace {
// Left Jacobian of SO(3): V in exp(xi) = [exp(phi), V rho].
Eigen::Matrix3d leftJacobianSO3(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d W = skew(phi);
  if (theta < 1e-8) return Eigen::Matrix3d::Identity() + 0.5 * W;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1 - std::cos(theta)) / t2 * W +
         (theta - std::sin(theta)) / (t2 * theta) * W * W;
}
}  // namespace

SE3 expSE3(const Vector6d& xi) {
  const Eigen::Vector3d rho = xi.head<3>(), phi = xi.tail<3>();
  SE3 T = SE3::Identity();
  T.linear() = expSO3(phi);
  T.translation() = leftJacobianSO3(phi) * rho;
  return T;
}

Vector6d logSE3(const SE3& T) {
  const Eigen::Vector3d phi = logSO3(T.linear());
  Vector6d xi;
  xi.head<3>() = leftJacobianSO3(phi).inverse() * T.translation();
  xi.tail<3>() = phi;
  return xi;
}

SE3 makeSE3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  SE3 T = SE3::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

SE3 se3FromArrays(const double position[3], const double q[4]) {
  return makeSE3(Eigen::Quaterniond(q[0], q[1], q[2], q[3]),
                 Eigen::Vector3d(position[0], position[1], position[2]));
}

void se3ToArrays(const SE3& T, double position[3], double q_wxyz[4]) {
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;  // one canonical sign
  for (int i = 0; i < 3; ++i) position[i] = T.translation()[i];
  q_wxyz[0] = q.w();
  q_wxyz[1] = q.x();
  q_wxyz[2] = q.y();
  q_wxyz[3] = q.z();
}

double rotationAngle(const Eigen::Matrix3d& R) {
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

double angleBetween(const SE3& a, const SE3& b) {
  return rotationAngle(a.linear().transpose() * b.linear());
}

Sim3 Sim3::inverse() const {
  Sim3 inv;
  inv.s = 1.0 / s;
  inv.R = R.transpose();
  inv.t = -inv.s * (inv.R * t);
  return inv;
}

SE3 Sim3::apply(const SE3& T) const {
  SE3 out = SE3::Identity();
  out.linear() = R * T.linear();
  out.translation() = (*this) * Eigen::Vector3d(T.translation());
  return out;
}

Eigen::Matrix4d Sim3::matrix() const {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = s * R;
  M.topRightCorner<3, 1>() = t;
  return M;
}

Sim3 alignUmeyama(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                  bool with_scale) {
  Sim3 out;
  const size_t n = std::min(src.size(), dst.size());
  if (n < 3) return out;
  Eigen::Matrix3Xd A(3, n), B(3, n);
  for (size_t i = 0; i < n; ++i) {
    A.col(i) = src[i];
    B.col(i) = dst[i];
  }
  const Eigen::Matrix4d M = Eigen::umeyama(A, B, with_scale);
  if (!M.allFinite()) return out;
  const Eigen::Matrix3d sR = M.topLeftCorner<3, 3>();
  out.s = with_scale ? std::cbrt(sR.determinant()) : 1.0;
  if (!(out.s > 0)) return Sim3();
  out.R = sR / out.s;
  out.t = M.topRightCorner<3, 1>();
  return out;
}

double rectIntersection(double ax, double ay, double aw, double ah, double bx, double by, double bw,
                        double bh) {
  const double x0 = std::max(ax, bx), y0 = std::max(ay, by);
  const double x1 = std::min(ax + aw, bx + bw), y1 = std::min(ay + ah, by + bh);
  return std::max(0.0, x1 - x0) * std::max(0.0, y1 - y0);
}

double rectIou(double ax, double ay, double aw, double ah, double bx, double by, double bw,
               double bh) {
  const double inter = rectIntersection(ax, ay, aw, ah, bx, by, bw, bh);
  const double uni = aw * ah + bw * bh - inter;
  return uni > 0 ? inter / uni : 0.0;
}

}  // namespace slamaware
