// The CAMERA / PROPOSALS join on seq: bounded buffers, proposals for frames never seen, waiting,
// time-outs and a camera stream that restarts; config/recognizer.yaml equals the defaults, and bad
// options are refused naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/config.h"
#include "procs/recognizer/recognizer.h"
#include "procs/recognizer/seq_joiner.h"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace slamaware::recognizer;

using Joiner = SeqJoiner<std::string, int>;

TEST(SeqJoiner, JoinsProposalsWithTheFrameOfTheSameSeq) {
  Joiner j(4, 4, 1.0);
  j.addFrame(0, "f0");
  j.addFrame(1, "f1");
  j.addProposals(1, 10, 0.0);
  j.addProposals(0, 20, 0.0);
  ASSERT_EQ(j.ready().size(), 2u);
  EXPECT_EQ(*j.ready()[0].frame, "f1");
  EXPECT_EQ(j.ready()[0].proposals, 10);
  EXPECT_EQ(*j.ready()[1].frame, "f0");
}

TEST(SeqJoiner, ProposalsWaitForTheirFrame) {
  Joiner j(4, 4, 1.0);
  j.addProposals(3, 30, 0.0);
  EXPECT_TRUE(j.ready().empty());
  EXPECT_EQ(j.pending(), 1u);
  j.addFrame(3, "f3");
  ASSERT_EQ(j.ready().size(), 1u);
  EXPECT_EQ(*j.ready()[0].frame, "f3");
  EXPECT_EQ(j.pending(), 0u);
}

TEST(SeqJoiner, ProposalsForAFrameNeverSeenComeOutWithoutFrame) {
  Joiner j(2, 4, 1.0);
  j.addFrame(5, "f5");
  j.addProposals(2, 1, 0.0);  // older than every frame seen: the frame was lost
  ASSERT_EQ(j.ready().size(), 1u);
  EXPECT_FALSE(j.ready()[0].frame);
  EXPECT_EQ(j.ready()[0].outcome, Joiner::Outcome::kUnknownFrame);
  j.ready().clear();
  j.addProposals(7, 2, 0.0);  // waits ...
  j.addFrame(8, "f8");        // ... but the camera skipped 7
  ASSERT_EQ(j.ready().size(), 1u);
  EXPECT_EQ(j.ready()[0].seq, 7);
  EXPECT_EQ(j.ready()[0].outcome, Joiner::Outcome::kUnknownFrame);
}

TEST(SeqJoiner, BuffersAreBounded) {
  Joiner j(3, 2, 10.0);
  for (int s = 0; s < 10; ++s) j.addFrame(s, "f" + std::to_string(s));
  EXPECT_EQ(j.frames(), 3u);
  j.addProposals(6, 0, 0.0);  // evicted
  EXPECT_EQ(j.ready().back().outcome, Joiner::Outcome::kUnknownFrame);
  j.addProposals(20, 0, 0.0);
  j.addProposals(21, 0, 0.0);
  j.addProposals(22, 0, 0.0);  // the oldest waiting one is given up
  EXPECT_EQ(j.pending(), 2u);
  EXPECT_EQ(j.ready().back().seq, 20);
  EXPECT_EQ(j.ready().back().outcome, Joiner::Outcome::kOverflow);
}

TEST(SeqJoiner, WaitingProposalsTimeOut) {
  Joiner j(3, 5, 2.0);
  j.addProposals(1, 0, 10.0);
  j.expire(11.0);
  EXPECT_EQ(j.pending(), 1u);
  j.expire(12.5);
  EXPECT_EQ(j.pending(), 0u);
  ASSERT_EQ(j.ready().size(), 1u);
  EXPECT_EQ(j.ready()[0].outcome, Joiner::Outcome::kTimedOut);
}

TEST(SeqJoiner, CameraRestartClearsOldFrames) {
  Joiner j(5, 5, 1.0);
  j.addFrame(40, "old40");
  j.addFrame(41, "old41");
  j.addFrame(0, "new0");  // --loop or a restarted camera
  EXPECT_EQ(j.frames(), 1u);
  j.addProposals(0, 0, 0.0);
  ASSERT_EQ(j.ready().size(), 1u);
  EXPECT_EQ(*j.ready()[0].frame, "new0");
}

