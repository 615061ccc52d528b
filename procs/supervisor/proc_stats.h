#pragma once
// CPU and memory of a process from /proc (Linux).
#include <sys/types.h>

#include <cstdint>
#include <optional>

namespace slamaware::supervisor {

struct ProcSample {
  uint64_t cpu_ticks = 0;  ///< utime + stime, clock ticks
  int64_t rss_kb = 0;      ///< resident set size, KiB
};

/// Reads /proc/<pid>/stat and /proc/<pid>/statm; nullopt if the process is gone.
std::optional<ProcSample> sampleProcess(pid_t pid);
/// % of one core used between two samples taken dt_s apart.
double cpuPercent(const ProcSample& before, const ProcSample& after, double dt_s);

}  // namespace slamaware::supervisor
