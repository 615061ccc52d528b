#include "common/tum.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace slamaware {

std::vector<TimedPose> readTum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw TumError(path + ": cannot open trajectory file");
  std::vector<TimedPose> out;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream s(line);
    double v[8];
    for (double& x : v) {
      if (!(s >> x) || !std::isfinite(x))
        throw TumError(path + ":" + std::to_string(line_no) +
                       ": expected 8 numbers 't tx ty tz qx qy qz qw', got '" + line + "'");
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::abs(q.norm() - 1.0) > 1e-2)
      throw TumError(path + ":" + std::to_string(line_no) + ": quaternion is not of unit length");
    out.push_back({v[0], makeSE3(q, Eigen::Vector3d(v[1], v[2], v[3]))});
  }
  return out;
}

void writeTum(const std::string& path, const std::vector<TimedPose>& poses) {
  std::ofstream out(path);
  if (!out) throw TumError(path + ": cannot write trajectory file");
  out << "# timestamp tx ty tz qx qy qz qw  (T_world_camera; camera x right, y down, z forward)\n";
  char buf[256];
  for (const auto& p : poses) {
    Eigen::Quaterniond q(p.T_world_camera.linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() *= -1;
    const Eigen::Vector3d t = p.T_world_camera.translation();
    std::snprintf(buf, sizeof(buf), "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", p.t, t.x(), t.y(),
                  t.z(), q.x(), q.y(), q.z(), q.w());
    out << buf;
  }
  if (!out) throw TumError(path + ": write failed");
}

const TimedPose* closestPose(const std::vector<TimedPose>& poses, double t, double max_dt) {
  auto it = std::lower_bound(poses.begin(), poses.end(), t,
                             [](const TimedPose& p, double time) { return p.t < time; });
  const TimedPose* best = nullptr;
  double best_dt = max_dt;
  for (auto c : {it, it == poses.begin() ? it : it - 1}) {
    if (c == poses.end()) continue;
    const double dt = std::abs(c->t - t);
    if (dt <= best_dt) {
      best_dt = dt;
      best = &*c;
    }
  }
  return best;
}

}  // namespace slamaware
