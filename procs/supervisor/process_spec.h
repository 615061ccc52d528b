#pragma once
// What the supervisor runs: the `supervisor` and `processes` sections of config/system.yaml.
#include <string>
#include <vector>

namespace slamaware::supervisor {

/// One supervised process (an item of the `processes` list).
struct ProcessSpec {
  std::string name;  ///< unique; its heartbeat is <NAME>_STATUS unless status_channel says
  std::vector<std::string>
      command;                 ///< program and arguments (relative paths: from the working folder)
  std::string host = "local";  ///< which supervisor runs it
  std::string group = "default";       ///< for commands addressed to several processes
  std::string restart = "on_failure";  ///< never | on_failure | always
  double backoff_initial_s = 0.01;     ///< first restart delay; doubles after each quick failure
  double backoff_max_s = 10.0;         ///< cap of the restart delay
  double stable_s = 10.0;              ///< a run this long resets the back-off
  std::string stop_signal = "INT";     ///< INT | TERM | HUP | QUIT | USR1 | USR2 | KILL
  double grace_s = 5.0;                ///< s between the stop signal and SIGKILL
  bool wait_running = true;  ///< start the next process only once this one's heartbeat says running
  double start_timeout_s = 20.0;  ///< how long to wait for that
  double heartbeat_timeout_s =
      5.0;  ///< no heartbeat for this long: hung, killed and restarted (0: not watched)
  std::string status_channel;  ///< "" = channels.statusOf(name)
  bool autostart = true;       ///< started with the supervisor (else only by a start command)

  template <class V>
  void visit(V& v) {
    v("name", name, "unique process name");
    v("command", command, "program and arguments");
    v("host", host, "supervisor (host name) that runs it");
    v("group", group, "group name for commands");
    v("restart", restart, "never | on_failure | always");
    v("backoff_initial_s", backoff_initial_s, "s, first restart delay");
    v("backoff_max_s", backoff_max_s, "s, cap of the restart delay");
    v("stable_s", stable_s, "s of running that resets the back-off");
    v("stop_signal", stop_signal, "signal that asks the process to stop");
    v("grace_s", grace_s, "s before SIGKILL follows the stop signal");
    v("wait_running", wait_running, "start the next process only when this one reports running");
    v("start_timeout_s", start_timeout_s, "s to wait for the running report");
    v("heartbeat_timeout_s", heartbeat_timeout_s,
      "s without heartbeat before the process counts as hung (0: off)");
    v("status_channel", status_channel, "heartbeat channel (default: NAME_STATUS)");
    v("autostart", autostart, "start with the supervisor");
  }
};

/// The supervisor's own options (section `supervisor`).
struct SupervisorOptions {
  std::string host = "local";  ///< this supervisor's host name; runs the processes of that host
  std::string log_dir = "build/logs";  ///< each process's output goes to <log_dir>/<name>.log
  int log_max_bytes = 4 << 20;         ///< rotate a log when it grows past this
  int log_keep = 3;                    ///< rotated logs kept (<name>.log.1 .. .N)
  double status_rate_hz = 1.0;         ///< PROC_STATUS rate

  template <class V>
  void visit(V& v) {
    v("host", host, "host name of this supervisor");
    v("log_dir", log_dir, "folder of the processes' log files");
    v("log_max_bytes", log_max_bytes, "bytes, a log is rotated past this size");
    v("log_keep", log_keep, "rotated logs kept per process");
    v("status_rate_hz", status_rate_hz, "Hz, PROC_STATUS rate");
  }
};

struct SupervisorConfig {
  SupervisorOptions options;
  std::vector<ProcessSpec> processes;  ///< every host's, in start order
};

/// Reads and checks the supervisor sections of a system.yaml: unique names, known restart
/// policies and signals, non-empty commands. Throws ConfigError naming file and entry.
SupervisorConfig loadSupervisorConfig(const std::string& path);

/// The command with ${NAME} and ${NAME:-default} replaced from the environment (an unset NAME
/// without a default becomes "").
std::vector<std::string> expandEnvironment(const std::vector<std::string>& command);

/// The signal number of a name in ProcessSpec::stop_signal; -1 if unknown.
int signalNumber(const std::string& name);

}  // namespace slamaware::supervisor
