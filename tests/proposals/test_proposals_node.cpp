// slamaware-proposals as a process on a bus in its own network namespace: a map of two objects
// on a table and a tracked pose give a PROPOSALS message for that frame with a box on each
// object; a malformed SLAM_MAP, a garbage message and a LOST pose leave it running, answering
// every pose, and the rejects are counted in PROPOSALS_STATUS.
#include <gtest/gtest.h>

#include <map>

#include "common/bus/bus.h"
#include "procs/proposals/synthetic_map.h"
#include "slamaware/proposals_t.hpp"
#include "slamaware/status_t.hpp"
#include "tests/support/test_support.h"

using namespace slamaware;
using namespace slamaware::proposals;
using namespace slamaware::synthmap;
using namespace slamaware::test;
using namespace std::chrono_literals;

namespace {

struct Listener {
  Bus bus{testUrl()};
  std::map<int32_t, proposals_t> proposals;
  status_t last_status{};
  bool have_status = false;
  Listener() {
    bus.subscribe<proposals_t>("PROPOSALS", [this](const proposals_t& p) { proposals[p.seq] = p; });
    bus.subscribe<status_t>("PROPOSALS_STATUS", [this](const status_t& s) {
      last_status = s;
      have_status = true;
    });
  }
  bool pump(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
    return waitUntil(
        [&] {
          bus.handle(10);
          return done();
        },
        timeout);
  }
};

// The pixel column of world x for the camera looking down from `height` (f = 500, cx = 319.5).
double columnOf(double x, double depth) { return 319.5 + 500 * x / depth; }

}  // namespace

TEST(ProposalsNode, ProposesObjectsAndSurvivesBadInput) {
  const std::string dir = tempDir("proposals_node");
  Listener l;
  ChildProcess node({binPath("slamaware-proposals"), "--lcm-url", testUrl(), "--lockstep"},
                    dir + "/node.log");
  ASSERT_TRUE(l.pump([&] { return l.have_status; }, 10s)) << node.log();

  const SE3 T = lookingDown(1.0);
  const auto scene = join(table(0.8f, 0.004f), join(cylinder(-0.12f, 0, 0.04f, 0.12f, 0.004f),
                                                    cylinder(0.12f, 0, 0.04f, 0.1f, 0.004f)));
  l.bus.publish("CAMERA_INFO", vgaInfo());
  l.bus.publish("SLAM_MAP", cloudMessage(1, scene));
  l.bus.publish("SLAM_POSE", poseMessage(0, pose_t::STATE_TRACKING, T));
  ASSERT_TRUE(l.pump([&] { return l.proposals.count(0) > 0; }, 20s)) << node.log();
  const proposals_t& p0 = l.proposals[0];
  EXPECT_EQ(p0.map_id, 1);
  ASSERT_EQ(p0.num_boxes, static_cast<int>(p0.boxes.size()));
  ASSERT_EQ(p0.candidate_ids.size(), p0.boxes.size());
  // A box around each object: centred on its column, about its width (8 cm at ~0.9 m: ~45 px).
  for (double x : {-0.12, 0.12}) {
    bool found = false;
    for (const auto& b : p0.boxes) {
      const double centre = b.x + b.w / 2;
      if (std::abs(centre - columnOf(x, 0.9)) < 10 && b.w > 35 && b.w < 70) found = true;
    }
    EXPECT_TRUE(found) << "no box on the object at x = " << x;
  }

  // Bad input: a truncated cloud, bytes that are no message, a LOST pose.
  const point_cloud_t cloud = cloudMessage(1, scene);
  std::vector<uint8_t> truncated(static_cast<size_t>(cloud.getEncodedSize()));
  cloud.encode(truncated.data(), 0, static_cast<int>(truncated.size()));
  truncated.resize(truncated.size() - 100);
  l.bus.publishRaw("SLAM_MAP", truncated.data(), truncated.size());
  const uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7};
  l.bus.publishRaw("SLAM_MAP", garbage, sizeof garbage);
  l.bus.publish("SLAM_POSE", poseMessage(1, pose_t::STATE_LOST, T));
  l.bus.publish("SLAM_POSE", poseMessage(2, pose_t::STATE_TRACKING, T));
  ASSERT_TRUE(l.pump([&] { return l.proposals.count(2) > 0; }, 20s)) << node.log();
  EXPECT_TRUE(node.running());
  EXPECT_EQ(l.proposals[1].num_boxes, 0) << "boxes for a frame SLAM lost";
  // The map survived the bad clouds: the same boxes as before, with the same candidate ids.
  EXPECT_EQ(l.proposals[2].candidate_ids, p0.candidate_ids);
  ASSERT_TRUE(l.pump([&] { return l.have_status && l.last_status.rejected >= 2; }, 5s))
      << "rejected " << l.last_status.rejected;
  EXPECT_EQ(node.stop(), 0) << node.log();
}
