#include "common/thread_priority.h"

#include <pthread.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

namespace slamaware {

namespace {
std::atomic<int> g_background_nice{0};
std::atomic<bool> g_warned{false};  // one line per process: clustering jobs come every keyframe
}  // namespace

bool lowerThreadPriority(int increment, const std::string& what) {
  if (increment <= 0) return true;
  // On Linux, PRIO_PROCESS with a thread id reads and sets that thread's nice value alone.
  const auto tid = static_cast<id_t>(syscall(SYS_gettid));
  errno = 0;
  const int current = getpriority(PRIO_PROCESS, tid);
  if (errno == 0 && setpriority(PRIO_PROCESS, tid, current + increment) == 0) return true;
  if (!g_warned.exchange(true))
    spdlog::warn("{} keeps its priority: setpriority(+{}): {}", what, increment,
                 std::strerror(errno));
  return false;
}

void setBackgroundNice(int increment) { g_background_nice = increment < 0 ? 0 : increment; }

bool enterBackground(const std::string& what) {
  return lowerThreadPriority(g_background_nice, what);
}

void nameThisThread(const std::string& name) {
  pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
}

}  // namespace slamaware
