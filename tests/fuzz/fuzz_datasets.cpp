// Fuzz target: the readers of the two on-disk layouts of DATASETS.md, as the camera, the trainer
// and the evaluator open them. Input: one byte of flags, then parts cut by fuzz::kSeparator.
//   bit 0 clear, a sequence folder: sequence.yaml, boxes.csv, objects.csv, groundtruth.txt,
//     timestamps.txt, then the names of the files in rgb/ (one per line); a part that is absent or
//     empty is a file that is not there.
//   bit 0 set, an object set: set.yaml, the relative paths of the files in the set (one per line),
//     then the contents of those files in order (absent: empty files).
// Checks beyond "no crash": a refusal is a DatasetError naming a file of the folder.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "common/dataset.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line) && out.size() < 64;)
    if (!line.empty()) out.push_back(line);
  return out;
}

/// A relative path that stays inside the folder (no absolute path, no "..", at most 4 levels).
bool safeRelative(const std::string& p) {
  if (p.empty() || p[0] == '/' || p.size() > 200) return false;
  int levels = 1;
  std::istringstream in(p);
  for (std::string part; std::getline(in, part, '/');) {
    if (part.empty() || part == "." || part == ".." || part.find('\0') != std::string::npos)
      return false;
    ++levels;
  }
  return levels <= 5;
}

void sequence(const std::vector<std::string>& parts, const std::string& dir) {
  const char* names[] = {"sequence.yaml", "boxes.csv", "objects.csv", "groundtruth.txt",
                         "timestamps.txt"};
  for (size_t i = 0; i < 5 && i < parts.size(); ++i)
    if (!parts[i].empty()) slamaware::fuzz::writeFile(dir + "/" + names[i], parts[i]);
  if (parts.size() > 5)
    for (const auto& name : lines(parts[5]))
      if (safeRelative(name) && name.find('/') == std::string::npos)
        slamaware::fuzz::writeFile(dir + "/rgb/" + name, "");
  const auto seq = slamaware::SequenceFolder::open(dir);
  for (size_t i = 0; i < seq.size(); ++i) {
    seq.framePath(i);
    seq.timestamp(i);
    seq.depthPath(i);
  }
  if (seq.hasBoxes()) seq.boxes();
  if (seq.hasObjects()) seq.objects();
  if (seq.hasGroundTruth()) seq.groundTruth();
  slamaware::isSyntheticSequence(seq);
}

void objectSet(const std::vector<std::string>& parts, const std::string& dir) {
  slamaware::fuzz::writeFile(dir + "/set.yaml", parts[0]);
  if (parts.size() > 1) {
    const auto files = lines(parts[1]);
    for (size_t i = 0; i < files.size(); ++i)
      if (safeRelative(files[i]))
        slamaware::fuzz::writeFile(dir + "/" + files[i], i + 2 < parts.size() ? parts[i + 2] : "");
  }
  const auto set = slamaware::ObjectSet::open(dir);
  set.instances();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::vector<std::string> parts = slamaware::fuzz::splitParts(data + 1, size - 1);
  const std::string dir = slamaware::fuzz::scratchDir() + "/data";
  std::filesystem::create_directories(dir);
  try {
    if (data[0] & 1)
      objectSet(parts, dir);
    else
      sequence(parts, dir);
  } catch (const slamaware::DatasetError& e) {
    if (std::string(e.what()).find(dir) == std::string::npos) {
      std::fprintf(stderr, "fuzz_datasets: a refusal that names no file of the folder: %s\n",
                   e.what());
      std::abort();
    }
  }
  return 0;
}
