#include "procs/supervisor/rotating_log.h"

#include <sys/stat.h>

#include <filesystem>

namespace slamaware::supervisor {

RotatingLog::RotatingLog(std::string path, size_t max_bytes, int keep)
    : path_(std::move(path)), max_bytes_(max_bytes), keep_(keep) {
  open();
}

RotatingLog::~RotatingLog() {
  if (file_) std::fclose(file_);
}

void RotatingLog::open() {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path_).parent_path(), ec);
  file_ = std::fopen(path_.c_str(), "a");
  if (!file_) {
    if (!failed_) std::fprintf(stderr, "supervisor: cannot write log %s\n", path_.c_str());
    failed_ = true;
    return;
  }
  struct stat st {};
  size_ = stat(path_.c_str(), &st) == 0 ? static_cast<size_t>(st.st_size) : 0;
}

void RotatingLog::rotate() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  for (int i = keep_; i >= 1; --i) {
    const std::string from = i == 1 ? path_ : path_ + "." + std::to_string(i - 1);
    std::rename(from.c_str(), (path_ + "." + std::to_string(i)).c_str());
  }
  if (keep_ <= 0) std::remove(path_.c_str());
  open();
}

void RotatingLog::write(const char* data, size_t n) {
  if (size_ + n > max_bytes_ && size_ > 0) rotate();
  if (!file_) return;
  std::fwrite(data, 1, n, file_);
  std::fflush(file_);
  size_ += n;
}

void RotatingLog::note(const std::string& line) {
  const std::string text = "--- " + line + " ---\n";
  write(text.data(), text.size());
}

}  // namespace slamaware::supervisor
