#include "common/dataset.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace slamaware {

namespace {

template <class T>
T required(const YAML::Node& node, const char* key, const std::string& path) {
  const YAML::Node v = node[key];
  if (!v) throw DatasetError(path + ": missing key '" + key + "'");
  try {
    return v.as<T>();
  } catch (const YAML::Exception&) {
    throw DatasetError(path + ": key '" + key + "' has the wrong type");
  }
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream s(line);
  while (std::getline(s, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    out.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

/// A finite number (nan and inf are refused: no ground-truth value is either).
double toDouble(const std::string& s, const std::string& path, int line) {
  double v = 0;
  try {
    size_t used = 0;
    v = std::stod(s, &used);
    if (used != s.size()) throw std::invalid_argument(s);
  } catch (const std::exception&) {
    throw DatasetError(path + ":" + std::to_string(line) + ": '" + s + "' is not a number");
  }
  if (!std::isfinite(v))
    throw DatasetError(path + ":" + std::to_string(line) + ": '" + s + "' is not a finite number");
  return v;
}

/// A whole number that fits an int (frame numbers, pixel positions).
int toInt(const std::string& s, const std::string& path, int line) {
  const double v = toDouble(s, path, line);
  if (v != std::floor(v) || std::fabs(v) > 1e9)
    throw DatasetError(path + ":" + std::to_string(line) + ": '" + s +
                       "' is not a whole number of at most 1e9");
  return static_cast<int>(v);
}

bool isImageFile(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

// Reads a CSV with the given header; calls row(cells, line_no) for each data line.
template <class Fn>
void readCsv(const std::string& path, const std::vector<std::string>& header, Fn row) {
  std::ifstream in(path);
  if (!in) throw DatasetError(path + ": cannot open");
  std::string line;
  if (!std::getline(in, line) || splitCsv(line) != header) {
    std::string h;
    for (const auto& c : header) h += (h.empty() ? "" : ",") + c;
    throw DatasetError(path + ": expected the header '" + h + "'");
  }
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto cells = splitCsv(line);
    if (cells.size() != header.size())
      throw DatasetError(path + ":" + std::to_string(line_no) + ": expected " +
                         std::to_string(header.size()) + " columns, got " +
                         std::to_string(cells.size()));
    row(cells, line_no);
  }
}

SequenceInfo sequenceInfoOf(const YAML::Node& root, const std::string& path) {
  SequenceInfo info;
  info.name = required<std::string>(root, "name", path);
  info.source = root["source"] ? root["source"].as<std::string>() : "";
  info.fps = required<double>(root, "fps", path);
  if (!(info.fps > 0) || !std::isfinite(info.fps))
    throw DatasetError(path + ": fps must be a positive number");
  info.frames = root["frames"] ? root["frames"].as<int>() : 0;
  const YAML::Node cam = root["camera"];
  if (!cam || !cam.IsMap()) throw DatasetError(path + ": missing map 'camera'");
  const std::string cam_path = path + " (camera)";
  std::array<double, 5> dist{0, 0, 0, 0, 0};
  if (cam["distortion"]) {
    const auto d = cam["distortion"].as<std::vector<double>>();
    if (d.size() != 5)
      throw DatasetError(path + ": camera.distortion must have 5 values (k1 k2 p1 p2 k3)");
    std::copy(d.begin(), d.end(), dist.begin());
  }
  info.camera = CameraModel(
      required<int>(cam, "width", cam_path), required<int>(cam, "height", cam_path),
      required<double>(cam, "fx", cam_path), required<double>(cam, "fy", cam_path),
      required<double>(cam, "cx", cam_path), required<double>(cam, "cy", cam_path), dist);
  if (!info.camera.valid()) throw DatasetError(path + ": camera intrinsics are not valid");
  if (root["classes"]) info.classes = root["classes"].as<std::vector<std::string>>();
  if (root["notes"]) info.notes = root["notes"].as<std::string>();
  return info;
}
}  // namespace

SequenceInfo readSequenceInfo(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw DatasetError(path + ": cannot open (not a sequence folder?)");
  } catch (const YAML::Exception& e) {
    throw DatasetError(path + ": YAML error: " + e.what());
  }
  // Every value of the wrong type is refused naming the file (yaml-cpp's conversions throw).
  try {
    return sequenceInfoOf(root, path);
  } catch (const YAML::Exception& e) {
    throw DatasetError(path + ": a value of the wrong type: " + e.what());
  }
}

void writeSequenceInfo(const std::string& path, const SequenceInfo& info) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  e << YAML::Key << "name" << YAML::Value << info.name;
  e << YAML::Key << "source" << YAML::Value << info.source;
  e << YAML::Key << "fps" << YAML::Value << info.fps;
  e << YAML::Key << "frames" << YAML::Value << info.frames;
  e << YAML::Key << "camera" << YAML::Value << YAML::BeginMap;
  const CameraModel& c = info.camera;
  e << YAML::Key << "width" << YAML::Value << c.width() << YAML::Key << "height" << YAML::Value
    << c.height();
  e << YAML::Key << "fx" << YAML::Value << c.fx() << YAML::Key << "fy" << YAML::Value << c.fy();
  e << YAML::Key << "cx" << YAML::Value << c.cx() << YAML::Key << "cy" << YAML::Value << c.cy();
  e << YAML::Key << "distortion" << YAML::Value << YAML::Flow
    << std::vector<double>(c.distortion().begin(), c.distortion().end());
  e << YAML::EndMap;
  e << YAML::Key << "classes" << YAML::Value << YAML::Flow << info.classes;
  e << YAML::Key << "notes" << YAML::Value << info.notes;
  e << YAML::EndMap;
  std::ofstream out(path);
  out << e.c_str() << "\n";
  if (!out) throw DatasetError(path + ": write failed");
}

SequenceFolder SequenceFolder::open(const std::string& dir) {
  SequenceFolder s;
  s.dir_ = dir;
  if (!fs::is_directory(dir)) throw DatasetError(dir + ": not a folder");
  s.info_ = readSequenceInfo((fs::path(dir) / "sequence.yaml").string());
  const fs::path rgb = fs::path(dir) / "rgb";
  if (!fs::is_directory(rgb)) throw DatasetError(rgb.string() + ": missing frame folder");
  for (const auto& e : fs::directory_iterator(rgb))
    if (e.is_regular_file() && isImageFile(e.path())) s.frames_.push_back(e.path().string());
  std::sort(s.frames_.begin(), s.frames_.end());
  if (s.frames_.empty()) throw DatasetError(rgb.string() + ": no .png or .jpg frames");
  s.timestamps_.resize(s.frames_.size());
  for (size_t i = 0; i < s.frames_.size(); ++i)
    s.timestamps_[i] = static_cast<double>(i) / s.info_.fps;
  const fs::path ts = fs::path(dir) / "timestamps.txt";
  if (fs::exists(ts)) {
    std::ifstream in(ts);
    std::string line;
    int line_no = 0;
    std::vector<bool> seen(s.frames_.size(), false);
    while (std::getline(in, line)) {
      ++line_no;
      if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
      std::istringstream ls(line);
      long idx;
      double t;
      if (!(ls >> idx >> t))
        throw DatasetError(ts.string() + ":" + std::to_string(line_no) +
                           ": expected '<frame index> <seconds>'");
      if (idx < 0 || idx >= static_cast<long>(s.frames_.size()))
        throw DatasetError(ts.string() + ":" + std::to_string(line_no) + ": frame index " +
                           std::to_string(idx) + " out of range");
      s.timestamps_[idx] = t;
      seen[idx] = true;
    }
    for (size_t i = 0; i < seen.size(); ++i)
      if (!seen[i])
        throw DatasetError(ts.string() + ": no timestamp for frame " + std::to_string(i));
  }
  return s;
}

bool SequenceFolder::hasGroundTruth() const {
  return fs::exists(fs::path(dir_) / "groundtruth.txt");
}
std::vector<TimedPose> SequenceFolder::groundTruth() const {
  try {
    return readTum((fs::path(dir_) / "groundtruth.txt").string());
  } catch (const TumError& e) {
    throw DatasetError(e.what());
  }
}
bool SequenceFolder::hasBoxes() const { return fs::exists(fs::path(dir_) / "boxes.csv"); }
std::vector<GroundTruthBox> SequenceFolder::boxes() const {
  return readBoxes((fs::path(dir_) / "boxes.csv").string());
}
bool SequenceFolder::hasObjects() const { return fs::exists(fs::path(dir_) / "objects.csv"); }
std::vector<GroundTruthObject> SequenceFolder::objects() const {
  return readObjects((fs::path(dir_) / "objects.csv").string());
}
std::string SequenceFolder::depthPath(size_t i) const {
  const fs::path p = fs::path(dir_) / "depth" / (fs::path(frames_[i]).stem().string() + ".png");
  return fs::exists(p) ? p.string() : "";
}

std::vector<GroundTruthBox> readBoxes(const std::string& path) {
  std::vector<GroundTruthBox> out;
  readCsv(path, {"frame", "x", "y", "w", "h", "class", "instance"},
          [&](const std::vector<std::string>& c, int line) {
            GroundTruthBox b;
            b.frame = toInt(c[0], path, line);
            b.x = toDouble(c[1], path, line);
            b.y = toDouble(c[2], path, line);
            b.w = toDouble(c[3], path, line);
            b.h = toDouble(c[4], path, line);
            b.cls = c[5];
            b.instance = c[6];
            out.push_back(b);
          });
  return out;
}

std::vector<GroundTruthObject> readObjects(const std::string& path) {
  std::vector<GroundTruthObject> out;
  readCsv(path, {"instance", "class", "cx", "cy", "cz", "sx", "sy", "sz"},
          [&](const std::vector<std::string>& c, int line) {
            GroundTruthObject o;
            o.instance = c[0];
            o.cls = c[1];
            for (int k = 0; k < 3; ++k) {
              o.center[k] = toDouble(c[2 + k], path, line);
              o.size[k] = toDouble(c[5 + k], path, line);
            }
            out.push_back(o);
          });
  return out;
}

void writeBoxes(const std::string& path, const std::vector<GroundTruthBox>& boxes) {
  std::ofstream out(path);
  out << "frame,x,y,w,h,class,instance\n";
  char buf[128];
  for (const auto& b : boxes) {
    std::snprintf(buf, sizeof(buf), "%d,%.1f,%.1f,%.1f,%.1f,", b.frame, b.x, b.y, b.w, b.h);
    out << buf << b.cls << "," << b.instance << "\n";
  }
  if (!out) throw DatasetError(path + ": write failed");
}

void writeObjects(const std::string& path, const std::vector<GroundTruthObject>& objects) {
  std::ofstream out(path);
  out << "instance,class,cx,cy,cz,sx,sy,sz\n";
  char buf[256];
  for (const auto& o : objects) {
    std::snprintf(buf, sizeof(buf), ",%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", o.center.x(), o.center.y(),
                  o.center.z(), o.size.x(), o.size.y(), o.size.z());
    out << o.instance << "," << o.cls << buf;
  }
  if (!out) throw DatasetError(path + ": write failed");
}

ObjectSet ObjectSet::open(const std::string& dir) {
  ObjectSet set;
  set.dir_ = dir;
  if (!fs::is_directory(dir)) throw DatasetError(dir + ": not an object set folder");
  std::set<std::string> categories;
  for (const auto& cat : fs::directory_iterator(dir)) {
    if (!cat.is_directory()) continue;
    const std::string category = cat.path().filename().string();
    for (const auto& inst : fs::directory_iterator(cat.path())) {
      if (!inst.is_directory()) continue;
      const std::string instance = inst.path().filename().string();
      if (instance.rfind(category + "_", 0) != 0)
        throw DatasetError(inst.path().string() + ": instance folder must be named " + category +
                           "_<n>");
      for (const auto& f : fs::directory_iterator(inst.path())) {
        const std::string name = f.path().filename().string();
        const std::string suffix = "_crop.png";
        if (name.size() <= suffix.size() ||
            name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
          continue;
        // <instance>_<video>_<frame>_crop.png
        const std::string stem = name.substr(0, name.size() - suffix.size());
        if (stem.rfind(instance + "_", 0) != 0)
          throw DatasetError(f.path().string() + ": file name must start with " + instance + "_");
        const std::string rest = stem.substr(instance.size() + 1);
        const size_t us = rest.find('_');
        ObjectView v;
        try {
          if (us == std::string::npos) throw std::invalid_argument(rest);
          v.video = std::stoi(rest.substr(0, us));
          v.frame = std::stoi(rest.substr(us + 1));
        } catch (const std::exception&) {
          throw DatasetError(f.path().string() + ": expected <instance>_<video>_<frame>_crop.png");
        }
        v.category = category;
        v.instance = instance;
        v.crop_path = f.path().string();
        const fs::path base = inst.path() / stem;
        const fs::path mask = base.string() + "_maskcrop.png";
        if (fs::exists(mask)) v.mask_path = mask.string();
        const fs::path loc = base.string() + "_loc.txt";
        if (fs::exists(loc)) {
          std::ifstream in(loc);
          std::string line;
          std::getline(in, line);
          const auto cells = splitCsv(line);
          if (cells.size() != 2) throw DatasetError(loc.string() + ": expected 'x,y'");
          v.loc_x = toInt(cells[0], loc.string(), 1);
          v.loc_y = toInt(cells[1], loc.string(), 1);
          v.has_location = true;
        }
        set.views_.push_back(std::move(v));
        categories.insert(category);
      }
    }
  }
  if (set.views_.empty()) throw DatasetError(dir + ": no *_crop.png views found");
  std::sort(set.views_.begin(), set.views_.end(), [](const ObjectView& a, const ObjectView& b) {
    return std::tie(a.category, a.instance, a.video, a.frame) <
           std::tie(b.category, b.instance, b.video, b.frame);
  });
  set.categories_.assign(categories.begin(), categories.end());
  // set.yaml is read line by line: the generator's own notes were not valid YAML before it quoted
  // them.
  std::ifstream yaml(fs::path(dir) / "set.yaml");
  for (std::string line; std::getline(yaml, line);)
    if (line.rfind("source: synth", 0) == 0 ||
        line.find("rendered by slamaware-synth") != std::string::npos)
      set.rendered_ = true;
  return set;
}

std::map<std::string, std::vector<std::string>> ObjectSet::instances() const {
  std::map<std::string, std::set<std::string>> m;
  for (const auto& v : views_) m[v.category].insert(v.instance);
  std::map<std::string, std::vector<std::string>> out;
  for (auto& [c, s] : m) out[c].assign(s.begin(), s.end());
  return out;
}

bool isSyntheticSequence(const SequenceFolder& sequence) {
  if (sequence.info().source.rfind("synth", 0) == 0) return true;
  return sequence.size() > 0 && !sequence.depthPath(0).empty();
}

std::string folderName(const std::string& dir) {
  std::filesystem::path p = std::filesystem::path(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

}  // namespace slamaware
