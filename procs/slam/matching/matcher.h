#pragma once
// Feature matching between frames, keyframes and map points (after ORB-SLAM's ORBmatcher): brute
// force with a ratio test for the reference keyframe and relocalisation, window search for
// initialisation, guided search by projection for tracking, epipolar search for triangulation,
// and fusion of duplicate points. Every function that touches map points expects the caller to
// hold the map's lock (shared for searches, exclusive for fuse()).
#include <Eigen/Core>
#include <memory>
#include <utility>
#include <vector>

#include "common/geometry.h"
#include "procs/slam/map/frame.h"

namespace slamaware::slam {

class KeyFrame;
class MapPoint;
class Map;

constexpr int kMatchDistanceHigh = 100;  ///< bits, loosest accepted descriptor distance
constexpr int kMatchDistanceLow = 50;    ///< bits, strict distance (triangulation, fusion)

using Matches = std::vector<std::pair<int, int>>;  ///< (feature in a, feature in b)

/// Keeps the matches whose rotation difference (keypoint angle in b minus in a) falls in the
/// three most populated of 30 bins: a frame pair has one dominant in-plane rotation.
void filterByRotation(const FrameFeatures& a, const FrameFeatures& b, Matches* matches);

/// For each feature a_indices[k] of `a`, the nearest feature of `b` if its distance is <=
/// max_distance and below `ratio` x the second nearest; a feature of b keeps only its best match.
Matches matchBruteForce(const FrameFeatures& a, const std::vector<int>& a_indices,
                        const FrameFeatures& b, double ratio, int max_distance,
                        bool check_rotation);

/// A map point's expected appearance in a camera: pixel, distance, pyramid level, viewing cosine.
struct Projection {
  Eigen::Vector2d px;
  double distance = 0;
  int level = 0;
  double view_cos = 1;
};
/// Projects a map point into a camera with pose T_camera_world; false when it is behind, outside
/// the image, outside its scale-invariance range or seen from more than 60 degrees off its normal.
bool projectMapPoint(const MapPoint& p, const SE3& T_camera_world,
                     const Eigen::Vector3d& camera_center, const Intrinsics& intrinsics,
                     Projection* out);

/// Motion-model search: projects the previous frame's matched points with frame.T_camera_world and
/// matches them in a window of radius_px x scale around the projection. Returns matches added.
int searchByProjection(Frame& frame, const Frame& previous, double radius_px);

/// Local-map search: matches points (with their projections, from projectMapPoint) into unmatched
/// features of the frame, window = radius_factor x (2.5 or 4 px by viewing angle) x scale.
int searchLocalPoints(Frame& frame, const std::vector<std::shared_ptr<MapPoint>>& points,
                      const std::vector<Projection>& projections, double radius_factor,
                      double ratio);

/// Projects a keyframe's points (those not already matched in the frame) into the frame and
/// matches them within radius_px x scale (relocalisation refinement). Returns matches added.
int searchKeyFramePoints(Frame& frame, const KeyFrame& kf, double radius_px, int max_distance);

/// New correspondences between unmatched features of two keyframes that satisfy the epipolar
/// constraint (for triangulation). F21 maps pixels of kf1 to epipolar lines in kf2.
/// skip1 (optional): features of kf1 to leave out (already used for a new point).
Matches searchForTriangulation(const KeyFrame& kf1, const KeyFrame& kf2, const Eigen::Matrix3d& F21,
                               const std::vector<bool>* skip1 = nullptr);

/// Projects points into kf and merges each with the point already at the matched feature (the one
/// with more observations survives) or adds the observation. Needs the exclusive lock.
/// Returns the number of points fused or added.
int fuse(Map& map, const std::shared_ptr<KeyFrame>& kf,
         const std::vector<std::shared_ptr<MapPoint>>& points, double radius_px);

/// Fundamental matrix mapping pixels of camera 1 to epipolar lines in camera 2 (pinhole K).
Eigen::Matrix3d fundamentalFromPoses(const SE3& T1_camera_world, const SE3& T2_camera_world,
                                     const Eigen::Matrix3d& K);

}  // namespace slamaware::slam
