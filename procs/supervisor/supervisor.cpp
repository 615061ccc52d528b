#include "procs/supervisor/supervisor.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <optional>
#include <thread>

namespace slamaware::supervisor {

const char* procStateName(ProcState s) {
  switch (s) {
    case ProcState::kStopped:
      return "stopped";
    case ProcState::kStarting:
      return "starting";
    case ProcState::kRunning:
      return "running";
    case ProcState::kStopping:
      return "stopping";
    case ProcState::kBackoff:
      return "backoff";
    case ProcState::kFailed:
      return "failed";
    case ProcState::kHung:
      return "hung";
  }
  return "?";
}

struct Supervisor::Managed {
  Managed(const ProcessSpec& s, std::string channel, const SupervisorOptions& o)
      : spec(s),
        status_channel(std::move(channel)),
        policy(RestartPolicy::parse(s.restart), s.backoff_initial_s, s.backoff_max_s, s.stable_s),
        log(std::make_unique<RotatingLog>(o.log_dir + "/" + s.name + ".log",
                                          static_cast<size_t>(o.log_max_bytes), o.log_keep)) {
    info.name = s.name;
    info.group = s.group;
    info.host = s.host;
  }
  ProcessSpec spec;
  std::string status_channel;
  RestartPolicy policy;
  std::unique_ptr<RotatingLog> log;
  ProcInfo info;
  int out_fd = -1;
  double started_at = 0;
  double last_heartbeat = -1;
  double restart_at = 0;
  double stop_deadline = 0;
  bool restart_after_stop = false;
  bool start_reported = false;  ///< the process reported running since its last start
  std::string last_exit;        ///< how the last run ended
  std::optional<ProcSample> last_sample;
};

namespace {
double monotonic() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

Supervisor::Supervisor(const SupervisorConfig& config,
                       const std::function<std::string(const std::string&)>& status_channel_of)
    : options_(config.options) {
  for (const auto& spec : config.processes) {
    if (spec.host != options_.host) continue;
    procs_.push_back(std::make_unique<Managed>(
        spec, spec.status_channel.empty() ? status_channel_of(spec.name) : spec.status_channel,
        options_));
  }
}

Supervisor::~Supervisor() { stopAll(); }

void Supervisor::spawn(Managed& m, double now) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) {
    m.info.state = ProcState::kFailed;
    m.info.message = std::string("pipe: ") + std::strerror(errno);
    return;
  }
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    m.info.state = ProcState::kFailed;
    m.info.message = std::string("fork: ") + std::strerror(errno);
    return;
  }
  if (pid == 0) {
    // Child: own process group (signals reach its children too), dies with the supervisor.
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(1);
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    const int devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) dup2(devnull, STDIN_FILENO);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    for (int s : {SIGINT, SIGTERM, SIGPIPE, SIGHUP}) std::signal(s, SIG_DFL);
    const std::vector<std::string> command = expandEnvironment(m.spec.command);
    std::vector<char*> argv;
    for (const auto& a : command) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    std::fprintf(stderr, "cannot run %s: %s\n", argv[0], std::strerror(errno));
    _exit(127);
  }
  setpgid(pid, pid);  // also here, so that signalling the group works before the child ran
  close(fds[1]);
  fcntl(fds[0], F_SETFL, O_NONBLOCK);
  m.out_fd = fds[0];
  m.info.pid = pid;
  m.info.state = (m.spec.wait_running || m.spec.heartbeat_timeout_s > 0) ? ProcState::kStarting
                                                                         : ProcState::kRunning;
  m.info.backoff_s = 0;
  m.started_at = now;
  m.last_heartbeat = -1;
  m.start_reported = false;
  m.last_sample.reset();
  m.policy.started(now);
  m.info.message = m.info.restarts > 0 ? "restart " + std::to_string(m.info.restarts) +
                                             " (last run: " + m.last_exit + ")"
                                       : "started";
  m.log->note("started pid " + std::to_string(pid));
  spdlog::info("{}: started (pid {})", m.spec.name, pid);
  changed_ = true;
}

void Supervisor::startAll(double now) {
  starting_ = true;
  next_to_start_ = 0;
  // Processes waiting for their turn in the start order count as starting (so that nobody takes
  // a queued process for one that has already run and stopped).
  for (auto& m : procs_)
    if (m->spec.autostart && m->info.pid == 0 && m->started_at == 0 &&
        m->info.state == ProcState::kStopped) {
      m->info.state = ProcState::kStarting;
      m->info.message = "queued in the start order";
    }
  tick(now);
}

void Supervisor::requestStop(Managed& m, double now) {
  if (m.info.pid <= 0) return;
  const int sig = signalNumber(m.spec.stop_signal);
  kill(-m.info.pid, sig);
  m.info.state = ProcState::kStopping;
  m.stop_deadline = now + m.spec.grace_s;
  m.log->note("stop requested (SIG" + m.spec.stop_signal + ")");
  changed_ = true;
}

