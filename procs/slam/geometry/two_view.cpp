#include "procs/slam/geometry/two_view.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <random>

#include "procs/slam/geometry/pnp.h"
#include "procs/slam/geometry/triangulation.h"
#include "procs/slam/optimization/bundle_adjustment.h"
#include "procs/slam/run_shared.h"

namespace slamaware::slam {

namespace {

using Points = std::vector<Eigen::Vector2d>;

// Hartley-style normalisation (zero mean, unit mean absolute deviation per axis): p_n = T * p.
Eigen::Matrix3d normalize(const Points& in, Points* out) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : in) mean += p;
  mean /= std::max<size_t>(1, in.size());
  Eigen::Vector2d dev = Eigen::Vector2d::Zero();
  for (const auto& p : in) dev += (p - mean).cwiseAbs();
  dev /= std::max<size_t>(1, in.size());
  const double sx = dev.x() > 1e-12 ? 1.0 / dev.x() : 1.0,
               sy = dev.y() > 1e-12 ? 1.0 / dev.y() : 1.0;
  out->resize(in.size());
  for (size_t i = 0; i < in.size(); ++i)
    (*out)[i] = {(in[i].x() - mean.x()) * sx, (in[i].y() - mean.y()) * sy};
  Eigen::Matrix3d T;
  T << sx, 0, -mean.x() * sx, 0, sy, -mean.y() * sy, 0, 0, 1;
  return T;
}

