#pragma once
// The process manager: starts the processes of one host in order, captures their output,
// restarts them by their policy, kills hung ones, and obeys start / stop / restart commands.
// Knows nothing of LCM: the node feeds it heartbeats and commands and publishes its table.
#include <sys/types.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "procs/supervisor/proc_stats.h"
#include "procs/supervisor/process_spec.h"
#include "procs/supervisor/restart_policy.h"
#include "procs/supervisor/rotating_log.h"

namespace slamaware::supervisor {

enum class ProcState {
  kStopped = 0,
  kStarting = 1,
  kRunning = 2,
  kStopping = 3,
  kBackoff = 4,
  kFailed = 5,
  kHung = 6
};
const char* procStateName(ProcState s);

/// What the supervisor reports about one process.
struct ProcInfo {
  std::string name, group, host;
  pid_t pid = 0;
  ProcState state = ProcState::kStopped;
  int restarts = 0;
  double cpu_pct = 0;
  int64_t rss_kb = 0;
  double heartbeat_age_s = -1;
  int exit_code = 0;  ///< last exit code, or -signal
  double backoff_s = 0;
  std::string message;
};

class Supervisor {
 public:
  enum class Command { kStart, kStop, kRestart };

  /// Manages the processes of `config` whose host is config.options.host.
  /// `status_channel_of(name)` gives a process's default heartbeat channel.
  Supervisor(const SupervisorConfig& config,
             const std::function<std::string(const std::string&)>& status_channel_of);
  ~Supervisor();

  /// Starts the autostart processes in order (one per tick when they wait for "running").
  void startAll(double now);
  /// Reaps exited children, reads their output, restarts, detects hung processes, samples CPU
  /// and memory. Call often; `now` is a monotonic clock in seconds.
  void tick(double now);
  /// A heartbeat arrived on `channel` with the process's reported state (status_t::STATE_*).
  void heartbeat(const std::string& channel, int reported_state, double now);
  /// Applies a command to the process or group `target` ("all" = every process). Returns the
  /// number of processes it applied to.
  int command(Command c, const std::string& target, double now);
  /// Stops every process (reverse start order), waits for them, SIGKILLs what remains after
  /// its grace period. Returns when none is left.
  void stopAll();

  /// File descriptors of the children's output pipes (to poll on), -1 entries skipped.
  std::vector<int> outputFds() const;
  /// Heartbeat channels of the managed processes.
  std::vector<std::string> heartbeatChannels() const;
  std::vector<ProcInfo> table() const;
  const std::string& host() const { return options_.host; }
  /// True when the table changed since the last call (state, pid, restarts).
  bool takeChanged();

 private:
  struct Managed;
  void spawn(Managed& m, double now);
  void requestStop(Managed& m, double now);
  void onExit(Managed& m, int status, double now);
  void drainOutput(Managed& m);
  Managed* find(pid_t pid);

  SupervisorOptions options_;
  std::vector<std::unique_ptr<Managed>> procs_;
  size_t next_to_start_ = 0;  ///< startAll() progress
  bool starting_ = false;
  double last_sample_ = -1;
  bool changed_ = true;
};

}  // namespace slamaware::supervisor
