#pragma once
// Free-space carving of a semi-dense map: a keyframe that seeded a point Y saw empty space along
// the ray from its centre to Y. A point X of the map that lies on such a ray, in front of Y, cannot
// be a surface (the keyframe would have seen X instead of Y): it is a wrong depth, typically
// smeared at an object's occluding edge. Such points merge neighbouring objects into one cluster
// and widen their boxes.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <vector>

#include "procs/proposals/scene_structure.h"

namespace slamaware::proposals {

/// The points of `test` that no keyframe saw through. Each keyframe's rays are its own points
/// (`by_keyframe`) from its centre; its orientation only parametrises directions, so the nearest
/// view's is used. Keyframes without a centre are skipped. `removed` counts what was dropped.
std::vector<MapPoint> removeSeenThrough(const std::vector<MapPoint>& test,
                                        const std::map<int32_t, std::vector<MapPoint>>& by_keyframe,
                                        const std::map<int32_t, Eigen::Vector3f>& centres,
                                        const std::vector<View>& views,
                                        const FreeSpaceOptions& options,
                                        int64_t* removed = nullptr);

}  // namespace slamaware::proposals
