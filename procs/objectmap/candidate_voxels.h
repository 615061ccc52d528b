#pragma once
// Which occupied voxels a detection box votes for. A box is the projection of a 3D candidate of
// the proposals stage, with the median depth of the candidate's points in that view: the voxels
// whose centre projects inside the box at a depth near that median depth are the candidate's,
// seen from this view. Background inside the box (the wall behind, the table in front) is at
// another depth or, seen from other views, outside the box: over many views only the object's
// own voxels are voted again and again (ObjectTable keeps those, VotingOptions::min_vote_share).
#include <cstdint>
#include <vector>

#include "common/camera_model.h"
#include "common/geometry.h"
#include "procs/objectmap/objectmap_options.h"
#include "procs/objectmap/occupancy_map.h"

namespace slamaware::objectmap {

struct VoteBox {
  float x = 0, y = 0, w = 0, h = 0;  ///< px, top-left corner and size
  float median_depth = 0;            ///< map units, along the camera's z axis
};

/// Half-width of the depth band of a box, in map units: the larger of depth_band x depth and
/// depth_band_box x the box's larger side at that depth.
double depthBandHalfWidth(const VoteBox& box, const CameraModel& camera,
                          const VotingOptions& options);

/// For each box, the keys (sorted) of the voxels of `occupied` that fall in it. Each voxel is
/// projected once; an image grid of grid_cell_px cells buckets them so that a box only looks at
/// the voxels projected near it.
std::vector<std::vector<VoxelKey>> voxelsInBoxes(const std::vector<OccupiedVoxel>& occupied,
                                                 const CameraModel& camera,
                                                 const SE3& T_world_camera,
                                                 const std::vector<VoteBox>& boxes,
                                                 const VotingOptions& options);

}  // namespace slamaware::objectmap
