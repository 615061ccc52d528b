#include "common/bus/status.h"

#include <unistd.h>

#include "common/bus/bus.h"
#include "common/heap.h"
#include "slamaware/status_t.hpp"

namespace slamaware {

StatusReporter::StatusReporter(Bus& bus, std::string name, std::string channel)
    : bus_(bus), name_(std::move(name)), channel_(std::move(channel)) {}

void StatusReporter::setState(State s) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (s == state_) return;
    state_ = s;
    state_changed_ = true;
    if (std::chrono::steady_clock::now() - last_publish_ < kStateChangeGap) return;
  }
  publish();
}
void StatusReporter::noteInput(int64_t utime, int32_t seq) {
  std::lock_guard<std::mutex> lock(mutex_);
  last_input_utime_ = utime;
  last_input_seq_ = seq;
}
void StatusReporter::addProcessed(int64_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  processed_ += n;
}
void StatusReporter::addDropped(int64_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  dropped_ += n;
}
void StatusReporter::setQueueDepth(int32_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_depth_ = n;
}
void StatusReporter::count(const std::string& c, int64_t n) {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_[c] += n;
}
void StatusReporter::setCounter(const std::string& c, int64_t value) {
  std::lock_guard<std::mutex> lock(mutex_);
  counters_[c] = value;
}
int64_t StatusReporter::counter(const std::string& c) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = counters_.find(c);
  return it == counters_.end() ? 0 : it->second;
}
void StatusReporter::setMessage(const std::string& message) {
  std::lock_guard<std::mutex> lock(mutex_);
  message_ = message;
}
int64_t StatusReporter::processed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return processed_;
}
int64_t StatusReporter::dropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

void StatusReporter::tick() {
  const auto now = std::chrono::steady_clock::now();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto since = now - last_publish_;
    if (since < std::chrono::seconds(1) && !(state_changed_ && since >= kStateChangeGap)) return;
  }
  publish();
}

void StatusReporter::publish() {
  status_t msg{};
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_publish_ = std::chrono::steady_clock::now();
    state_changed_ = false;
    msg.utime = wallUtime();
    msg.name = name_;
    msg.pid = static_cast<int32_t>(getpid());
    msg.state = static_cast<int8_t>(state_);
    msg.last_input_utime = last_input_utime_;
    msg.last_input_seq = last_input_seq_;
    msg.queue_depth = queue_depth_;
    msg.frames_processed = processed_;
    msg.frames_dropped = dropped_;
    msg.message = message_;
    for (const auto& kv : counters_) {
      msg.counter_names.push_back(kv.first);
      msg.counter_values.push_back(kv.second);
    }
  }
  msg.rejected = 0;
  for (const auto& kv : bus_.rejects()) {
    msg.counter_names.push_back("rejected." + kv.first);
    msg.counter_values.push_back(kv.second);
    msg.rejected += kv.second;
  }
  for (const auto& kv : bus_.handlerErrors()) {
    msg.counter_names.push_back("errors." + kv.first);
    msg.counter_values.push_back(kv.second);
    msg.rejected += kv.second;
  }
  // The heap as the allocator sees it: what the process holds, and what it freed but keeps (RSS
  // that grows with heap.free_kb is the allocator's, with heap.used_kb the process's own).
  if (const auto heap = heapUse()) {
    msg.counter_names.push_back("heap.used_kb");
    msg.counter_values.push_back(static_cast<int64_t>(heap->used / 1024));
    msg.counter_names.push_back("heap.free_kb");
    msg.counter_values.push_back(static_cast<int64_t>(heap->free / 1024));
  }
  if (msg.message.empty()) msg.message = bus_.lastProblem();
  msg.num_counters = static_cast<int32_t>(msg.counter_names.size());
  bus_.publish(channel_, msg);
}

}  // namespace slamaware
