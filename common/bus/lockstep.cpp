#include "common/bus/lockstep.h"

#include <algorithm>
#include <chrono>
#include <memory>
#include <set>

#include "common/bus/bus.h"
#include "common/bus/frame_stamp.h"
#include "common/bus/shutdown.h"

namespace slamaware {

using Clock = std::chrono::steady_clock;

LockstepGate::LockstepGate(Bus& bus, const std::string& channel, int window)
    : bus_(bus), channel_(channel), window_(static_cast<size_t>(std::max(1, window))) {
  bus_.subscribeRaw(channel_, [this](const Bus::RawMessage& m) {
    if (auto s = peekFrameStamp(m.data, m.size))
      acked_ = std::max(acked_, s->seq);
    else
      bus_.reject(m.channel, "not a well-formed per-frame message (lockstep answer)");
  });
}

bool LockstepGate::waitFor(int32_t seq, double timeout_s, const std::function<void()>& idle) {
  const auto start = Clock::now();
  while (acked_ < seq) {
    if (shutdownRequested()) return false;
    if (Clock::now() - start > std::chrono::duration<double>(timeout_s)) return false;
    bus_.handle(20);
    if (idle) idle();
  }
  return true;
}

bool LockstepGate::waitForRoom(bool all, double timeout_s, const std::function<void()>& idle,
                               int32_t* timed_out) {
  const size_t room = all ? 0 : window_ - 1;
  while (true) {
    while (!waiting_.empty() && waiting_.front() <= acked_) waiting_.pop_front();
    if (waiting_.size() <= room) return true;
    const int32_t oldest = waiting_.front();
    if (!waitFor(oldest, timeout_s, idle)) {
      if (!shutdownRequested()) {
        waiting_.pop_front();
        if (timed_out) *timed_out = oldest;
      }
      return false;
    }
  }
}

std::vector<std::string> waitForChannels(Bus& bus, const std::vector<std::string>& channels,
                                         double timeout_s, const std::function<void()>& idle) {
  auto waiting = std::make_shared<std::set<std::string>>(channels.begin(), channels.end());
  for (const auto& c : channels)
    bus.subscribeRaw(c, [waiting, c](const Bus::RawMessage&) { waiting->erase(c); });
  const auto start = Clock::now();
  while (!waiting->empty() && !shutdownRequested() &&
         Clock::now() - start < std::chrono::duration<double>(timeout_s)) {
    bus.handle(50);
    if (idle) idle();
  }
  return {waiting->begin(), waiting->end()};
}

std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= s.size()) {
    const size_t comma = std::min(s.find(',', start), s.size());
    if (comma > start) out.push_back(s.substr(start, comma - start));
    start = comma + 1;
  }
  return out;
}

}  // namespace slamaware