// Real time: of the joined jobs ready together only the newest is handled, the others are
// dropped; proposals without a frame are answered. Proposals for a frame older than the jobs taken
// before (a map's reference keyframe, sent late on purpose) are never dropped, even with newer
// ones beside them; after a camera restart the seqs count from the new stream.
TEST(SeqJoiner, RealTimeDropsAllButTheNewestExceptLateProposals) {
  Joiner j(30, 30, 1.0);
  for (int32_t s = 0; s < 6; ++s) j.addFrame(s, "f" + std::to_string(s));
  j.addProposals(2, 2, 0.0);
  j.addProposals(3, 3, 0.0);
  j.addProposals(4, 4, 0.0);
  j.markRealTimeDrops();
  ASSERT_EQ(j.ready().size(), 3u);
  EXPECT_TRUE(j.ready()[0].drop);
  EXPECT_TRUE(j.ready()[1].drop);
  EXPECT_FALSE(j.ready()[2].drop) << "the newest";
  j.ready().clear();
  // Seq 0's late proposals come just before seq 5's: both are handled.
  j.addProposals(0, 0, 0.0);
  j.addProposals(5, 5, 0.0);
  j.markRealTimeDrops();
  ASSERT_EQ(j.ready().size(), 2u);
  EXPECT_EQ(j.ready()[0].seq, 0);
  EXPECT_FALSE(j.ready()[0].drop) << "late: older than seq 4, taken before";
  EXPECT_FALSE(j.ready()[1].drop);
  j.ready().clear();
  // The camera restarts at seq 0: its frames 0-2 are new, and 1 is dropped for 2.
  for (int32_t s = 0; s < 3; ++s) j.addFrame(s, "g" + std::to_string(s));
  j.addProposals(1, 1, 0.0);
  j.addProposals(2, 2, 0.0);
  j.markRealTimeDrops();
  ASSERT_EQ(j.ready().size(), 2u);
  EXPECT_TRUE(j.ready()[0].drop) << "not late: the seqs before the restart do not count";
  EXPECT_FALSE(j.ready()[1].drop);
}

TEST(ShippedConfig, RecognizerYamlEqualsDefaults) {
  RecognizerOptions file = loadConfig<RecognizerOptions>(test::sourcePath("config/recognizer.yaml"),
                                                         "recognizer", false);
  RecognizerOptions defaults;
  EXPECT_TRUE(optionsEqual(file, defaults)) << describeOptions(optionListOf(file));
  EXPECT_EQ(test::readTextFile(test::sourcePath("config/recognizer.yaml")),
            defaultConfigFileText<RecognizerOptions>("recognizer"))
      << "config/recognizer.yaml is generated from the built-in defaults: make configs";
}

TEST(RecognizerConfig,
     AnUnknownEncoderANonPositiveSuppressionIoUOrABadWarmUpSizeIsRefusedNamingTheKey) {
  RecognizerOptions o;
  EXPECT_NO_THROW(checkOptions(o, "recognizer.yaml"));
  o.nms_iou = 1.0;  // no suppression
  EXPECT_NO_THROW(checkOptions(o, "recognizer.yaml"));
  for (const double bad : {0.0, -0.5, std::nan("")}) {
    o.nms_iou = bad;
    try {
      checkOptions(o, "my.yaml");
      ADD_FAILURE() << "nms_iou " << bad << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("my.yaml: key 'recognizer.nms_iou'"), std::string::npos)
          << e.what();
    }
  }
  o = RecognizerOptions{};
  o.encoder = "fast";
  EXPECT_THROW(checkOptions(o, "my.yaml"), ConfigError);
  for (const double bad : {-1.0, 181.0, std::nan("")}) {
    o = RecognizerOptions{};
    o.view_selection.angle_deg = bad;
    EXPECT_THROW(checkOptions(o, "my.yaml"), ConfigError) << "angle " << bad;
    o = RecognizerOptions{};
    o.view_selection.scale = bad == 181.0 ? HUGE_VAL : bad;
    EXPECT_THROW(checkOptions(o, "my.yaml"), ConfigError) << "scale " << bad;
  }
  // The warm-up frame: a size, or none.
  o = RecognizerOptions{};
  o.warm_up_width = o.warm_up_height = 0;
  EXPECT_NO_THROW(checkOptions(o, "my.yaml"));
  for (const auto& [w, h] :
       std::vector<std::pair<int, int>>{{-640, 480}, {640, 0}, {0, 480}, {64000, 48000}}) {
    o.warm_up_width = w;
    o.warm_up_height = h;
    try {
      checkOptions(o, "my.yaml");
      ADD_FAILURE() << "warm-up " << w << " x " << h << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("my.yaml: keys 'recognizer.warm_up_width'"),
                std::string::npos)
          << e.what();
    }
  }
}