void Supervisor::onExit(Managed& m, int status, double now) {
  drainOutput(m);
  if (m.out_fd >= 0) close(m.out_fd);
  m.out_fd = -1;
  const bool signaled = WIFSIGNALED(status);
  m.info.exit_code = signaled ? -WTERMSIG(status) : WEXITSTATUS(status);
  const std::string how = signaled ? "killed by signal " + std::to_string(WTERMSIG(status))
                                   : "exited with code " + std::to_string(WEXITSTATUS(status));
  const bool hung = m.info.state == ProcState::kHung;
  m.log->note(how);
  m.last_exit = hung ? "hung, " + how : how;
  m.info.pid = 0;
  m.info.cpu_pct = 0;
  m.info.rss_kb = 0;
  changed_ = true;
  if (m.info.state == ProcState::kStopping) {
    m.info.state = ProcState::kStopped;
    m.info.message = "stopped (" + how + ")";
    spdlog::info("{}: stopped ({})", m.spec.name, how);
    if (m.restart_after_stop) {
      m.restart_after_stop = false;
      ++m.info.restarts;
      spawn(m, now);
    }
    return;
  }
  const bool failed = hung || signaled || WEXITSTATUS(status) != 0;
  const double delay = m.policy.ended(now, failed);
  if (delay < 0) {
    m.info.state = failed ? ProcState::kFailed : ProcState::kStopped;
    m.info.message =
        how + (hung ? " (hung)" : "") + "; not restarted (restart: " + m.spec.restart + ")";
    spdlog::warn("{}: {}", m.spec.name, m.info.message);
    return;
  }
  m.info.state = ProcState::kBackoff;
  m.restart_at = now + delay;
  m.info.backoff_s = delay;
  m.info.message =
      how + (hung ? " (hung)" : "") + "; restart in " + std::to_string(delay).substr(0, 5) + " s";
  if (m.policy.quickFailures() >= 3)
    m.info.message +=
        " (crash loop: " + std::to_string(m.policy.quickFailures()) + " quick failures)";
  spdlog::warn("{}: {}", m.spec.name, m.info.message);
}

Supervisor::Managed* Supervisor::find(pid_t pid) {
  for (auto& m : procs_)
    if (m->info.pid == pid) return m.get();
  return nullptr;
}

void Supervisor::drainOutput(Managed& m) {
  if (m.out_fd < 0) return;
  char buf[8192];
  while (true) {
    const ssize_t n = read(m.out_fd, buf, sizeof(buf));
    if (n > 0) {
      m.log->write(buf, static_cast<size_t>(n));
      continue;
    }
    if (n == 0) {  // the child closed its output (it may still run)
      close(m.out_fd);
      m.out_fd = -1;
    }
    break;
  }
}

void Supervisor::tick(double now) {
  for (auto& m : procs_) drainOutput(*m);
  // Reap.
  while (true) {
    int status = 0;
    const pid_t pid = waitpid(-1, &status, WNOHANG);
    if (pid <= 0) break;
    if (Managed* m = find(pid)) onExit(*m, status, now);
  }
  for (auto& mp : procs_) {
    Managed& m = *mp;
    switch (m.info.state) {
      case ProcState::kBackoff:
        if (now >= m.restart_at) {
          ++m.info.restarts;
          spawn(m, now);
        }
        break;
      case ProcState::kStopping:
        if (now > m.stop_deadline && m.info.pid > 0) {
          m.log->note("no exit after " + std::to_string(m.spec.grace_s) + " s: SIGKILL");
          kill(-m.info.pid, SIGKILL);
          m.stop_deadline = now + 1e9;
        }
        break;
      case ProcState::kStarting:
      case ProcState::kRunning: {
        if (m.spec.heartbeat_timeout_s <= 0) break;
        // Before its first heartbeat a process gets its start timeout.
        const double ref = m.last_heartbeat >= 0 ? m.last_heartbeat : m.started_at;
        const double limit = m.last_heartbeat >= 0
                                 ? m.spec.heartbeat_timeout_s
                                 : std::max(m.spec.heartbeat_timeout_s, m.spec.start_timeout_s);
        if (now - ref > limit && m.info.pid > 0) {
          m.info.state = ProcState::kHung;
          m.info.message = "no heartbeat on " + m.status_channel + " for " +
                           std::to_string(now - ref).substr(0, 4) + " s: killed";
          spdlog::warn("{}: {}", m.spec.name, m.info.message);
          m.log->note(m.info.message);
          kill(-m.info.pid, SIGKILL);
          changed_ = true;
        }
        break;
      }
      default:
        break;
    }
    m.info.heartbeat_age_s = m.last_heartbeat >= 0 ? now - m.last_heartbeat : -1;
  }
  // Ordered start: the next process once the previous one reports running (or timed out).
  while (starting_ && next_to_start_ < procs_.size()) {
    Managed& prev_or_next = *procs_[next_to_start_];
    if (prev_or_next.info.pid == 0 && prev_or_next.spec.autostart && prev_or_next.started_at == 0 &&
        (prev_or_next.info.state == ProcState::kStopped ||
         prev_or_next.info.state == ProcState::kStarting)) {
      spawn(prev_or_next, now);
    }
    Managed& m = prev_or_next;
    const bool waiting = m.spec.autostart && m.spec.wait_running &&
                         m.info.state == ProcState::kStarting && !m.start_reported &&
                         now - m.started_at < m.spec.start_timeout_s;
    if (waiting) break;
    if (m.spec.autostart && m.spec.wait_running && !m.start_reported &&
        m.info.state == ProcState::kStarting)
      m.info.message =
          "no running report within " + std::to_string(m.spec.start_timeout_s).substr(0, 4) + " s";
    ++next_to_start_;
  }
  if (next_to_start_ >= procs_.size()) starting_ = false;
  // CPU and memory, once a second.
  if (last_sample_ < 0 || now - last_sample_ >= 1.0) {
    const double dt = last_sample_ < 0 ? 0 : now - last_sample_;
    last_sample_ = now;
    for (auto& m : procs_) {
      if (m->info.pid <= 0) continue;
      auto s = sampleProcess(m->info.pid);
      if (!s) continue;
      if (m->last_sample && dt > 0) m->info.cpu_pct = cpuPercent(*m->last_sample, *s, dt);
      m->info.rss_kb = s->rss_kb;
      m->last_sample = s;
    }
  }
}