// DLT homography p2 ~ H p1 from (normalised) correspondences.
Eigen::Matrix3d computeH21(const Points& p1, const Points& p2, const std::vector<int>& idx) {
  Eigen::MatrixXd A(2 * idx.size(), 9);
  for (size_t k = 0; k < idx.size(); ++k) {
    const double u1 = p1[idx[k]].x(), v1 = p1[idx[k]].y(), u2 = p2[idx[k]].x(), v2 = p2[idx[k]].y();
    A.row(2 * k) << 0, 0, 0, -u1, -v1, -1, v2 * u1, v2 * v1, v2;
    A.row(2 * k + 1) << u1, v1, 1, 0, 0, 0, -u2 * u1, -u2 * v1, -u2;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd h = svd.matrixV().col(8);
  Eigen::Matrix3d H;
  H << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  return H;
}

// Eight-point fundamental matrix p2^T F p1 = 0 (least squares over idx), rank 2 enforced.
Eigen::Matrix3d computeF21(const Points& p1, const Points& p2, const std::vector<int>& idx) {
  Eigen::MatrixXd A(idx.size(), 9);
  for (size_t k = 0; k < idx.size(); ++k) {
    const double u1 = p1[idx[k]].x(), v1 = p1[idx[k]].y(), u2 = p2[idx[k]].x(), v2 = p2[idx[k]].y();
    A.row(k) << u2 * u1, u2 * v1, u2, v2 * u1, v2 * v1, v2, u1, v1, 1;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd f = svd.matrixV().col(8);
  Eigen::Matrix3d F;
  F << f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7), f(8);
  Eigen::JacobiSVD<Eigen::Matrix3d> s2(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d sv = s2.singularValues();
  sv(2) = 0;
  return s2.matrixU() * sv.asDiagonal() * s2.matrixV().transpose();
}

// Symmetric transfer error score (ORB-SLAM's CheckHomography): each direction adds th - chi2 for
// matches under the chi-square threshold (2 dof, 95%).
double scoreHomography(const Eigen::Matrix3d& H21, const Points& p1, const Points& p2, double sigma,
                       std::vector<bool>* inliers) {
  const double th = 5.991, inv_s2 = 1.0 / (sigma * sigma);
  const Eigen::Matrix3d H12 = H21.inverse();
  double score = 0;
  inliers->assign(p1.size(), false);
  for (size_t i = 0; i < p1.size(); ++i) {
    bool in = true;
    const Eigen::Vector3d a = H21 * p1[i].homogeneous();
    const double e2 = (a.hnormalized() - p2[i]).squaredNorm() * inv_s2;
    if (!(e2 <= th))
      in = false;
    else
      score += th - e2;
    const Eigen::Vector3d b = H12 * p2[i].homogeneous();
    const double e1 = (b.hnormalized() - p1[i]).squaredNorm() * inv_s2;
    if (!(e1 <= th))
      in = false;
    else
      score += th - e1;
    (*inliers)[i] = in;
  }
  return score;
}

// Epipolar distance score (ORB-SLAM's CheckFundamental): chi-square threshold of 1 dof for the
// inlier test, scored against the 2-dof threshold so that H and F scores are comparable.
double scoreFundamental(const Eigen::Matrix3d& F21, const Points& p1, const Points& p2,
                        double sigma, std::vector<bool>* inliers) {
  const double th = 3.841, th_score = 5.991, inv_s2 = 1.0 / (sigma * sigma);
  double score = 0;
  inliers->assign(p1.size(), false);
  for (size_t i = 0; i < p1.size(); ++i) {
    bool in = true;
    const Eigen::Vector3d l2 = F21 * p1[i].homogeneous();
    const double d2 = l2.dot(p2[i].homogeneous());
    const double e2 = d2 * d2 / (l2.x() * l2.x() + l2.y() * l2.y()) * inv_s2;
    if (!(e2 <= th))
      in = false;
    else
      score += th_score - e2;
    const Eigen::Vector3d l1 = F21.transpose() * p2[i].homogeneous();
    const double d1 = l1.dot(p1[i].homogeneous());
    const double e1 = d1 * d1 / (l1.x() * l1.x() + l1.y() * l1.y()) * inv_s2;
    if (!(e1 <= th))
      in = false;
    else
      score += th_score - e1;
    (*inliers)[i] = in;
  }
  return score;
}

struct Hypothesis {
  SE3 T_cur_ref = SE3::Identity();
  int good = 0;
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> flags;
  double parallax_deg = 0;
};

// Triangulates the inliers for a candidate (R, t) and counts points in front of both cameras
// with reprojection errors under max_error_px (ORB-SLAM's CheckRT, which uses 2 sigma).
Hypothesis checkPose(const SE3& T_cur_ref, const Points& p1, const Points& p2,
                     const std::vector<bool>& inliers, const Eigen::Matrix3d& K,
                     double max_error_px) {
  Hypothesis h;
  h.T_cur_ref = T_cur_ref;
  h.points.assign(p1.size(), Eigen::Vector3d::Zero());
  h.flags.assign(p1.size(), false);
  const double th2 = max_error_px * max_error_px;
  const Eigen::Matrix3d Kinv = K.inverse();
  const Eigen::Vector3d o1 = Eigen::Vector3d::Zero(),
                        o2 = -T_cur_ref.linear().transpose() * T_cur_ref.translation();
  std::vector<double> parallax;
  for (size_t i = 0; i < p1.size(); ++i) {
    if (!inliers[i]) continue;
    Eigen::Vector3d p;
    if (!triangulateDlt(SE3::Identity(), T_cur_ref, Kinv * p1[i].homogeneous(),
                        Kinv * p2[i].homogeneous(), &p))
      continue;
    const Eigen::Vector3d q = T_cur_ref * p;
    if (p.z() <= 0 || q.z() <= 0) continue;
    const double e1 = ((K * p).hnormalized() - p1[i]).squaredNorm(),
                 e2 = ((K * q).hnormalized() - p2[i]).squaredNorm();
    if (e1 > th2 || e2 > th2) continue;
    const double c = parallaxCos(p, o1, o2);
    ++h.good;
    h.points[i] = p;
    // Points with almost no parallax count for the pose but are not made map points.
    if (c < 0.99998) {
      h.flags[i] = true;
      parallax.push_back(std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI);
    }
  }
  if (!parallax.empty()) {
    std::nth_element(parallax.begin(), parallax.begin() + parallax.size() / 2, parallax.end());
    h.parallax_deg = parallax[parallax.size() / 2];
  }
  return h;
}

// Correspondences whose two rays meet in front of both cameras under (R, t): the depths from the
// 2x2 least-squares system d1 R x1 - d2 x2 = -t must both be positive.
int countInFront(const SE3& T, const std::vector<Eigen::Vector3d>& rays1,
                 const std::vector<Eigen::Vector3d>& rays2, const std::vector<int>& idx) {
  const Eigen::Matrix3d& R = T.linear();
  const Eigen::Vector3d& t = T.translation();
  int n = 0;
  for (int i : idx) {
    const Eigen::Vector3d a = R * rays1[i], &b = rays2[i];
    const double aa = a.dot(a), bb = b.dot(b), ab = a.dot(b), at = a.dot(t), bt = b.dot(t);
    const double det = aa * bb - ab * ab;
    if (det < 1e-12) continue;
    const double d1 = (-bb * at + ab * bt) / det, d2 = (-ab * at + aa * bt) / det;
    n += d1 > 0 && d2 > 0;
  }
  return n;
}

// The four (R, t) of an essential matrix (|t| = 1).
std::vector<SE3> decomposeEssential(const Eigen::Matrix3d& E) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  Eigen::Matrix3d W;
  W << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  Eigen::Matrix3d R1 = U * W * V.transpose(), R2 = U * W.transpose() * V.transpose();
  if (R1.determinant() < 0) R1 = -R1;
  if (R2.determinant() < 0) R2 = -R2;
  const Eigen::Vector3d t = U.col(2).normalized();
  std::vector<SE3> out;
  for (const auto& R : {R1, R2})
    for (const auto& tt : {t, Eigen::Vector3d(-t)}) {
      SE3 T = SE3::Identity();
      T.linear() = R;
      T.translation() = tt;
      out.push_back(T);
    }
  return out;
}

bool samePose(const SE3& a, const SE3& b) {
  return rotationAngle(a.linear().transpose() * b.linear()) < 0.035 &&
         a.translation().normalized().dot(b.translation().normalized()) > 0.985;
}

// Two-view bundle adjustment from a candidate pose (the reference camera fixed). Every inlier
// takes part: a point the candidate puts behind a camera starts at the median depth on its ray,
// so that a wrong candidate pays for the points it cannot explain. Returns the refined pose
// (|t| = 1) and the final RMS reprojection error of the correspondences it kept.
SE3 refinePose(const SE3& T0, const Points& p1, const Points& p2, const std::vector<bool>& inliers,
               const Eigen::Matrix3d& K, double* rms_px) {
  const Eigen::Matrix3d Kinv = K.inverse();
  std::vector<Eigen::Vector3d> pts(p1.size());
  std::vector<bool> front(p1.size(), false);
  std::vector<double> depths;
  for (size_t i = 0; i < p1.size(); ++i) {
    if (!inliers[i]) continue;
    Eigen::Vector3d p;
    if (!triangulateDlt(SE3::Identity(), T0, Kinv * p1[i].homogeneous(), Kinv * p2[i].homogeneous(),
                        &p))
      continue;
    if (p.z() <= 0 || (T0 * p).z() <= 0) continue;
    pts[i] = p;
    front[i] = true;
    depths.push_back(p.z());
  }
  *rms_px = 1e9;
  if (depths.size() < 8) return T0;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double median_depth = depths[depths.size() / 2];
  BaProblem ba;
  ba.fx = K(0, 0);
  ba.fy = K(1, 1);
  ba.cx = K(0, 2);
  ba.cy = K(1, 2);
  ba.cameras = {{SE3::Identity(), true}, {T0, false}};
  for (size_t i = 0; i < p1.size(); ++i) {
    if (!inliers[i]) continue;
    const int k = static_cast<int>(ba.points.size());
    ba.points.push_back(
        {front[i] ? pts[i] : Eigen::Vector3d(Kinv * p1[i].homogeneous() * median_depth), false});
    ba.observations.push_back({0, k, p1[i], 1.0});
    ba.observations.push_back({1, k, p2[i], 1.0});
  }
  // Robust pass, then again without the correspondences it could not explain.
  BaOptions options;
  options.iterations = 15;
  if (!bundleAdjust(&ba, options).usable) return T0;
  for (size_t k = 0; k + 1 < ba.observations.size(); k += 2) {
    bool f0 = true, f1 = true;
    const bool bad = observationChi2(ba, ba.observations[k], &f0) > 5.991 ||
                     observationChi2(ba, ba.observations[k + 1], &f1) > 5.991 || !f0 || !f1;
    ba.observations[k].enabled = ba.observations[k + 1].enabled = !bad;
  }
  const BaSummary summary = bundleAdjust(&ba, options);
  if (!summary.usable) return T0;
  SE3 T = ba.cameras[1].T_camera_world;
  const double scale = T.translation().norm();
  if (!(scale > 1e-12)) return T0;
  T.translation() /= scale;
  *rms_px = summary.final_rms_px;  // over the correspondences kept
  return T;
}

bool neckerTwin(const Hypothesis& h, const Points& p1, const Points& p2, const Eigen::Matrix3d& K,
                uint64_t seed, SE3* twin) {
  std::vector<double> depths;
  for (size_t i = 0; i < p1.size(); ++i)
    if (h.points[i].z() > 0) depths.push_back(h.points[i].z());
  if (depths.size() < 8) return false;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double z0 = depths[depths.size() / 2];
  const Eigen::Matrix3d Kinv = K.inverse();
  std::vector<Eigen::Vector3d> pw;
  std::vector<Eigen::Vector2d> px;
  for (size_t i = 0; i < p1.size(); ++i) {
    if (h.points[i].z() <= 0) continue;
    const double z = 2 * z0 - h.points[i].z();
    if (z < 0.1 * z0) continue;
    pw.push_back(Kinv * p1[i].homogeneous() * z);
    px.push_back(p2[i]);
  }
  PnpOptions options;
  options.chi2 = 5.991 * 4;
  options.min_inliers = static_cast<int>(pw.size() / 2);
  const PnpResult r = solvePnpRansac(pw, px, std::vector<double>(pw.size(), 1.0), K(0, 0), K(1, 1),
                                     K(0, 2), K(1, 2), options, seed);
  if (!r.ok || r.T_camera_world.translation().norm() < 1e-12) return false;
  *twin = r.T_camera_world;
  twin->translation().normalize();
  return true;
}

void fillResult(const Hypothesis& h, TwoViewResult* r) {
  r->T_cur_ref = h.T_cur_ref;
  r->p_ref = h.points;
  r->triangulated = h.flags;
  r->num_triangulated = static_cast<int>(std::count(h.flags.begin(), h.flags.end(), true));
  r->parallax_deg = h.parallax_deg;
}

// The matches of both views, Hartley-normalised for the DLTs, and the random generator every
// sample of the initialisation draws from (in a fixed order).
struct Matches {
  const Points& px_ref;
  const Points& px_cur;
  const Eigen::Matrix3d& K;
  int n = 0;
  Points n1, n2;
  Eigen::Matrix3d T1, T2, T2inv, Kinv;
  std::mt19937_64 rng;

  Matches(const Points& ref, const Points& cur, const Eigen::Matrix3d& k, uint64_t seed)
      : px_ref(ref),
        px_cur(cur),
        K(k),
        n(static_cast<int>(std::min(ref.size(), cur.size()))),
        rng(seed) {
    T1 = normalize(px_ref, &n1);
    T2 = normalize(px_cur, &n2);
    T2inv = T2.inverse();
    Kinv = K.inverse();
  }
  // k distinct indices of `from` (a partial Fisher-Yates shuffle).
  std::vector<int> sample(const std::vector<int>& from, int k) {
    std::vector<int> pool = from, out(k);
    for (int j = 0; j < k; ++j) {
      const int pick = j + static_cast<int>(rng() % static_cast<uint64_t>(pool.size() - j));
      std::swap(pool[j], pool[pick]);
      out[j] = pool[j];
    }
    return out;
  }
  std::vector<int> all() const {
    std::vector<int> a(n);
    for (int i = 0; i < n; ++i) a[i] = i;
    return a;
  }
};

struct ModelFit {
  double score = -1;  // <= 0: none
  Eigen::Matrix3d M = Eigen::Matrix3d::Identity();
  std::vector<bool> inliers;
};

// Homography: RANSAC over 4-point samples, then re-fitted to its inliers while that helps.
ModelFit fitHomography(Matches& m, const InitOptions& opt) {
  ModelFit best;
  std::vector<bool> tmp;
  const std::vector<int> all = m.all();
  for (int it = 0; it < opt.ransac_iterations; ++it) {
    const Eigen::Matrix3d h = m.T2inv * computeH21(m.n1, m.n2, m.sample(all, 4)) * m.T1;
    if (!h.allFinite() || std::abs(h.determinant()) < 1e-12) continue;
    const double s = scoreHomography(h, m.px_ref, m.px_cur, opt.sigma_px, &tmp);
    if (s > best.score) best = {s, h, tmp};
  }
  for (int round = 0; round < 3 && best.score > 0; ++round) {
    std::vector<int> inl;
    for (int i = 0; i < m.n; ++i)
      if (best.inliers[i]) inl.push_back(i);
    if (inl.size() < 8) break;
    const Eigen::Matrix3d h = m.T2inv * computeH21(m.n1, m.n2, inl) * m.T1;
    const double s =
        h.allFinite() ? scoreHomography(h, m.px_ref, m.px_cur, opt.sigma_px, &tmp) : -1;
    if (s <= best.score) break;
    best = {s, h, tmp};
  }
  if (best.inliers.empty()) best.inliers.assign(static_cast<size_t>(m.n), false);
  return best;
}

// Epipolar geometry: the calibrated five-point essential matrix (Nister 2004, OpenCV's RANSAC)
// gives the score and the inliers, and its decompositions are candidate poses. Its pose is not
// trusted alone: with a narrow field of view, rotation and sideways translation are nearly
// interchangeable (the bas-relief ambiguity) and the minimal solvers often land on the wrong
// member of the family, which puts part of the points behind a camera.
ModelFit fitEssential(const Matches& m, const InitOptions& opt, std::vector<SE3>* poses) {
  ModelFit fit;
  fit.inliers.assign(static_cast<size_t>(m.n), false);
  std::vector<cv::Point2d> a(m.n), b(m.n);
  for (int i = 0; i < m.n; ++i) {
    a[i] = cv::Point2d(m.px_ref[i].x(), m.px_ref[i].y());
    b[i] = cv::Point2d(m.px_cur[i].x(), m.px_cur[i].y());
  }
  cv::Mat Kcv, mask, Ecv;
  cv::eigen2cv(m.K, Kcv);
  try {
    Ecv = cv::findEssentialMat(a, b, Kcv, cv::RANSAC, 0.999, std::sqrt(3.841) * opt.sigma_px, mask);
  } catch (const cv::Exception&) {
    Ecv.release();
  }
  if (Ecv.rows >= 3 && Ecv.cols == 3) {
    Eigen::Matrix3d E;
    cv::cv2eigen(Ecv.rowRange(0, 3), E);
    const Eigen::Matrix3d F = m.Kinv.transpose() * E * m.Kinv;
    if (F.allFinite()) {
      fit.score = scoreFundamental(F, m.px_ref, m.px_cur, opt.sigma_px, &fit.inliers);
      fit.M = F;
      for (const SE3& T : decomposeEssential(E)) poses->push_back(T);
    }
  }
  return fit;
}

// The calibrated homography's decompositions into up to four (R, t/d, n) solutions.
std::vector<SE3> homographyPoses(const Eigen::Matrix3d& H21, const Eigen::Matrix3d& K) {
  std::vector<SE3> poses;
  cv::Mat Hcv, Kcv;
  cv::eigen2cv(H21, Hcv);
  cv::eigen2cv(K, Kcv);
  std::vector<cv::Mat> Rs, ts, normals;
  try {
    cv::decomposeHomographyMat(Hcv, Kcv, Rs, ts, normals);
  } catch (const cv::Exception&) {
    Rs.clear();
  }
  for (size_t k = 0; k < Rs.size(); ++k) {
    SE3 T = SE3::Identity();
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    cv::cv2eigen(Rs[k], R);
    cv::cv2eigen(ts[k], t);
    if (t.norm() < 1e-9) continue;
    T.linear() = R;
    T.translation() = t.normalized();
    poses.push_back(T);
  }
  return poses;
}

// Up to five distinct candidates, best first: those that put nearly as many of the chosen
// model's inliers in front of both cameras as the best does, ordered by how well their epipolar
// geometry fits (the same score as model selection).
std::vector<SE3> rankCandidates(const std::vector<SE3>& candidates, const Matches& m,
                                const std::vector<bool>& inliers, const InitOptions& opt) {
  std::vector<Eigen::Vector3d> rays1(m.n), rays2(m.n);
  for (int i = 0; i < m.n; ++i) {
    rays1[i] = m.Kinv * m.px_ref[i].homogeneous();
    rays2[i] = m.Kinv * m.px_cur[i].homogeneous();
  }
  std::vector<int> inlier_idx;
  for (int i = 0; i < m.n; ++i)
    if (inliers[i]) inlier_idx.push_back(i);
  std::vector<int> in_front(candidates.size());
  int most = 0;
  for (size_t k = 0; k < candidates.size(); ++k) {
    in_front[k] = countInFront(candidates[k], rays1, rays2, inlier_idx);
    most = std::max(most, in_front[k]);
  }
  std::vector<std::pair<double, size_t>> ranked;
  std::vector<bool> tmp;
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (in_front[k] < 0.97 * most) continue;
    const Eigen::Matrix3d F =
        m.Kinv.transpose() * skew(candidates[k].translation()) * candidates[k].linear() * m.Kinv;
    ranked.push_back({scoreFundamental(F, m.px_ref, m.px_cur, opt.sigma_px, &tmp), k});
  }
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const auto& x, const auto& y) { return x.first > y.first; });
  std::vector<SE3> distinct;
  for (const auto& [score, k] : ranked) {
    if (distinct.size() >= 5) break;
    bool seen = false;
    for (const SE3& d : distinct) seen = seen || samePose(d, candidates[k]);
    if (!seen) distinct.push_back(candidates[k]);
  }
  return distinct;
}

