#pragma once
// Message rate and bandwidth over the last 2 s, for the console views of slamaware-ctl.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <utility>

namespace slamaware {

class RateMeter {
 public:
  using Clock = std::chrono::steady_clock;

  void tick(Clock::time_point now, size_t bytes = 0) {
    ++count_;
    recent_.emplace_back(now, bytes);
    while (now - recent_.front().first > std::chrono::seconds(2)) recent_.pop_front();
  }
  /// Messages per second over the window; 0 when fewer than 2 or the last is older than the window.
  double hz(Clock::time_point now) const {
    const double s = span(now);
    return s > 0 ? static_cast<double>(recent_.size() - 1) / s : 0;
  }
  /// kB per second over the window.
  double kbPerSecond(Clock::time_point now) const {
    const double s = span(now);
    if (s <= 0) return 0;
    size_t b = 0;
    for (const auto& r : recent_) b += r.second;
    return static_cast<double>(b) / 1024.0 / s;
  }
  int64_t count() const { return count_; }
  /// When the last message came (rates at this moment ignore how long ago that was).
  Clock::time_point lastTick() const {
    return recent_.empty() ? Clock::time_point{} : recent_.back().first;
  }

 private:
  double span(Clock::time_point now) const {
    if (recent_.size() < 2 || now - recent_.back().first > std::chrono::seconds(2)) return 0;
    return std::chrono::duration<double>(recent_.back().first - recent_.front().first).count();
  }
  std::deque<std::pair<Clock::time_point, size_t>> recent_;
  int64_t count_ = 0;
};

}  // namespace slamaware
