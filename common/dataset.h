#pragma once
// Readers (and writers) of the two on-disk layouts of DATASETS.md: the sequence folder (what a
// camera saw, with optional ground truth) and the object set (labelled crops of object instances,
// the layout of the UW RGB-D Object dataset).
#include <Eigen/Core>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/camera_model.h"
#include "common/tum.h"

namespace slamaware {

class DatasetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// sequence.yaml
struct SequenceInfo {
  std::string name;
  std::string source;
  double fps = 30.0;
  int frames = 0;
  CameraModel camera;
  std::vector<std::string> classes;
  std::string notes;
};

/// A row of boxes.csv: a visible object in a frame (pixels, x, y = top-left).
struct GroundTruthBox {
  int frame = 0;
  double x = 0, y = 0, w = 0, h = 0;
  std::string cls;
  std::string instance;
};

/// A row of objects.csv: the axis-aligned 3D box of an object in the ground-truth world frame.
struct GroundTruthObject {
  std::string instance;
  std::string cls;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
};

class SequenceFolder {
 public:
  /// Opens a sequence folder: reads sequence.yaml, lists rgb/, reads timestamps.txt if present.
  /// Throws DatasetError naming the file at fault.
  static SequenceFolder open(const std::string& dir);

  const std::string& dir() const { return dir_; }
  const SequenceInfo& info() const { return info_; }
  size_t size() const { return frames_.size(); }
  /// Path of frame i (lexicographic order of rgb/).
  const std::string& framePath(size_t i) const { return frames_[i]; }
  /// Time of frame i in seconds (timestamps.txt, or i / fps).
  double timestamp(size_t i) const { return timestamps_[i]; }

  // Ground truth: for evaluation and training only, never for the processes.
  bool hasGroundTruth() const;
  std::vector<TimedPose> groundTruth() const;  ///< groundtruth.txt
  bool hasBoxes() const;
  std::vector<GroundTruthBox> boxes() const;  ///< boxes.csv
  bool hasObjects() const;
  std::vector<GroundTruthObject> objects() const;  ///< objects.csv
  /// depth/<frame stem>.png (16-bit, millimetres) if present, else "".
  std::string depthPath(size_t i) const;

 private:
  std::string dir_;
  SequenceInfo info_;
  std::vector<std::string> frames_;
  std::vector<double> timestamps_;
};

/// True for sequences of the synthetic suite (the generator's source, or depth ground truth).
bool isSyntheticSequence(const SequenceFolder& sequence);

/// The name of a sequence folder or object set: its last path component ("a/set/" -> "set").
std::string folderName(const std::string& dir);

/// Reads sequence.yaml; throws DatasetError naming the file and the key at fault.
SequenceInfo readSequenceInfo(const std::string& path);
void writeSequenceInfo(const std::string& path, const SequenceInfo& info);
void writeBoxes(const std::string& path, const std::vector<GroundTruthBox>& boxes);
void writeObjects(const std::string& path, const std::vector<GroundTruthObject>& objects);
std::vector<GroundTruthBox> readBoxes(const std::string& path);
std::vector<GroundTruthObject> readObjects(const std::string& path);

/// One labelled view of an object instance.
struct ObjectView {
  std::string category;   ///< e.g. "apple"
  std::string instance;   ///< e.g. "apple_1"
  int video = 0;          ///< video (elevation) index from the file name
  int frame = 0;          ///< frame index from the file name
  std::string crop_path;  ///< ..._crop.png
  std::string mask_path;  ///< ..._maskcrop.png, "" if absent
  bool has_location = false;
  int loc_x = 0, loc_y = 0;  ///< crop's top-left corner in the full frame (..._loc.txt)
};

class ObjectSet {
 public:
  /// Lists <dir>/<category>/<category>_<instance>/<...>_crop.png; throws DatasetError when the
  /// folder is missing, empty, or a file name does not follow the layout.
  static ObjectSet open(const std::string& dir);

  const std::string& dir() const { return dir_; }
  const std::vector<std::string>& categories() const { return categories_; }
  const std::vector<ObjectView>& views() const { return views_; }
  /// Instance names per category, sorted.
  std::map<std::string, std::vector<std::string>> instances() const;
  /// True for a set rendered by the synthetic generator (its set.yaml says `source: synth`, or, as
  /// written before that key, notes "rendered by slamaware-synth"); false for photographs.
  bool rendered() const { return rendered_; }

 private:
  std::string dir_;
  bool rendered_ = false;
  std::vector<std::string> categories_;
  std::vector<ObjectView> views_;
};

}  // namespace slamaware
