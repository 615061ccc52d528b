#pragma once
// When to restart a process that ended: its policy (never / on failure / always) and an
// exponential back-off, so that a process that dies at once is not restarted in a tight loop.
// Pure logic on a caller-given clock (seconds), unit-tested without processes.
#include <string>

namespace slamaware::supervisor {

class RestartPolicy {
 public:
  enum class Mode { kNever, kOnFailure, kAlways };
  static Mode parse(const std::string& s);

  RestartPolicy(Mode mode, double initial_s, double max_s, double stable_s);

  /// The process started at time `now`.
  void started(double now);
  /// The process ended at `now` (failed: non-zero exit, killed by a signal, or hung). Returns the
  /// delay before the restart, or a negative value for "do not restart".
  double ended(double now, bool failed);
  /// Consecutive quick failures (runs shorter than stable_s).
  int quickFailures() const { return quick_failures_; }

 private:
  Mode mode_;
  double initial_s_, max_s_, stable_s_;
  double backoff_s_;
  double started_at_ = 0;
  int quick_failures_ = 0;
};

}  // namespace slamaware::supervisor
