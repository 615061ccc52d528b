// The proposals target on real data: SLAM and the proposals stage (each its own process, lockstep,
// in a private network namespace) on every frame of the Middlebury temple ring, scored against its
// ground-truth boxes. The temple must be proposed (IoU >= 0.5) in at least 90 % of the views SLAM
// localises (procs/proposals/README.md: 41 of 43, all that the ground truth's own offset allows).
#include <gtest/gtest.h>

#include "common/bus/system_config.h"
#include "common/dataset.h"
#include "tests/support/test_support.h"
#include "tests/system/lockstep_pipeline.h"
#include "tools/eval/pipeline_run.h"
#include "tools/eval/proposal_metrics.h"

using namespace slamaware;
using namespace slamaware::proposals;

TEST(TempleProposals, TheTempleIsProposedInNineOfTenLocalisedViews) {
  const std::string temple = test::sharedData("sequences/middlebury_temple_ring");
  SKIP_WITHOUT_SHARED_DATA(temple);
  SystemConfig sys;
  PipelineRunOptions options = test::lockstepPipeline(&sys);
  const std::string dir = test::tempDir("temple_proposals");
  options.only = {"slam", "proposals"};
  const std::string log = dir + "/temple.lcm";
  const PipelineRun result = runPipeline(temple, log, sys, options);
  ASSERT_TRUE(result.ok) << result.error << " (process outputs: " << log << ".<stage>.txt)";

  const SequenceFolder sequence = SequenceFolder::open(temple);
  ProposalEvalOptions eval;
  eval.stride = 1;
  eval.baseline = false;
  const ProposalScores scores =
      scoreProposals(readProposalRecording(log, sys.channels), sequence, eval);
  // The report's figure, as make eval writes it (the temple has one ground-truth box per frame).
  const nlohmann::json section = proposalSection(scores);
  ASSERT_GE(scores.rank50_localized.size(), 40u) << "SLAM localised too few of the 47 views";
  EXPECT_GE(section["recall_iou50_localized_frames"].get<double>(), 90.0)
      << "the temple is proposed in " << section["recall_iou50_localized_frames"] << " % of "
      << scores.rank50_localized.size() << " localised views";
}
