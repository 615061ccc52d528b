#include "procs/objectmap/map_store.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <stdexcept>

#include "common/atomic_file.h"
#include "procs/objectmap/json_number.h"

namespace slamaware::objectmap {

namespace fs = std::filesystem;

namespace {

const std::regex kJsonPattern(R"(objectmap-(\d{6,})\.json)");
const std::regex kSegmentPattern(R"(objectmap-(\d{6,})-seg(-?\d+)\.ot)");
const std::string kContentKey = "\n\"content\":";

bool readFile(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

}  // namespace

MapStore::MapStore(std::string dir) : dir_(std::move(dir)) {}

MapStore::~MapStore() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

std::string MapStore::jsonName(int64_t generation) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "objectmap-%06lld.json", static_cast<long long>(generation));
  return buf;
}

std::string MapStore::segmentName(int64_t generation, int32_t segment) {
  char buf[80];
  std::snprintf(buf, sizeof(buf), "objectmap-%06lld-seg%d.ot", static_cast<long long>(generation),
                segment);
  return buf;
}

bool MapStore::lock(std::string* why) {
  if (lock_fd_ >= 0) return true;
  std::error_code ec;
  fs::create_directories(dir_, ec);
  const std::string path = (fs::path(dir_) / "objectmap.lock").string();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    *why = path + ": cannot open the lock file: " + std::strerror(errno);
    return false;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    *why = "the map folder " + dir_ + " is in use by another slamaware-objectmap (" + path +
           " is locked)";
    ::close(fd);
    return false;
  }
  lock_fd_ = fd;
  return true;
}

size_t MapStore::removeTemporaryFiles() {
  size_t n = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind("objectmap-", 0) == 0 && name.find(".tmp.") != std::string::npos &&
        fs::remove(it->path(), ec))
      ++n;
  }
  return n;
}

void MapStore::scan() {
  // The next generation is above every generation on disk, damaged ones included: a damaged
  // newer file is never overwritten.
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::smatch m;
    if (std::regex_match(name, m, kJsonPattern) || std::regex_match(name, m, kSegmentPattern))
      next_generation_ = std::max<int64_t>(next_generation_, std::stoll(m[1].str()) + 1);
  }
  scanned_ = true;
}

int64_t MapStore::nextGeneration() {
  if (!scanned_) scan();
  return next_generation_;
}

MapSnapshot MapStore::readGeneration(int64_t generation, std::map<int32_t, FileRef>* files) const {
  const std::string path = (fs::path(dir_) / jsonName(generation)).string();
  auto fail = [&](const std::string& why) { throw std::runtime_error(path + ": " + why); };
  std::string text;
  if (!readFile(path, &text)) fail("cannot read the file");
  if (text.empty()) fail("empty file");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    fail(std::string("not valid JSON (truncated or damaged): ") + e.what());
  }
  int64_t content_bytes = 0;
  uint32_t content_crc = 0;
  try {
    const std::string format = doc.at("format").get<std::string>();
    if (format != kFormat) fail("not a slamaware object map (format '" + format + "')");
    const int version = jsonInt<int>(doc.at("version"));
    if (version != kVersion)
      fail("format version " + std::to_string(version) + ", this build reads version " +
           std::to_string(kVersion));
    const int64_t g = jsonInt<int64_t>(doc.at("generation"));
    if (g != generation) fail("header says generation " + std::to_string(g) + " (damaged)");
    content_bytes = jsonInt<int64_t>(doc.at("content_bytes"));
    content_crc = jsonInt<uint32_t>(doc.at("content_crc32"));
    if (!doc.at("content").is_object()) fail("content is not an object");
  } catch (const std::exception& e) {  // nlohmann's, and jsonInt's out-of-range integers
    fail(std::string("header field missing or of the wrong type: ") + e.what());
  }
  // The checksum covers the content's bytes as written (not a re-serialisation).
  const size_t start = text.find(kContentKey);
  if (start == std::string::npos) fail("no content line (damaged)");
  const size_t begin = start + kContentKey.size();
  if (content_bytes < 0 || begin + static_cast<size_t>(content_bytes) + 2 != text.size() ||
      text.compare(begin + static_cast<size_t>(content_bytes), 2, "}\n") != 0)
    fail("content is " + std::to_string(text.size() >= begin + 2 ? text.size() - begin - 2 : 0) +
         " bytes, the header says " + std::to_string(content_bytes) + " (truncated or damaged)");
  if (crc32(text.data() + begin, static_cast<size_t>(content_bytes)) != content_crc)
    fail("content checksum mismatch (the file is damaged)");

  MapSnapshot snapshot;
  snapshot.content = std::move(doc.at("content"));
  files->clear();
  try {
    for (const auto& seg : snapshot.content.at("segments")) {
      FileRef ref;
      const int32_t id = jsonInt<int32_t>(seg.at("id"));
      ref.name = seg.at("file").get<std::string>();
      ref.bytes = jsonInt<size_t>(seg.at("bytes"));
      ref.crc = jsonInt<uint32_t>(seg.at("crc32"));
      if (ref.name.find('/') != std::string::npos || !std::regex_match(ref.name, kSegmentPattern))
        fail("segment " + std::to_string(id) + " names an unexpected file '" + ref.name + "'");
      const std::string ot = (fs::path(dir_) / ref.name).string();
      std::string bytes;
      if (!readFile(ot, &bytes))
        throw std::runtime_error(ot + ": missing or unreadable (named by " + path + ")");
      if (bytes.size() != ref.bytes)
        throw std::runtime_error(ot + ": " + std::to_string(bytes.size()) + " bytes, " + path +
                                 " says " + std::to_string(ref.bytes) + " (truncated or damaged)");
      if (crc32(bytes.data(), bytes.size()) != ref.crc)
        throw std::runtime_error(ot + ": checksum mismatch (the file is damaged)");
      snapshot.segment_files[id] = std::move(bytes);
      (*files)[id] = ref;
    }
  } catch (const std::exception& e) {  // nlohmann's, and jsonInt's out-of-range integers
    fail(std::string("segment list missing or of the wrong type: ") + e.what());
  }
  return snapshot;
}

