#include "procs/supervisor/proc_stats.h"

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <string>

namespace slamaware::supervisor {

std::optional<ProcSample> sampleProcess(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return std::nullopt;
  // The command name (field 2) is in parentheses and may hold spaces: parse after the last ')'.
  const size_t close = line.rfind(')');
  if (close == std::string::npos) return std::nullopt;
  std::istringstream rest(line.substr(close + 2));
  std::string field;
  ProcSample s;
  // Fields from 3 on: state(3) ... utime(14) stime(15).
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) s.cpu_ticks = std::stoull(field);
    if (i == 15) s.cpu_ticks += std::stoull(field);
  }
  std::ifstream statm("/proc/" + std::to_string(pid) + "/statm");
  int64_t size_pages = 0, rss_pages = 0;
  if (statm >> size_pages >> rss_pages) s.rss_kb = rss_pages * (sysconf(_SC_PAGESIZE) / 1024);
  return s;
}

double cpuPercent(const ProcSample& before, const ProcSample& after, double dt_s) {
  if (dt_s <= 0 || after.cpu_ticks < before.cpu_ticks) return 0;
  return 100.0 * static_cast<double>(after.cpu_ticks - before.cpu_ticks) / sysconf(_SC_CLK_TCK) /
         dt_s;
}

}  // namespace slamaware::supervisor
