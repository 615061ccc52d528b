#pragma once
// <NAME>_STATUS heartbeat at 1 Hz (docs/architecture.md §1): state, last input handled, queue
// depth, frames processed and dropped, rejects of the bus, the heap (heap.used_kb, heap.free_kb:
// glibc's mallinfo2), and the process's own counters. A
// change of state goes out at once (at most 10 per second): the supervisor learns that a process
// it restarted is running when it is, not up to a second later.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace slamaware {

class Bus;

class StatusReporter {
 public:
  enum class State : int8_t { kStarting = 0, kRunning = 1, kDegraded = 2, kStopping = 3 };

  /// Publishes on `channel` for process `name`; the first status goes out at the first tick() or
  /// change of state.
  StatusReporter(Bus& bus, std::string name, std::string channel);

  /// A new state is published at once, or at the first tick() 0.1 s after the last status.
  void setState(State s);
  /// The last input message handled (its frame utime and seq).
  void noteInput(int64_t utime, int32_t seq);
  void addProcessed(int64_t n = 1);
  void addDropped(int64_t n = 1);
  void setQueueDepth(int32_t n);
  /// Adds to (or sets) a named counter reported in the status.
  void count(const std::string& counter, int64_t n = 1);
  void setCounter(const std::string& counter, int64_t value);
  int64_t counter(const std::string& counter) const;
  /// The last warning or error worth showing to an operator (sent until replaced).
  void setMessage(const std::string& message);

  /// Publishes if a second has passed since the last status, or 0.1 s when the state changed
  /// since. Call often (main loop).
  void tick();
  /// Publishes now.
  void publish();

  int64_t processed() const;
  int64_t dropped() const;

 private:
  Bus& bus_;
  std::string name_, channel_;
  mutable std::mutex mutex_;
  State state_ = State::kStarting;
  int64_t last_input_utime_ = 0;
  int32_t last_input_seq_ = -1;
  int32_t queue_depth_ = 0;
  int64_t processed_ = 0, dropped_ = 0;
  std::map<std::string, int64_t> counters_;
  std::string message_;
  bool state_changed_ = false;  ///< the state changed since the last status
  std::chrono::steady_clock::time_point last_publish_{};
  static constexpr std::chrono::milliseconds kStateChangeGap{100};
};

}  // namespace slamaware
