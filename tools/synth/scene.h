#pragma once
// A synthetic tabletop scene: a room with a table, 3-8 objects on it (paper classes plus
// distractors), a light and a camera path, built deterministically from a config and a seed.
// Renders any frame on demand (same bits whatever the order) with its ground truth.
#include <memory>
#include <string>
#include <vector>

#include "common/camera_model.h"
#include "common/dataset.h"
#include "tools/synth/categories.h"
#include "tools/synth/environment.h"
#include "tools/synth/rasterizer.h"
#include "tools/synth/synth_options.h"
#include "tools/synth/trajectory.h"

namespace slamaware::synth {

/// An object placed in the scene.
struct SceneObject {
  std::string category;
  std::string instance;  ///< "<category>_<n>", n counted per category from 1
  uint64_t instance_seed = 0;
  int id = 0;                     ///< object id in the render buffers
  Eigen::AlignedBox3d world_box;  ///< axis-aligned box of its vertices, world frame
  double yaw = 0;                 ///< rad, rotation about z on the table
};

/// Visibility of an object in one frame.
struct ObjectVisibility {
  int id = 0;
  int64_t visible_px = 0;                ///< pixels where it is the nearest surface
  int64_t silhouette_px = 0;             ///< pixels it would cover alone (also outside the image)
  double fraction = 0;                   ///< visible / silhouette
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  ///< bounding box of the visible pixels (inclusive)
  bool listed = false;  ///< passes the boxes.csv rule (>= 30 % visible, box >= 20 x 20)
};

class SyntheticScene {
 public:
  static constexpr double kMinVisibleFraction = 0.3;
  static constexpr int kMinBoxSide = 20;

  /// Builds the scene; `seed` replaces options.seed when >= 0; `frames` > 0 renders only the first
  /// frames of the sequence (the camera path is the one of options.frames). Throws
  /// std::invalid_argument when the objects cannot be placed on the table.
  SyntheticScene(const SceneOptions& options, int64_t seed = -1, int frames = -1);

  const SceneOptions& options() const { return opt_; }
  uint64_t seed() const { return seed_; }
  /// Frames to render (options.frames unless fewer were asked for).
  int frames() const { return frames_; }
  double fps() const { return opt_.camera.fps; }
  CameraModel camera() const;
  const Intrinsics& intrinsics() const { return K_; }
  /// T_world_camera of frame i (mid-exposure).
  Eigen::Isometry3d pose(int frame) const;
  double time(int frame) const { return frame / opt_.camera.fps; }

  const std::vector<SceneObject>& objects() const { return objects_; }
  const RenderScene& renderScene() const { return scene_; }
  const Environment& environment() const { return env_; }

  /// Renders frame i: fills `fb` (depth, object ids, linear colour) and returns the 8-bit image.
  cv::Mat render(int frame, FrameBuffers* fb);
  /// Visibility of every object in a rendered frame (uses fb's object ids).
  std::vector<ObjectVisibility> visibility(int frame, const FrameBuffers& fb);
  /// The boxes.csv rows of a frame.
  std::vector<GroundTruthBox> boxes(int frame, const std::vector<ObjectVisibility>& vis) const;
  /// The objects.csv rows.
  std::vector<GroundTruthObject> groundTruthObjects() const;
  /// sequence.yaml.
  SequenceInfo sequenceInfo(const std::string& config_name) const;

 private:
  void placeObjects(Rng& rng);

  SceneOptions opt_;
  uint64_t seed_ = 0;
  int frames_ = 0;
  Intrinsics K_;
  RenderScene scene_;
  Environment env_;
  std::unique_ptr<Trajectory> trajectory_;
  std::vector<SceneObject> objects_;
  Rasterizer raster_;
};

}  // namespace slamaware::synth
