// Work spread over threads: results reach the consumer in item order whatever the number of
// workers and however long each item takes, every worker uses only its own state, and a failing
// item stops the loop with its exception.
#include <gtest/gtest.h>

#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "common/parallel.h"

using namespace slamaware;

namespace {

// Items of very different cost, so that workers finish out of order.
std::vector<long> squaresInConsumedOrder(int workers, size_t n, size_t window,
                                         std::vector<int>* used_by) {
  std::vector<int> states(static_cast<size_t>(workers));
  for (int w = 0; w < workers; ++w) states[static_cast<size_t>(w)] = w;
  std::vector<long> out;
  used_by->assign(n, -1);
  orderedParallelFor<long>(
      n, states, window,
      [&](size_t i, int& state) {
        std::this_thread::sleep_for(std::chrono::microseconds(i % 3 == 0 ? 2000 : 10));
        (*used_by)[i] = state;
        return static_cast<long>(i * i);
      },
      [&](size_t i, const long& r) {
        EXPECT_EQ(out.size(), i) << "consumed out of order";
        out.push_back(r);
      });
  return out;
}

}  // namespace

TEST(OrderedParallelFor, ConsumesInItemOrderForAnyNumberOfWorkers) {
  std::vector<long> want;
  for (size_t i = 0; i < 101; ++i) want.push_back(static_cast<long>(i * i));
  for (const int workers : {1, 2, 3, 7}) {
    std::vector<int> used_by;
    EXPECT_EQ(squaresInConsumedOrder(workers, 101, 16, &used_by), want) << workers << " workers";
    for (const int w : used_by) EXPECT_TRUE(w >= 0 && w < workers);
  }
  std::vector<int> used_by;
  EXPECT_TRUE(squaresInConsumedOrder(2, 0, 16, &used_by).empty());
}

TEST(OrderedParallelFor, AFailingItemStopsTheLoopWithItsException) {
  std::vector<int> states(2);
  size_t consumed = 0;
  EXPECT_THROW(orderedParallelFor<int>(
                   100, states, 10,
                   [](size_t i, int&) {
                     if (i == 42) throw std::runtime_error("item 42");
                     return 0;
                   },
                   [&](size_t, const int&) { ++consumed; }),
               std::runtime_error);
  EXPECT_EQ(consumed, 40u) << "the windows before the failing one, and nothing after";
}

TEST(WorkerThreads, ZeroMeansOnePerCore) {
  EXPECT_EQ(workerThreads(3), 3);
  EXPECT_GE(workerThreads(0), 1);
}
