// The CPU a process used while frames streamed, from the runner's samples of its CPU time:
// interpolated between samples, clamped outside them.
#include <gtest/gtest.h>

#include "tools/eval/pipeline_run.h"

using namespace slamaware;

TEST(PipelineCpu, CpuBetweenTwoMomentsIsInterpolatedFromTheSamples) {
  // Start-up burns 2 s of CPU before the first frame at t = 1 s; then half a core.
  const std::vector<CpuSample> trace = {
      {0, 0.0}, {1'000'000, 2.0}, {2'000'000, 2.5}, {3'000'000, 3.0}, {5'000'000, 4.0}};
  EXPECT_DOUBLE_EQ(cpuSecondsBetween(trace, 1'000'000, 5'000'000), 2.0);
  EXPECT_DOUBLE_EQ(cpuSecondsBetween(trace, 1'500'000, 2'500'000), 0.5);
  EXPECT_DOUBLE_EQ(cpuSecondsBetween(trace, 4'000'000, 4'500'000), 0.25);
  // Outside the samples: clamped to the first and last.
  EXPECT_DOUBLE_EQ(cpuSecondsBetween(trace, -5'000'000, 9'000'000), 4.0);
  EXPECT_DOUBLE_EQ(cpuSecondsBetween({}, 0, 1'000'000), 0.0);
  EXPECT_DOUBLE_EQ(cpuSecondsBetween({{7, 1.5}}, 0, 1'000'000), 0.0);
}
