// The heartbeat: a change of state is published at once (the supervisor's restart time depends on
// it), a state set again is not news, and a burst of changes is rate-limited without losing the
// last one. In-process bus (memq://), no network.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "common/bus/bus.h"
#include "common/bus/status.h"
#include "slamaware/status_t.hpp"

using namespace slamaware;
using State = StatusReporter::State;

namespace {

struct Heartbeat : ::testing::Test {
  Bus bus{"memq://"};
  StatusReporter status{bus, "probe", "PROBE_STATUS"};
  std::vector<status_t> got;
  void SetUp() override {
    bus.subscribe<status_t>(
        "PROBE_STATUS", [this](const status_t& m) { got.push_back(m); }, 4096);
  }
  void drain() {
    while (bus.handle(0) > 0) {
    }
  }
};

void sleepS(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

}  // namespace

TEST_F(Heartbeat, AChangeOfStateGoesOutAtOnce) {
  status.tick();
  drain();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got.back().state, static_cast<int8_t>(State::kStarting));
  sleepS(0.15);
  status.setState(State::kRunning);  // no tick: published by the change itself
  drain();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got.back().state, static_cast<int8_t>(State::kRunning));
  EXPECT_EQ(got.back().name, "probe");
  sleepS(0.15);
  status.setState(State::kRunning);  // the same state again is not news
  drain();
  EXPECT_EQ(got.size(), 2u);
}

TEST_F(Heartbeat, ABurstOfChangesIsRateLimitedAndTheLastOneArrives) {
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 200; ++i) status.setState(i % 2 ? State::kRunning : State::kDegraded);
  status.setState(State::kDegraded);  // the last word of the burst
  const double burst_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  drain();
  // At most one status per 0.1 s of the burst (and the first at once).
  EXPECT_LE(got.size(), 1u + static_cast<size_t>(burst_s / 0.1) + 1u);
  sleepS(0.15);
  status.tick();  // 0.1 s after the last status, the pending change goes out without a full second
  drain();
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.back().state, static_cast<int8_t>(State::kDegraded));
}
