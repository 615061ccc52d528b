#pragma once
// The object map on disk (docs/architecture.md §6). A save is a numbered generation:
//   objectmap-<generation>-seg<id>.ot  one OctoMap ColorOcTree per map segment (octovis opens it;
//                                      colour = label), written only when its bytes changed
//   objectmap-<generation>.json        the object table; its first line is a header
//     {"format":"slamaware-objectmap","version":1,"generation":G,"content_bytes":N,"content_crc32":C,
//     "content":{...}}
//   with N and C the size and CRC-32 of the content's bytes; the content names each segment's .ot
//   file with its size and CRC-32.
// Commit order: the .ot files (atomically, new names), then the JSON (atomically: its rename is the
// commit point), then the removal of generations older than the previous good one. A process killed
// at any moment leaves the previous generation intact, and at worst orphan files that the next save
// removes. Loading takes the newest generation that passes every check and falls back to older
// ones; a damaged file is reported (file and why) and never deleted or overwritten because of it
// before a newer good generation exists.
#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

namespace slamaware::objectmap {

/// What is saved: the object table (content["segments"] lists {"id": ...} per segment) and each
/// segment's .ot bytes by segment id.
struct MapSnapshot {
  nlohmann::json content;
  std::map<int32_t, std::string> segment_files;
};

struct SaveReport {
  int64_t generation = -1;
  std::string json_path;
  std::map<int32_t, std::string> segment_paths;  ///< segment id -> .ot path
  size_t bytes_written = 0;                      ///< new bytes (unchanged .ot files are reused)
  size_t files_removed = 0;
  double ms = 0;
};

struct LoadReport {
  int64_t generation = -1;  ///< -1: nothing loaded (empty folder, or every generation refused)
  std::string json_path;
  std::vector<std::string> failures;  ///< one line per refused generation: the file and why
};

class MapStore {
 public:
  static constexpr const char* kFormat = "slamaware-objectmap";
  static constexpr int kVersion = 1;

  /// The store in folder `dir` (created at the first save).
  explicit MapStore(std::string dir);
  ~MapStore();
  MapStore(const MapStore&) = delete;
  MapStore& operator=(const MapStore&) = delete;

  const std::string& dir() const { return dir_; }

  /// Takes the folder's lock (objectmap.lock, flock): one writer per folder. False (and *why) when
  /// another process holds it.
  bool lock(std::string* why);
  /// Removes temporary files of saves that were interrupted (a killed process leaves them).
  size_t removeTemporaryFiles();

  /// Hands the newest generation that passes the file checks to accept(), which may throw to
  /// refuse it (inconsistent content); then tries older ones. Never modifies the folder.
  LoadReport load(const std::function<void(const MapSnapshot&)>& accept);

  /// Writes a new generation and commits it; then removes the generations older than the previous
  /// good one (loaded or saved by this store). Throws std::runtime_error naming the file when a
  /// write fails: the previous generation is then still the newest good one. The snapshot is taken
  /// by value and consumed (move it in: a large table is not copied).
  SaveReport save(MapSnapshot snapshot);

  /// The generation that the next save writes.
  int64_t nextGeneration();

  /// File names of a generation.
  static std::string jsonName(int64_t generation);
  static std::string segmentName(int64_t generation, int32_t segment);

 private:
  struct FileRef {
    std::string name;
    size_t bytes = 0;
    uint32_t crc = 0;
  };
  /// Reads and checks one generation's JSON and .ot files; throws std::runtime_error naming the
  /// file.
  MapSnapshot readGeneration(int64_t generation, std::map<int32_t, FileRef>* files) const;
  void scan();
  /// Removes the files of generations up to `newest` whose names are not in `keep`.
  size_t removeOld(int64_t newest, const std::set<std::string>& keep);

  std::string dir_;
  bool scanned_ = false;
  int64_t next_generation_ = 1;
  int64_t good_generation_ = -1;           ///< last generation loaded or saved
  std::map<int32_t, FileRef> good_files_;  ///< its .ot files by segment
  int lock_fd_ = -1;
};

}  // namespace slamaware::objectmap
