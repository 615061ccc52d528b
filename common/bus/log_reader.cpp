#include "common/bus/log_reader.h"

#include <sys/stat.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>

namespace slamaware {

namespace {
constexpr int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;  // sync, eventnum, timestamp, channel len, data len
}

LogReader::LogReader(const std::string& path) : path_(path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) throw LogError(path + ": cannot open log file", -1);
  file_size_ = st.st_size;
  log_ = std::make_unique<lcm::LogFile>(path, "r");
  if (!log_->good()) throw LogError(path + ": cannot open log file", -1);
}

LogReader::~LogReader() = default;

std::optional<LogRecord> LogReader::next() {
  if (done_) return std::nullopt;
  const lcm::LogEvent* ev = log_->readNextEvent();
  if (!ev) {
    done_ = true;
    if (expected_offset_ == file_size_) return std::nullopt;
    throw LogError(path_ + ": corrupt log: " + std::to_string(file_size_ - expected_offset_) +
                       " bytes at byte offset " + std::to_string(expected_offset_) +
                       " do not form a complete event (truncated or damaged)",
                   expected_offset_);
  }
  const int64_t end = std::ftell(log_->getFilePtr());
  const int64_t size = kHeaderBytes + static_cast<int64_t>(ev->channel.size()) + ev->datalen;
  const int64_t start = end - size;
  if (start != expected_offset_) {
    done_ = true;
    throw LogError(path_ + ": corrupt log: damaged event header at byte offset " +
                       std::to_string(expected_offset_) + " (" + std::to_string(start - expected_offset_) +
                       " bytes skipped before the next valid event)",
                   expected_offset_);
  }
  LogRecord r;
  r.eventnum = ev->eventnum;
  r.timestamp = ev->timestamp;
  r.channel = ev->channel;
  r.offset = start;
  const auto* d = static_cast<const uint8_t*>(ev->data);
  r.data.assign(d, d + ev->datalen);
  expected_offset_ = end;
  return r;
}

std::vector<LogRecord> LogReader::readAll(const std::string& path) {
  LogReader reader(path);
  std::vector<LogRecord> out;
  while (auto r = reader.next()) out.push_back(std::move(*r));
  return out;
}

}  // namespace slamaware
