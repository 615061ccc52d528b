#pragma once
// Independent jobs shared out to a few threads: job k runs on thread k mod threads (the calling
// thread takes its share too) and writes only its own result, so the outcome never depends on
// the number of threads or on their timing.
#include <algorithm>
#include <thread>
#include <vector>

namespace slamaware::slam {

/// Runs job(k) for k in [0, count) on min(threads, count) threads and returns when all are done.
/// `job` must not throw.
template <class Job>
void runShared(int count, int threads, Job&& job) {
  const int n = std::max(1, std::min(threads, count));
  auto share = [&](int first) {
    for (int k = first; k < count; k += n) job(k);
  };
  std::vector<std::thread> helpers;
  for (int t = 1; t < n; ++t) helpers.emplace_back(share, t);
  share(0);
  for (auto& h : helpers) h.join();
}

}  // namespace slamaware::slam
