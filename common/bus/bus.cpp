#include "common/bus/bus.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

namespace slamaware {

int64_t wallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

struct Bus::Subscription {
  Bus* bus;
  std::string channel;
  RawHandler handler;
  size_t max_bytes;
};

Bus::Bus(const std::string& url) : url_(url), lcm_(std::make_unique<lcm::LCM>(url)) {
  if (!lcm_->good())
    throw std::runtime_error(
        "cannot open the LCM bus '" + url +
        "' (bad URL, or no multicast route: 'ip route add 224.0.0.0/4 dev lo')");
}

Bus::~Bus() = default;

void Bus::subscribeRaw(const std::string& channel, RawHandler handler, size_t max_bytes) {
  subs_.push_back(
      std::make_unique<Subscription>(Subscription{this, channel, std::move(handler), max_bytes}));
  lcm_->subscribeFunction(channel, &Bus::dispatch, subs_.back().get());
}

void Bus::dispatch(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Subscription* sub) {
  Bus* bus = sub->bus;
  if (rbuf->data_size > sub->max_bytes) {
    bus->reject(channel, "message of " + std::to_string(rbuf->data_size) +
                             " bytes exceeds the cap of " + std::to_string(sub->max_bytes));
    return;
  }
  try {
    sub->handler(RawMessage{channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size,
                            rbuf->recv_utime});
  } catch (const std::exception& e) {
    bus->handlerError(channel, e.what());
  } catch (...) {
    bus->handlerError(channel, "unknown exception");
  }
}

bool Bus::publishRaw(const std::string& channel, const uint8_t* data, size_t size) {
  if (lcm_->publish(channel, data, static_cast<unsigned int>(size)) != 0)
    return publishFailed(channel, "LCM publish failed (" + std::to_string(size) + " bytes)");
  return true;
}

bool Bus::publishFailed(const std::string& channel, const std::string& why) {
  spdlog::error("publish on {}: {}", channel, why);
  return false;
}

int Bus::handle(int timeout_ms) { return lcm_->handleTimeout(timeout_ms); }

int Bus::fileno() const { return lcm_->getFileno(); }

void Bus::note(const std::string& channel, const std::string& what, const std::string& why) {
  // Log the first problem of a channel, then at most one line per 5 s (a flood of bad messages
  // must not flood the log).
  const int64_t now = wallUtime();
  int64_t& last = last_logged_us_[channel];
  last_problem_ = channel + ": " + what + ": " + why;
  if (now - last > 5000000) {
    last = now;
    spdlog::warn("{}: {}: {} (rejects so far on this channel: {})", channel, what, why,
                 rejects_[channel] + handler_errors_[channel]);
  }
}

void Bus::reject(const std::string& channel, const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++rejects_[channel];
  note(channel, "rejected message", why);
}

void Bus::handlerError(const std::string& channel, const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++handler_errors_[channel];
  note(channel, "error handling message", why);
}

std::map<std::string, int64_t> Bus::rejects() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rejects_;
}

std::map<std::string, int64_t> Bus::handlerErrors() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return handler_errors_;
}

int64_t Bus::totalRejects() const {
  std::lock_guard<std::mutex> lock(mutex_);
  int64_t n = 0;
  for (const auto& kv : rejects_) n += kv.second;
  for (const auto& kv : handler_errors_) n += kv.second;
  return n;
}

std::string Bus::lastProblem() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_problem_;
}

}  // namespace slamaware
