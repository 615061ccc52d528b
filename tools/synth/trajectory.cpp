#include "tools/synth/trajectory.h"

#include <cmath>

namespace slamaware::synth {

namespace {
constexpr double kTwoPi = 6.283185307179586;
constexpr double kDeg = 3.141592653589793 / 180.0;
}  // namespace

std::vector<Trajectory::Wave> Trajectory::waves(Rng& rng, int n, double f_lo, double f_hi) {
  std::vector<Wave> w;
  double total = 0;
  for (int i = 0; i < n; ++i) {
    w.push_back({rng.uniform(0.3, 1.0), rng.uniform(f_lo, f_hi), rng.uniform(0, kTwoPi)});
    total += w.back().amp;
  }
  for (auto& x : w) x.amp /= total;
  return w;
}

double Trajectory::eval(const std::vector<Wave>& w, double t) {
  double s = 0;
  for (const auto& x : w) s += x.amp * std::sin(kTwoPi * x.freq_hz * t + x.phase);
  return s;
}

Trajectory::Trajectory(const TrajectoryOptions& o, const Eigen::Vector3d& centre, double duration_s,
                       Rng rng)
    : o_(o), centre_(centre) {
  theta0_ = rng.uniform(0, kTwoPi);
  dir_ = o.direction != 0 ? (o.direction > 0 ? 1.0 : -1.0) : (rng.chance(0.5) ? 1.0 : -1.0);
  speed_ = waves(rng, 3, 0.04, 0.25);
  radius_ = waves(rng, 3, 0.02, 0.12);
  height_ = waves(rng, 3, 0.02, 0.15);
  look_x_ = waves(rng, 3, 0.05, 0.3);
  look_y_ = waves(rng, 3, 0.05, 0.3);
  look_z_ = waves(rng, 2, 0.05, 0.2);
  shake_x_ = waves(rng, 3, 0.8, 3.0);
  shake_y_ = waves(rng, 3, 0.8, 3.0);
  shake_z_ = waves(rng, 3, 0.8, 3.0);
  roll_ = waves(rng, 2, 0.03, 0.15);
  // Scale the angle so that the whole sequence travels arc_deg.
  k_ = 1.0;
  const double end = angle(duration_s) - angle(0);
  k_ = std::fabs(end) > 1e-9 ? o.arc_deg * kDeg / end : 0.0;
}

// Integral of the angular speed 1 + v * s(t): t - v * sum(a / (2 pi f) cos(2 pi f t + p)).
double Trajectory::angle(double t) const {
  double s = t;
  for (const auto& w : speed_)
    s -= o_.speed_variation * w.amp / (kTwoPi * w.freq_hz) *
         std::cos(kTwoPi * w.freq_hz * t + w.phase);
  return k_ * s;
}

Eigen::Vector3d Trajectory::position(double t) const {
  const double th = theta0_ + dir_ * (angle(t) - angle(0));
  const double r = 0.5 * (o_.radius_min + o_.radius_max) +
                   0.5 * (o_.radius_max - o_.radius_min) * eval(radius_, t);
  const double h = 0.5 * (o_.height_min + o_.height_max) +
                   0.5 * (o_.height_max - o_.height_min) * eval(height_, t);
  return centre_ + Eigen::Vector3d(r * std::cos(th), r * std::sin(th), h);
}

Eigen::Isometry3d Trajectory::pose(double t) const {
  const Eigen::Vector3d p = position(t);
  const Eigen::Vector3d target =
      centre_ +
      o_.look_jitter * Eigen::Vector3d(eval(look_x_, t), eval(look_y_, t), 0.5 * eval(look_z_, t));
  const Eigen::Vector3d z = (target - p).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  const double s = o_.shake_deg * kDeg;
  const Eigen::Matrix3d jitter =
      (Eigen::AngleAxisd(o_.roll_deg * kDeg * eval(roll_, t) + s * eval(shake_z_, t),
                         Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(s * eval(shake_x_, t), Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(s * eval(shake_y_, t), Eigen::Vector3d::UnitY()))
          .toRotationMatrix();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R * jitter;
  T.translation() = p;
  return T;
}

}  // namespace slamaware::synth
