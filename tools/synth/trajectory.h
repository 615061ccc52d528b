#pragma once
// A hand-held camera circling a table: the angle around the table advances with a smoothly
// varying speed, the distance and the height drift slowly within their ranges, the point looked
// at wanders around the table centre, and a small tremor and roll are added. Every component is
// a sum of sinusoids, so the path is smooth (no jumps) and defined at any time t, which gives
// exact poses for motion blur too.
#include <Eigen/Geometry>
#include <vector>

#include "tools/synth/rng.h"
#include "tools/synth/synth_options.h"

namespace slamaware::synth {

class Trajectory {
 public:
  /// `centre`: the table-top centre looked at (world); `duration_s`: the sequence length.
  Trajectory(const TrajectoryOptions& options, const Eigen::Vector3d& centre, double duration_s,
             Rng rng);

  /// T_world_camera at time t (s); camera frame x right, y down, z forward.
  Eigen::Isometry3d pose(double t) const;
  /// Camera centre at time t.
  Eigen::Vector3d position(double t) const;

 private:
  struct Wave {
    double amp, freq_hz, phase;
  };
  // A smooth signal in [-1, 1]: a normalised sum of waves.
  static std::vector<Wave> waves(Rng& rng, int n, double f_lo, double f_hi);
  static double eval(const std::vector<Wave>& w, double t);
  double angle(double t) const;

  TrajectoryOptions o_;
  Eigen::Vector3d centre_;
  double theta0_ = 0, dir_ = 1, k_ = 1;
  std::vector<Wave> speed_, radius_, height_, look_x_, look_y_, look_z_, shake_x_, shake_y_,
      shake_z_, roll_;
};

}  // namespace slamaware::synth
