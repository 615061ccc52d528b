#include "procs/slam/depth/seed.h"

#include <algorithm>
#include <cmath>

namespace slamaware::slam {

DepthSeed makeSeed(float u, float v, const Eigen::Vector3f& bearing, float mean_depth,
                   float min_depth) {
  DepthSeed s;
  s.u = u;
  s.v = v;
  s.f = bearing;
  s.mu = 1.f / mean_depth;
  s.z_range = 1.f / min_depth;
  // The prior covers the whole inverse-depth range at 3 sigma either side.
  s.sigma2 = s.z_range * s.z_range / 36.f;
  return s;
}

void updateSeed(DepthSeed* s, float x, float tau2) {
  const float norm_scale = std::sqrt(s->sigma2 + tau2);
  if (!std::isfinite(norm_scale) || norm_scale <= 0) return;
  // Gaussian part: the product of the prior and the measurement likelihood.
  const float s2 = 1.f / (1.f / s->sigma2 + 1.f / tau2);
  const float m = s2 * (s->mu / s->sigma2 + x / tau2);
  // Responsibilities of the inlier (Gaussian) and outlier (uniform) explanations of x.
  const float d = (x - s->mu) / norm_scale;
  float c1 =
      s->a / (s->a + s->b) * std::exp(-0.5f * d * d) / (norm_scale * std::sqrt(2.f * float(M_PI)));
  float c2 = s->b / (s->a + s->b) / s->z_range;
  const float normalization = c1 + c2;
  if (!(normalization > 0)) return;
  c1 /= normalization;
  c2 /= normalization;
  // First and second moments of the inlier ratio under the new posterior.
  const float ab = s->a + s->b;
  const float f = c1 * (s->a + 1.f) / (ab + 1.f) + c2 * s->a / (ab + 1.f);
  const float e = c1 * (s->a + 1.f) * (s->a + 2.f) / ((ab + 1.f) * (ab + 2.f)) +
                  c2 * s->a * (s->a + 1.f) / ((ab + 1.f) * (ab + 2.f));
  const float mu_new = c1 * m + c2 * s->mu;
  const float sigma2_new = c1 * (s2 + m * m) + c2 * (s->sigma2 + s->mu * s->mu) - mu_new * mu_new;
  if (!std::isfinite(mu_new) || !(sigma2_new > 0)) return;
  s->mu = mu_new;
  s->sigma2 = sigma2_new;
  const float a = (e - f) / (f - e / f), b = a * (1.f - f) / f;
  if (std::isfinite(a) && std::isfinite(b)) {
    s->a = std::max(a, 1e-3f);
    s->b = std::max(b, 1e-3f);
  }
  ++s->updates;
}

double depthUncertainty(const Eigen::Vector3d& t, const Eigen::Vector3d& f, double z,
                        double px_error_angle) {
  const Eigen::Vector3d a = f * z - t;
  const double t_norm = t.norm(), a_norm = a.norm();
  if (t_norm <= 0 || a_norm <= 0) return z;
  const double alpha = std::acos(std::clamp(f.dot(t) / t_norm, -1.0, 1.0));
  const double beta = std::acos(std::clamp(a.dot(-t) / (t_norm * a_norm), -1.0, 1.0));
  const double beta_plus = beta + px_error_angle;
  const double gamma_plus = M_PI - alpha - beta_plus;
  if (gamma_plus <= 1e-9) return z;  // the widened ray no longer meets the host ray
  const double z_plus = t_norm * std::sin(beta_plus) / std::sin(gamma_plus);
  return std::abs(z_plus - z);
}

}  // namespace slamaware::slam