void Supervisor::heartbeat(const std::string& channel, int reported_state, double now) {
  for (auto& m : procs_) {
    if (m->status_channel != channel || m->info.pid <= 0) continue;
    m->last_heartbeat = now;
    // status_t: 1 = running, 2 = degraded (running with a problem).
    if (reported_state == 1 || reported_state == 2) {
      m->start_reported = true;
      if (m->info.state == ProcState::kStarting) {
        m->info.state = ProcState::kRunning;
        changed_ = true;
      }
    }
  }
}

int Supervisor::command(Command c, const std::string& target, double now) {
  int n = 0;
  for (auto& mp : procs_) {
    Managed& m = *mp;
    if (target != "all" && m.spec.name != target && m.spec.group != target) continue;
    ++n;
    const bool alive = m.info.pid > 0;
    switch (c) {
      case Command::kStart:
        if (!alive) {
          m.policy = RestartPolicy(RestartPolicy::parse(m.spec.restart), m.spec.backoff_initial_s,
                                   m.spec.backoff_max_s, m.spec.stable_s);
          spawn(m, now);
        }
        break;
      case Command::kStop:
        m.restart_after_stop = false;
        m.info.message = "stop requested";
        if (alive && m.info.state != ProcState::kStopping)
          requestStop(m, now);
        else if (!alive)
          m.info.state = ProcState::kStopped;
        break;
      case Command::kRestart:
        if (alive) {
          m.restart_after_stop = true;
          if (m.info.state != ProcState::kStopping) requestStop(m, now);
        } else {
          ++m.info.restarts;
          spawn(m, now);
        }
        break;
    }
    changed_ = true;
  }
  return n;
}

void Supervisor::stopAll() {
  starting_ = false;
  double now = monotonic();
  for (auto it = procs_.rbegin(); it != procs_.rend(); ++it) {
    (*it)->restart_after_stop = false;
    if ((*it)->info.pid > 0 && (*it)->info.state != ProcState::kStopping) requestStop(**it, now);
    if ((*it)->info.state == ProcState::kBackoff) (*it)->info.state = ProcState::kStopped;
  }
  while (true) {
    now = monotonic();
    tick(now);
    bool any = false;
    for (auto& m : procs_) {
      if (m->info.pid <= 0) continue;
      any = true;
      if (m->info.state != ProcState::kStopping) requestStop(*m, now);  // e.g. restarted meanwhile
    }
    if (!any) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

std::vector<int> Supervisor::outputFds() const {
  std::vector<int> fds;
  for (auto& m : procs_)
    if (m->out_fd >= 0) fds.push_back(m->out_fd);
  return fds;
}

std::vector<std::string> Supervisor::heartbeatChannels() const {
  std::vector<std::string> out;
  for (auto& m : procs_) out.push_back(m->status_channel);
  return out;
}

std::vector<ProcInfo> Supervisor::table() const {
  std::vector<ProcInfo> out;
  for (auto& m : procs_) out.push_back(m->info);
  return out;
}

bool Supervisor::takeChanged() {
  const bool c = changed_;
  changed_ = false;
  return c;
}

}  // namespace slamaware::supervisor
