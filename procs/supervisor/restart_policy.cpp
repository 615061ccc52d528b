#include "procs/supervisor/restart_policy.h"

#include <algorithm>
#include <stdexcept>

namespace slamaware::supervisor {

RestartPolicy::Mode RestartPolicy::parse(const std::string& s) {
  if (s == "never") return Mode::kNever;
  if (s == "on_failure") return Mode::kOnFailure;
  if (s == "always") return Mode::kAlways;
  throw std::invalid_argument("unknown restart policy '" + s + "'");
}

RestartPolicy::RestartPolicy(Mode mode, double initial_s, double max_s, double stable_s)
    : mode_(mode),
      initial_s_(initial_s),
      max_s_(max_s),
      stable_s_(stable_s),
      backoff_s_(initial_s) {}

void RestartPolicy::started(double now) { started_at_ = now; }

double RestartPolicy::ended(double now, bool failed) {
  if (mode_ == Mode::kNever || (mode_ == Mode::kOnFailure && !failed)) return -1;
  if (now - started_at_ >= stable_s_) {
    // It ran long enough: this is a new, isolated failure.
    backoff_s_ = initial_s_;
    quick_failures_ = 0;
  }
  const double delay = backoff_s_;
  ++quick_failures_;
  backoff_s_ = std::min(max_s_, backoff_s_ * 2);
  return delay;
}

}  // namespace slamaware::supervisor