struct Refined {
  SE3 T;
  double rms;
  Hypothesis h;
};

// Each start refined by bundle adjustment over the inliers, then the depth-reversed twin of each
// refined pose (every point on its reference ray with its depth mirrored about the median depth,
// the current camera re-sectioned against them: the Necker reversal that narrow views allow)
// refined too. Each refinement is independent of the others (two bundle adjustments, most of the
// initialisation's time): they are shared out to opt.threads threads, each result kept at its
// candidate's index, so the outcome does not depend on the threads.
std::vector<Refined> refineWithTwins(const std::vector<SE3>& starts, const Matches& m,
                                     const std::vector<bool>& inliers, const InitOptions& opt,
                                     uint64_t seed) {
  auto refineAll = [&](const std::vector<SE3>& from) {
    std::vector<Refined> out(from.size());
    runShared(static_cast<int>(from.size()), opt.threads, [&](int k) {
      double rms = 1e9;
      const SE3 T = refinePose(from[k], m.px_ref, m.px_cur, inliers, m.K, &rms);
      out[k] = {T, rms, checkPose(T, m.px_ref, m.px_cur, inliers, m.K, 2 * opt.sigma_px)};
    });
    return out;
  };
  std::vector<Refined> refined = refineAll(starts);
  std::vector<SE3> twins;
  for (const Refined& k : refined) {
    SE3 twin;
    if (neckerTwin(k.h, m.px_ref, m.px_cur, m.K, seed, &twin)) twins.push_back(twin);
  }
  for (Refined& k : refineAll(twins)) refined.push_back(std::move(k));
  return refined;
}