LoadReport MapStore::load(const std::function<void(const MapSnapshot&)>& accept) {
  LoadReport report;
  if (!scanned_) scan();
  std::set<int64_t, std::greater<>> generations;
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    std::smatch m;
    const std::string name = it->path().filename().string();
    if (std::regex_match(name, m, kJsonPattern)) generations.insert(std::stoll(m[1].str()));
  }
  for (int64_t g : generations) {
    std::map<int32_t, FileRef> files;
    try {
      const MapSnapshot snapshot = readGeneration(g, &files);
      try {
        accept(snapshot);
      } catch (
          const std::exception& e) {  // a table the map cannot take: refused by its file's name
        throw std::runtime_error((fs::path(dir_) / jsonName(g)).string() + ": " + e.what());
      }
    } catch (const std::exception& e) {
      report.failures.push_back(e.what());
      continue;
    }
    report.generation = g;
    report.json_path = (fs::path(dir_) / jsonName(g)).string();
    good_generation_ = g;
    good_files_ = std::move(files);
    break;
  }
  return report;
}

SaveReport MapStore::save(MapSnapshot snapshot) {
  const auto t0 = std::chrono::steady_clock::now();
  SaveReport report;
  const int64_t generation = nextGeneration();
  report.generation = generation;
  nlohmann::json& content = snapshot.content;
  std::map<int32_t, FileRef> files;
  // 1. The segments' .ot files: an unchanged one (same size and checksum as in the previous good
  // generation, still on disk) is referenced again instead of written again.
  for (auto& seg : content.at("segments")) {
    const int32_t id = jsonInt<int32_t>(seg.at("id"));
    auto blob = snapshot.segment_files.find(id);
    if (blob == snapshot.segment_files.end())
      throw std::runtime_error("object map snapshot: no .ot bytes for segment " +
                               std::to_string(id));
    FileRef ref;
    ref.bytes = blob->second.size();
    ref.crc = crc32(blob->second.data(), blob->second.size());
    auto old = good_files_.find(id);
    std::error_code ec;
    if (old != good_files_.end() && old->second.bytes == ref.bytes && old->second.crc == ref.crc &&
        fs::file_size(fs::path(dir_) / old->second.name, ec) == ref.bytes && !ec) {
      ref.name = old->second.name;
    } else {
      ref.name = segmentName(generation, id);
      writeFileAtomic((fs::path(dir_) / ref.name).string(), blob->second.data(),
                      blob->second.size());
      report.bytes_written += ref.bytes;
    }
    seg["file"] = ref.name;
    seg["bytes"] = ref.bytes;
    seg["crc32"] = ref.crc;
    report.segment_paths[id] = (fs::path(dir_) / ref.name).string();
    files[id] = ref;
  }
  // 2. The JSON: its rename commits the generation.
  // Class names come from other processes: bytes that are not UTF-8 are replaced, not fatal.
  const std::string body = content.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  content = nlohmann::json();  // the tree is several times the text: freed before the file is built
  std::string text =
      "{\"format\":\"" + std::string(kFormat) + "\",\"version\":" + std::to_string(kVersion) +
      ",\"generation\":" + std::to_string(generation) +
      ",\"content_bytes\":" + std::to_string(body.size()) +
      ",\"content_crc32\":" + std::to_string(crc32(body.data(), body.size())) + "," + kContentKey;
  text += body;
  text += "}\n";
  report.json_path = (fs::path(dir_) / jsonName(generation)).string();
  writeFileAtomic(report.json_path, text.data(), text.size());
  report.bytes_written += text.size();
  next_generation_ = generation + 1;
  // 3. Only now: the generations before the previous good one go.
  std::set<std::string> keep{jsonName(generation)};
  for (const auto& [id, ref] : files) keep.insert(ref.name);
  if (good_generation_ >= 0) {
    keep.insert(jsonName(good_generation_));
    for (const auto& [id, ref] : good_files_) keep.insert(ref.name);
  }
  good_generation_ = generation;
  good_files_ = std::move(files);
  report.files_removed = removeOld(generation, keep);
  report.ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

size_t MapStore::removeOld(int64_t newest, const std::set<std::string>& keep) {
  // The kept generations' files are known from their load or save: the JSON is not read again
  // (parsing it took as much memory and time as building it). Anything newer than `newest` stays
  // (none is expected: generations are numbered above everything on disk).
  size_t removed = 0;
  std::error_code ec;
  std::vector<fs::path> doomed;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::smatch m;
    if (keep.count(name)) continue;
    if ((std::regex_match(name, m, kJsonPattern) || std::regex_match(name, m, kSegmentPattern)) &&
        std::stoll(m[1].str()) <= newest)
      doomed.push_back(it->path());
  }
  // JSON files first: a generation whose JSON is gone is no longer a candidate for loading.
  std::sort(doomed.begin(), doomed.end(), [](const fs::path& a, const fs::path& b) {
    return std::make_pair(a.extension() != ".json", a) <
           std::make_pair(b.extension() != ".json", b);
  });
  for (const auto& p : doomed)
    if (fs::remove(p, ec)) ++removed;
  return removed;
}

}  // namespace slamaware::objectmap
