#include "common/bus/log_reader.h"

#include <sys/stat.h>
#include <unistd.h>

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
  if (expected_offset_ == file_size_) {
    done_ = true;
    return std::nullopt;
  }
  // The header is checked before LCM reads the event: LCM allocates whatever length a header
  // claims (a damaged one can claim 2 GB) and skips garbage silently.
  if (!headerAt(expected_offset_)) {
    done_ = true;
    throw damageAt(expected_offset_);
  }
  const lcm::LogEvent* ev = log_->readNextEvent();
  if (!ev) {
    done_ = true;
    // LCM refuses an intact event when the header after it is damaged ("Invalid header after
    // log data"): read that event ourselves and report the damage where it really is.
    std::optional<LogRecord> intact = readEventAt(expected_offset_);
    if (!intact) throw damageAt(expected_offset_);
    const int64_t bad = intact->offset + recordSize(*intact);
    done_ = false;
    pending_error_ = std::make_unique<LogError>(damageAt(bad));
    expected_offset_ = bad;
    return intact;
  }
  const int64_t end = std::ftell(log_->getFilePtr());
  const int64_t size = kHeaderBytes + static_cast<int64_t>(ev->channel.size()) + ev->datalen;
  if (end - size != expected_offset_) {  // a guard: LCM scans only when the sync word is not there
    done_ = true;
    throw damageAt(expected_offset_);
  }
  LogRecord r;
  r.eventnum = ev->eventnum;
  r.timestamp = ev->timestamp;
  r.channel = ev->channel;
  r.offset = expected_offset_;
  const auto* d = static_cast<const uint8_t*>(ev->data);
  r.data.assign(d, d + ev->datalen);
  expected_offset_ = end;
  return r;
}

LogError LogReader::damageAt(int64_t offset) const {
  return LogError(path_ + ": corrupt log: " + std::to_string(file_size_ - offset) +
                      " bytes at byte offset " + std::to_string(offset) +
                      " do not form a complete event (truncated or damaged)",
                  offset);
}

int64_t LogReader::recordSize(const LogRecord& r) {
  return kHeaderBytes + static_cast<int64_t>(r.channel.size()) +
         static_cast<int64_t>(r.data.size());
}

std::optional<LogReader::Header> LogReader::headerAt(int64_t offset) const {
  // The event layout: sync word, eventnum, timestamp, channel length, data length (big-endian),
  // then the channel name and the data.
  uint8_t h[kHeaderBytes];
  if (pread(fileno(log_->getFilePtr()), h, kHeaderBytes, offset) != kHeaderBytes)
    return std::nullopt;
  auto be = [&](int at, int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | h[at + i];
    return v;
  };
  if (be(0, 4) != 0xEDA1DA01u) return std::nullopt;
  Header out;
  out.eventnum = static_cast<int64_t>(be(4, 8));
  out.timestamp = static_cast<int64_t>(be(12, 8));
  out.channel_len = static_cast<int32_t>(be(20, 4));
  out.data_len = static_cast<int32_t>(be(24, 4));
  if (out.channel_len <= 0 || out.channel_len >= 1000 || out.data_len < 0 ||
      offset + kHeaderBytes + out.channel_len + out.data_len > file_size_)
    return std::nullopt;
  return out;
}

std::optional<LogRecord> LogReader::readEventAt(int64_t offset) const {
  const std::optional<Header> h = headerAt(offset);
  if (!h) return std::nullopt;
  LogRecord r;
  r.eventnum = h->eventnum;
  r.timestamp = h->timestamp;
  r.offset = offset;
  r.channel.resize(h->channel_len);
  r.data.resize(h->data_len);
  const int fd = fileno(log_->getFilePtr());
  if (pread(fd, r.channel.data(), h->channel_len, offset + kHeaderBytes) != h->channel_len ||
      pread(fd, r.data.data(), h->data_len, offset + kHeaderBytes + h->channel_len) != h->data_len)
    return std::nullopt;
  return r;
}

std::vector<LogRecord> LogReader::readAll(const std::string& path) {
  LogReader reader(path);
  std::vector<LogRecord> out;
  while (auto r = reader.next()) out.push_back(std::move(*r));
  return out;
}

}  // namespace slamaware
