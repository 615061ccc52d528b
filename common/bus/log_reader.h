#pragma once
// Reading LCM log files (lcm-logger's format) so that a corrupt log is told from its end.
// lcm::LogFile silently skips damaged bytes (it scans for the next sync word) and returns NULL
// both at the end and on a truncated event; LogReader checks that every event starts where the
// previous one ended and that the last one ends at the end of the file, and says where not. A
// header is checked before LCM reads its event, so a damaged length never makes it allocate.
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace lcm {
class LogFile;
}

namespace slamaware {

class LogError : public std::runtime_error {
 public:
  LogError(const std::string& what, int64_t offset) : std::runtime_error(what), offset_(offset) {}
  /// Byte offset in the file where the problem starts (-1 when not about a position).
  int64_t offset() const { return offset_; }

 private:
  int64_t offset_;
};

struct LogRecord {
  int64_t eventnum = 0;
  int64_t timestamp = 0;  ///< µs, when the logger received the message
  std::string channel;
  std::vector<uint8_t> data;
  int64_t offset = 0;  ///< byte offset of the event in the file
};

/// Decodes a logged message as Msg; false when it fails to decode or leaves bytes over.
template <class Msg>
bool decodeRecord(const LogRecord& r, Msg* m) {
  try {
    return m->decode(r.data.data(), 0, static_cast<int>(r.data.size())) ==
           static_cast<int>(r.data.size());
  } catch (const std::exception&) {
    return false;
  }
}

class LogReader {
 public:
  /// Opens a log; throws LogError if it cannot be read.
  explicit LogReader(const std::string& path);
  ~LogReader();

  /// The next event, or std::nullopt at the clean end of the log. Throws LogError with the byte
  /// offset when the log is damaged (garbage between events, a bad header, a truncated event).
  std::optional<LogRecord> next();

  const std::string& path() const { return path_; }
  /// Reads a whole log; throws LogError like next().
  static std::vector<LogRecord> readAll(const std::string& path);

 private:
  struct Header {
    int64_t eventnum = 0, timestamp = 0, channel_len = 0, data_len = 0;
  };
  static int64_t recordSize(const LogRecord& r);
  /// The header at offset when it has the sync word and its event fits in the file.
  std::optional<Header> headerAt(int64_t offset) const;
  std::optional<LogRecord> readEventAt(int64_t offset) const;
  LogError damageAt(int64_t offset) const;

  std::string path_;
  std::unique_ptr<LogError> pending_error_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t file_size_ = 0;
  int64_t expected_offset_ = 0;
  bool done_ = false;
};

}  // namespace slamaware
