#pragma once
// Work spread over threads whose outcome does not depend on how many there are: each worker owns
// its state (an encoder and its buffers), results are handed on in item order on the calling
// thread. For the long offline loops (training) on a machine of few cores; the processes of the
// pipeline stay single-threaded per stage.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace slamaware {

/// `requested` threads if > 0, else one per core of the machine (at least 1).
inline int workerThreads(int requested) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

/// Runs work(w) for w in [0, threads) at once, worker 0 on the calling thread; rethrows the first
/// worker's exception (by worker index) after all have ended.
template <class Work>
void runWorkers(int threads, Work work) {
  threads = std::max(1, threads);
  std::vector<std::exception_ptr> errors(static_cast<size_t>(threads));
  auto guarded = [&](int w) {
    try {
      work(w);
    } catch (...) {
      errors[static_cast<size_t>(w)] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(guarded, w);
  guarded(0);
  for (auto& t : pool) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
}

/// For each i in [0, n): result = work(i, states[w]) on one of states.size() workers, then
/// consume(i, result) on the calling thread in order of i. At most `window` results are held at a
/// time. The same as the plain loop `for i: consume(i, work(i, states[0]))` whenever work(i, s)
/// depends on i alone (not on what s did before). An exception stops the loop and is rethrown
/// (items before the window it happened in have been consumed).
template <class Result, class State, class Work, class Consume>
void orderedParallelFor(size_t n, std::vector<State>& states, size_t window, Work work,
                        Consume consume) {
  const int threads = static_cast<int>(std::max<size_t>(1, states.size()));
  window = std::max<size_t>(window, 1);
  std::vector<Result> results;
  for (size_t begin = 0; begin < n; begin += window) {
    const size_t end = std::min(n, begin + window);
    results.assign(end - begin, Result());
    std::atomic<size_t> next{begin};
    runWorkers(std::min<int>(threads, static_cast<int>(end - begin)), [&](int w) {
      for (size_t i = next++; i < end; i = next++)
        results[i - begin] = work(i, states[static_cast<size_t>(w)]);
    });
    for (size_t i = begin; i < end; ++i) consume(i, results[i - begin]);
  }
}

}  // namespace slamaware
