#pragma once
// The structure of a semi-dense map that is not object: large planes (walls, floor, the table)
// and, among them, the support the objects stand on. The views (camera poses) of the map give
// two priors a monocular map lacks: which way is up (a hand-held or robot camera is held with
// little roll, so its x axis is horizontal whatever its pitch) and what the camera looks at (the
// optical axes of views circling a table meet over it).
#include <Eigen/Core>
#include <vector>

#include "procs/proposals/proposal_options.h"

namespace slamaware::proposals {

struct MapPoint {
  Eigen::Vector3f p;
  uint8_t r = 0, g = 0, b = 0;
};

/// One camera pose of the map: centre, optical axis, image right (x) and image up (-y), world
/// frame.
struct View {
  Eigen::Vector3f centre, forward, right, up;
};

/// What the views of a map tell about the scene.
struct ViewPriors {
  bool valid = false;  ///< at least one view
  /// The views turned about the up axis enough for their x axes to span the horizontal: up is
  /// the direction perpendicular to all of them (on the side of the images' up).
  bool up_known = false;
  Eigen::Vector3f up{0, 0, 0};  ///< unit (valid when up_known)
  Eigen::Vector3f mean_centre{0, 0, 0};
  bool has_look_at = false;          ///< the optical axes meet (they are not all parallel)
  Eigen::Vector3f look_at{0, 0, 0};  ///< the point closest to every optical axis (least squares)
};

ViewPriors viewPriors(const std::vector<View>& views);

/// A plane of the map: n·p + d = 0, n unit and towards the cameras. (No 16-byte Eigen types in
/// this header: candidate_map.cpp includes it and is compiled without AVX, see CMakeLists.txt.)
struct Plane {
  Eigen::Vector3f n{0, 0, 1};
  float d = 0;
  const Eigen::Vector3f& normal() const { return n; }
  float distance(const Eigen::Vector3f& p) const { return n.dot(p) + d; }
};

/// A support plane and the region of it that holds points (a table top, a floor): its points'
/// largest connected patch, as a convex polygon in plane coordinates.
struct Support {
  Plane plane;
  Eigen::Vector3f origin{0, 0, 0}, axis_u{0, 0, 0}, axis_v{0, 0, 0};  ///< plane coordinates
  std::vector<Eigen::Vector2f> hull;                                  ///< convex, counter-clockwise
  /// True if the foot of `p` on the plane lies inside the hull grown by `margin`.
  bool over(const Eigen::Vector3f& p, float margin) const;
};

struct StructureStats {
  int planes = 0;                ///< planes found
  int structure_planes = 0;      ///< of them, removed as structure (larger than an object)
  int64_t structure_points = 0;  ///< points removed with them
  bool support = false;
};

/// Splits `points` (filtered, lengths of `o` already scaled) into structure and the rest: up to
/// o.max_planes planes by RANSAC (on o.ransac_points of them); the parts of a plane whose connected
/// patch is larger than an object (o.structure_extent) are structure and removed. The support is
/// the near-horizontal plane (normal within o.support_max_tilt_deg of the views' up; a plane
/// without structure only when up is known: a small table top) nearest under the point the
/// views' optical axes meet (else the structure plane they hit first most
/// often).
struct StructureResult {
  std::vector<MapPoint> kept;  ///< the points that are not structure
  bool has_support = false;
  Support support;             ///< when has_support
  std::vector<MapPoint> band;  ///< the support's own points (band of o.support_distance), removed
  StructureStats stats;
};
StructureResult removeStructure(const std::vector<MapPoint>& points, const std::vector<View>& views,
                                const ViewPriors& priors, const ProposalOptions& o);

}  // namespace slamaware::proposals