// The refined pose that explains the most inliers, the lowest error among near ties; -1 when
// another pose explains the points about as well (the two views cannot tell them apart).
int pickRefined(const std::vector<Refined>& refined) {
  size_t best = 0;
  for (size_t k = 1; k < refined.size(); ++k) {
    const bool more = refined[k].h.good > 1.05 * refined[best].h.good;
    const bool tie = refined[k].h.good >= refined[best].h.good / 1.05;
    if (more || (tie && refined[k].rms < refined[best].rms)) best = k;
  }
  for (size_t k = 0; k < refined.size(); ++k) {
    if (k == best || samePose(refined[k].T, refined[best].T)) continue;
    if (refined[k].h.good >= 0.95 * refined[best].h.good &&
        refined[k].rms < 1.03 * refined[best].rms)
      return -1;
  }
  return static_cast<int>(best);
}

}  // namespace

TwoViewResult reconstructTwoView(const Points& px_ref, const Points& px_cur,
                                 const Eigen::Matrix3d& K, const InitOptions& opt, uint64_t seed) {
  TwoViewResult r;
  if (std::min(px_ref.size(), px_cur.size()) < 8) {
    r.reason = "fewer than 8 matches";
    return r;
  }
  Matches m(px_ref, px_cur, K, seed);
  const ModelFit homography = fitHomography(m, opt);
  std::vector<SE3> epipolar_candidates;
  const ModelFit essential = fitEssential(m, opt, &epipolar_candidates);
  if (homography.score <= 0 && essential.score <= 0) {
    r.reason = "no model";
    return r;
  }
  const double best_h = std::max(0.0, homography.score), best_f = std::max(0.0, essential.score);
  r.score_ratio = best_h / (best_h + best_f);
  const bool use_h = r.score_ratio > opt.homography_ratio;
  r.model = use_h ? 'H' : 'F';
  const std::vector<bool>& inliers = use_h ? homography.inliers : essential.inliers;
  r.num_inliers = static_cast<int>(std::count(inliers.begin(), inliers.end(), true));
  const int min_good = std::max(static_cast<int>(0.9 * r.num_inliers), opt.min_triangulated);

  // Candidate poses from both models: the homography's decompositions, the essential matrix's,
  // and those of eight-point samples of the epipolar inliers. With narrow views both can land on
  // the depth-reversed twin of the true motion (the Necker reversal: rotation mirrored,
  // translation flipped, all points still in front); bundle adjustment over the chosen model's
  // inliers then tells them apart.
  std::vector<SE3> candidates;
  if (homography.score > 0) candidates = homographyPoses(homography.M, K);
  std::vector<int> f_inliers;
  for (int i = 0; i < m.n; ++i)
    if (essential.inliers[i]) f_inliers.push_back(i);
  if (f_inliers.size() >= 8)
    for (int it = 0; it < opt.ransac_iterations; ++it) {
      const Eigen::Matrix3d F =
          m.T2.transpose() * computeF21(m.n1, m.n2, m.sample(f_inliers, 8)) * m.T1;
      if (!F.allFinite()) continue;
      for (const SE3& T : decomposeEssential(K.transpose() * F * K))
        epipolar_candidates.push_back(T);
    }
  candidates.insert(candidates.end(), epipolar_candidates.begin(), epipolar_candidates.end());
  if (candidates.empty()) {
    r.reason = "no pose hypothesis";
    return r;
  }
  const std::vector<Refined> refined =
      refineWithTwins(rankCandidates(candidates, m, inliers, opt), m, inliers, opt, seed);
  const int best = pickRefined(refined);
  if (best < 0) {
    r.reason =
        std::string("ambiguous ") + (use_h ? "homography" : "essential-matrix") + " decomposition";
    return r;
  }
  const Hypothesis& h = refined[static_cast<size_t>(best)].h;
  fillResult(h, &r);
  if (h.good < min_good) {
    r.reason = "only " + std::to_string(h.good) + " of " + std::to_string(r.num_inliers) +
               " inliers triangulated";
    return r;
  }
  if (r.num_triangulated < opt.min_triangulated) {
    r.reason = "only " + std::to_string(r.num_triangulated) + " points with parallax";
    return r;
  }
  if (h.parallax_deg < opt.min_parallax_deg) {
    r.reason = "median parallax " + std::to_string(h.parallax_deg) + " deg";
    return r;
  }
  r.ok = true;
  return r;
}

}  // namespace slamaware::slam
