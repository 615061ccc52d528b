#include "common/bus/log_reader.h"

#include <sys/stat.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>

namespace slamaware {

namespace {
constexpr int64_t kHeaderBytes =
    4 + 8 + 8 + 4 + 4;  // sync, eventnum, timestamp, channel len, data len
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
  if (pending_error_) {
    done_ = true;
    throw *pending_error_;
  }
  const lcm::LogEvent* ev = log_->readNextEvent();
  if (!ev) {
    done_ = true;
    if (expected_offset_ == file_size_) return std::nullopt;
    // LCM refuses an intact event when the header after it is damaged ("Invalid header after
    // log data"): read that event ourselves and report the damage where it really is.
    std::optional<LogRecord> intact = readEventAt(expected_offset_);
    const int64_t bad = intact ? intact->offset + recordSize(*intact) : expected_offset_;
    LogError error(path_ + ": corrupt log: " + std::to_string(file_size_ - bad) +
                       " bytes at byte offset " + std::to_string(bad) +
                       " do not form a complete event (truncated or damaged)",
                   bad);
    if (!intact) throw error;
    done_ = false;
    pending_error_ = std::make_unique<LogError>(error);
    expected_offset_ = bad;
    return intact;
  }
  const int64_t end = std::ftell(log_->getFilePtr());
  const int64_t size = kHeaderBytes + static_cast<int64_t>(ev->channel.size()) + ev->datalen;
  const int64_t start = end - size;
  if (start != expected_offset_) {
    done_ = true;
    throw LogError(path_ + ": corrupt log: damaged event header at byte offset " +
                       std::to_string(expected_offset_) + " (" +
                       std::to_string(start - expected_offset_) +
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

int64_t LogReader::recordSize(const LogRecord& r) {
  return kHeaderBytes + static_cast<int64_t>(r.channel.size()) +
         static_cast<int64_t>(r.data.size());
}

std::optional<LogRecord> LogReader::readEventAt(int64_t offset) const {
  // The event layout: sync word, eventnum, timestamp, channel length, data length (big-endian),
  // then the channel name and the data.
  std::FILE* f = std::fopen(path_.c_str(), "rb");
  if (!f) return std::nullopt;
  std::optional<LogRecord> out;
  uint8_t h[kHeaderBytes];
  auto be = [&](int at, int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | h[at + i];
    return v;
  };
  if (std::fseek(f, offset, SEEK_SET) == 0 && std::fread(h, 1, kHeaderBytes, f) == kHeaderBytes &&
      be(0, 4) == 0xEDA1DA01u) {
    const int64_t channel_len = static_cast<int32_t>(be(20, 4));
    const int64_t data_len = static_cast<int32_t>(be(24, 4));
    if (channel_len > 0 && channel_len < 1000 && data_len >= 0 &&
        offset + kHeaderBytes + channel_len + data_len <= file_size_) {
      LogRecord r;
      r.eventnum = static_cast<int64_t>(be(4, 8));
      r.timestamp = static_cast<int64_t>(be(12, 8));
      r.channel.resize(channel_len);
      r.data.resize(data_len);
      r.offset = offset;
      if (std::fread(r.channel.data(), 1, channel_len, f) == static_cast<size_t>(channel_len) &&
          std::fread(r.data.data(), 1, data_len, f) == static_cast<size_t>(data_len))
        out = std::move(r);
    }
  }
  std::fclose(f);
  return out;
}

std::vector<LogRecord> LogReader::readAll(const std::string& path) {
  LogReader reader(path);
  std::vector<LogRecord> out;
  while (auto r = reader.next()) out.push_back(std::move(*r));
  return out;
}

}  // namespace slamaware
