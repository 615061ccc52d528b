#include "common/serial_worker.h"

#include <spdlog/spdlog.h>

#include "common/thread_priority.h"

namespace slamaware {

SerialWorker::SerialWorker(bool threaded, std::string name, int nice)
    : threaded_(threaded), name_(std::move(name)), nice_(nice) {
  if (threaded_) thread_ = std::thread([this] { run(); });
}

SerialWorker::~SerialWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  work_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void SerialWorker::post(std::function<void()> job) {
  if (!threaded_) {
    job();
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(job));
  }
  work_cv_.notify_one();
}

size_t SerialWorker::pending() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return jobs_.size() + running_;
}

void SerialWorker::waitIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_cv_.wait(lock, [this] { return jobs_.empty() && running_ == 0; });
}

void SerialWorker::run() {
  nameThisThread(name_);
  lowerThreadPriority(nice_, "the " + name_ + " thread");
  while (true) {
    std::function<void()> job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_cv_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
      if (jobs_.empty()) break;  // stop requested and nothing left
      job = std::move(jobs_.front());
      jobs_.pop_front();
      running_ = 1;
    }
    try {
      job();
    } catch (const std::exception& e) {
      spdlog::error("worker job failed: {}", e.what());
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      running_ = 0;
    }
    idle_cv_.notify_all();
  }
  idle_cv_.notify_all();
}

}  // namespace slamaware
