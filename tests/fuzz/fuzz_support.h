#pragma once
// Helpers shared by the fuzz targets (tests/fuzz/README.md): a private scratch folder per process
// and the splitting of one input into the several files some readers need.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace slamaware::fuzz {

/// The path of this process's scratch folder (never destroyed: the exit handler that removes the
/// folder runs after static destructors).
inline const std::string& scratchPath() {
  static const std::string* const path = [] {
    const char* tmp = std::getenv("TMPDIR");
    auto* p = new std::string(std::string(tmp && *tmp ? tmp : "/tmp") + "/slamaware-fuzz-" +
                              std::to_string(::getpid()));
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratchPath(), ec);
    });
    return p;
  }();
  return *path;
}

/// This process's scratch folder (removed at exit), emptied on every call: each input starts from
/// nothing.
inline const std::string& scratchDir() {
  std::error_code ec;
  std::filesystem::remove_all(scratchPath(), ec);
  std::filesystem::create_directories(scratchPath());
  return scratchPath();
}

/// Writes a file, creating its folders; a path that cannot be made (a file where a folder should
/// be) is skipped: the folder is then simply without it.
inline void writeFile(const std::string& path, const uint8_t* data, size_t size) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (ec || std::filesystem::is_directory(path, ec)) return;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}
inline void writeFile(const std::string& path, const std::string& text) {
  writeFile(path, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

/// The parts of an input cut at every occurrence of kSeparator (the seeds are built this way).
inline const std::string kSeparator = "\n--8<--\n";
inline std::vector<std::string> splitParts(const uint8_t* data, size_t size) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> parts;
  size_t begin = 0;
  for (;;) {
    const size_t at = all.find(kSeparator, begin);
    if (at == std::string::npos) break;
    parts.push_back(all.substr(begin, at - begin));
    begin = at + kSeparator.size();
  }
  parts.push_back(all.substr(begin));
  return parts;
}
inline std::string joinParts(const std::vector<std::string>& parts) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? kSeparator : "") + parts[i];
  return out;
}

}  // namespace slamaware::fuzz
