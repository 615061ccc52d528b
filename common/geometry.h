#pragma once
// Rigid (SE(3)) and similarity (Sim(3)) transforms on Eigen. Names carry frames:
// T_world_camera maps camera coordinates into the world frame (p_world = T_world_camera *
// p_camera). And the overlap of two image boxes.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace slamaware {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using SE3 = Eigen::Isometry3d;

/// Cross-product matrix: skew(a) * b == a.cross(b).
Eigen::Matrix3d skew(const Eigen::Vector3d& v);
/// Rotation of the rotation vector w (angle |w| about w / |w|), and its inverse.
Eigen::Matrix3d expSO3(const Eigen::Vector3d& w);
Eigen::Vector3d logSO3(const Eigen::Matrix3d& R);
/// SE(3) exponential of xi = (rho, phi): translation part first, rotation part last.
SE3 expSE3(const Vector6d& xi);
Vector6d logSE3(const SE3& T);

SE3 makeSE3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t);
/// From the message layout: position[3], orientation[4] as w, x, y, z.
SE3 se3FromArrays(const double position[3], const double orientation_wxyz[4]);
void se3ToArrays(const SE3& T, double position[3], double orientation_wxyz[4]);
/// Rotation angle (rad) and translation distance between two poses.
double rotationAngle(const Eigen::Matrix3d& R);
double angleBetween(const SE3& a, const SE3& b);

/// A similarity transform p' = s R p + t.
struct Sim3 {
  double s = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return s * (R * p) + t; }
  Sim3 operator*(const Sim3& o) const { return {s * o.s, R * o.R, s * (R * o.t) + t}; }
  Sim3 inverse() const;
  /// Applied to a camera pose: the camera centre is transformed, the orientation rotated.
  SE3 apply(const SE3& T_world_camera) const;
  Eigen::Matrix4d matrix() const;
};

/// Least-squares transform (Umeyama 1991) mapping src[i] onto dst[i]; with_scale = false gives
/// SE(3). Needs at least 3 non-collinear pairs; returns identity otherwise.
Sim3 alignUmeyama(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                  bool with_scale);

/// The area two axis-aligned boxes, given by their top-left corner and size, have in common (0 when
/// they do not overlap).
double rectIntersection(double ax, double ay, double aw, double ah, double bx, double by, double bw,
                        double bh);

/// Intersection over union of two axis-aligned boxes given by their top-left corner and size
/// (px); 0 when neither has an area.
double rectIou(double ax, double ay, double aw, double ah, double bx, double by, double bw,
               double bh);

}  // namespace slamaware
