#pragma once
// A log file that rotates by size: <path> is current, <path>.1 the previous one, ... <path>.N.
#include <cstddef>
#include <cstdio>
#include <string>

namespace slamaware::supervisor {

class RotatingLog {
 public:
  RotatingLog(std::string path, size_t max_bytes, int keep);
  ~RotatingLog();
  RotatingLog(const RotatingLog&) = delete;
  RotatingLog& operator=(const RotatingLog&) = delete;
  /// Appends bytes (rotating first when they would pass the size limit). Errors are reported
  /// once on stderr; the supervisor keeps going without the log.
  void write(const char* data, size_t n);
  /// Writes a line of the supervisor's own ("--- started pid 123 ---").
  void note(const std::string& line);
  const std::string& path() const { return path_; }

 private:
  void open();
  void rotate();
  std::string path_;
  size_t max_bytes_;
  int keep_;
  std::FILE* file_ = nullptr;
  size_t size_ = 0;
  bool failed_ = false;
};

}  // namespace slamaware::supervisor
