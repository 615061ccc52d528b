// Proposals on tables no option was chosen on: random scenes (slamaware-synth scene --random),
// the first 120 frames of each, SLAM and the proposals stage as processes, lockstep, in a private
// network namespace, scored against the rendered ground truth. Seed 4 is a small table seen from
// above: the support used to be the plane with most points around the views' look-at point, there
// the floor, and the boxes ran in strips across the table top (recall a third over the whole
// sequence); the support is now the plane nearest under that point. Seed 9 is a small round
// table seen from a metre away (the bistro table): its top forms no plane patch larger than an
// object, it was never the support, and the floor was; a level plane under where the views look
// is now the support when the views know which way is up.
#include <gtest/gtest.h>

#include <iostream>

#include "common/bus/system_config.h"
#include "common/dataset.h"
#include "tests/support/test_support.h"
#include "tests/system/lockstep_pipeline.h"
#include "tools/eval/pipeline_run.h"
#include "tools/eval/proposal_metrics.h"
#include "tools/synth/random_scene.h"
#include "tools/synth/writers.h"

using namespace slamaware;

namespace {

constexpr int kFrames = 120;

double recallOfRandomScene(uint64_t seed) {
  const std::string dir = test::tempDir("random_scene_" + std::to_string(seed));
  auto scene = synth::buildRandomScene(seed, 300, kFrames, nullptr);
  synth::writeSceneFolder(*scene, dir + "/sequence", "random", false);

  SystemConfig sys;
  PipelineRunOptions run = test::lockstepPipeline(&sys);
  run.only = {"slam", "proposals"};
  const std::string log = dir + "/run.lcm";
  const PipelineRun result = runPipeline(dir + "/sequence", log, sys, run);
  EXPECT_TRUE(result.ok) << result.error << " (process outputs: " << log << ".<stage>.txt)";
  ProposalEvalOptions eval;
  eval.stride = 2;
  eval.baseline = false;
  const ProposalScores scores = scoreProposals(readProposalRecording(log, sys.channels),
                                               SequenceFolder::open(dir + "/sequence"), eval);
  return proposalSection(scores)["recall_iou50"].get<double>();
}

}  // namespace

/// A seed and the recall its first 120 frames must reach. Measured 2026-12-02 with the support
/// as now chosen / as it was: seed 4 95.6 / 78.9 %; seeds 5 and 7 (guards) 80.8 and 81.6 % under
/// both. Seed 9 (the bistro table), with a level plane without structure admitted as the support
/// / without: 78.5 / 42.6 %. Seed 7 moves with the last digits of SLAM's map: 81.6 % before the
/// bundle adjustment of 2026-12-06 and 78.4 % after (the same trajectory and keyframes), 74.9 % in
/// the sanitizer build (other floating-point rounding); its floor leaves room for that and still
/// fails a table that breaks the way the bistro table did (21-43 %).
struct Floor {
  int seed;
  double recall;
};

class RandomSceneProposals : public ::testing::TestWithParam<Floor> {};

TEST_P(RandomSceneProposals, ObjectsOfARandomTableAreProposed) {
  const Floor f = GetParam();
  const double recall = recallOfRandomScene(static_cast<uint64_t>(f.seed));
  std::cout << "random scene " << f.seed << ": proposals recall " << recall << " %\n";
  EXPECT_GE(recall, f.recall) << "random scene " << f.seed << " (slamaware-synth scene --random "
                              << f.seed << " --frames " << kFrames
                              << "): proposals recall at IoU 0.5 " << recall << " %";
}

INSTANTIATE_TEST_SUITE_P(Seeds, RandomSceneProposals,
                         ::testing::Values(Floor{4, 88.0}, Floor{5, 75.0}, Floor{7, 70.0},
                                           Floor{9, 70.0}),
                         [](const auto& info) { return "seed" + std::to_string(info.param.seed); });
