// slamaware-slam as a process, each case in its own network namespace: a recorded log replayed
// lockstep through it gives a trajectory within a stated ATE of the ground truth, one SLAM_POSE
// per frame, and the same bytes on a second run; bad input (black, repeated, corrupt, wrong-size
// frames, time going backwards, malformed messages) leaves it running, with every state change
// reported and no pose jump without one.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "common/bus/image_msg.h"
#include "common/bus/log_reader.h"
#include "common/dataset.h"
#include "common/image_codec.h"
#include "slamaware/camera_info_t.hpp"
#include "slamaware/pose_t.hpp"
#include "slamaware/status_t.hpp"
#include "tests/support/test_support.h"
#include "tools/eval/pipeline_run.h"
#include "tools/eval/slam_metrics.h"
#include "tools/synth/scene.h"

using namespace slamaware;
using namespace std::chrono_literals;

namespace {

struct PoseMessage {
  pose_t msg;
  std::vector<uint8_t> bytes;
};

std::vector<PoseMessage> readPoses(const std::string& log) {
  std::vector<PoseMessage> out;
  for (auto& r : LogReader::readAll(log)) {
    if (r.channel != "SLAM_POSE") continue;
    PoseMessage p;
    EXPECT_EQ(p.msg.decode(r.data.data(), 0, static_cast<int>(r.data.size())),
              static_cast<int>(r.data.size()));
    p.bytes = std::move(r.data);
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<std::vector<uint8_t>> payloads(const std::string& log, const std::string& channel) {
  std::vector<std::vector<uint8_t>> out;
  for (auto& r : LogReader::readAll(log))
    if (r.channel == channel) out.push_back(std::move(r.data));
  return out;
}

/// The last SLAM_STATUS in a log, as counter name -> value.
std::map<std::string, int64_t> lastStatus(const std::string& log) {
  std::map<std::string, int64_t> counters;
  for (auto& r : LogReader::readAll(log)) {
    if (r.channel != "SLAM_STATUS") continue;
    status_t s;
    if (s.decode(r.data.data(), 0, static_cast<int>(r.data.size())) <= 0) continue;
    counters.clear();
    for (int i = 0; i < s.num_counters; ++i) counters[s.counter_names[i]] = s.counter_values[i];
    counters["rejected"] = s.rejected;
  }
  return counters;
}

/// Plays `log` lockstep (each frame waits for the previous frame's SLAM_POSE) through
/// slamaware-slam and records what it publishes. Returns the recording.
std::string replayThroughSlam(const std::string& dir, const std::string& log,
                              const std::string& name) {
  const std::string out = dir + "/" + name + ".lcm";
  test::BusRecorder recorder(out, "SLAM_.*");
  test::ChildProcess slam(
      {test::binPath("slamaware-slam"), "--lockstep", "--lcm-url", test::testUrl()},
      dir + "/" + name + ".slam.txt");
  test::ChildProcess replay({test::binPath("slamaware-replay"), log, "--lcm-url", test::testUrl(),
                             "--lockstep", "SLAM_POSE", "--wait-for", "SLAM_STATUS"},
                            dir + "/" + name + ".replay.txt");
  EXPECT_EQ(replay.wait(300s), 0) << replay.log();
  EXPECT_TRUE(slam.running()) << "slamaware-slam died:\n" << slam.log();
  std::this_thread::sleep_for(1200ms);  // one more heartbeat with the final counters
  EXPECT_EQ(slam.stop(10s), 0) << slam.log();
  recorder.stop();
  return out;
}

/// Records a sequence folder through the camera (CAMERA_INFO and CAMERA only).
std::string recordSequence(const std::string& dir, const std::string& sequence, double speed) {
  const std::string log = dir + "/input.lcm";
  test::BusRecorder recorder(log, "CAMERA.*");
  test::ChildProcess camera({test::binPath("slamaware-camera"), "--source", sequence, "--lcm-url",
                             test::testUrl(), "--speed", std::to_string(speed)},
                            dir + "/camera.txt");
  EXPECT_EQ(camera.wait(120s), 0) << camera.log();
  recorder.stop();
  return log;
}

/// ATE RMSE (m) of TRACKING / RELOCALIZED poses against ground truth by seq, each map aligned
/// on its own by Sim(3) (Umeyama).
double ateRmse(const std::vector<PoseMessage>& poses, const std::map<int, Eigen::Vector3d>& truth,
               int* used) {
  std::map<int, std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>>> by_map;
  for (const auto& p : poses) {
    if (p.msg.state != pose_t::STATE_TRACKING && p.msg.state != pose_t::STATE_RELOCALIZED) continue;
    auto t = truth.find(p.msg.seq);
    if (t == truth.end()) continue;
    by_map[p.msg.map_id].first.push_back(
        Eigen::Vector3d(p.msg.position[0], p.msg.position[1], p.msg.position[2]));
    by_map[p.msg.map_id].second.push_back(t->second);
  }
  double sq = 0;
  *used = 0;
  for (const auto& [id, pairs] : by_map) {
    if (pairs.first.size() < 3) continue;
    const Sim3 s = alignUmeyama(pairs.first, pairs.second, true);
    for (size_t i = 0; i < pairs.first.size(); ++i) {
      sq += (s * pairs.first[i] - pairs.second[i]).squaredNorm();
      ++*used;
    }
  }
  return *used ? std::sqrt(sq / *used) : 1e9;
}

}  // namespace

TEST(SlamNode, LockstepReplayOfTheTempleRingIsAccurateAndDeterministic) {
  const std::string temple = test::sharedData("sequences/middlebury_temple_ring");
  SKIP_WITHOUT_SHARED_DATA(temple);
  const std::string dir = test::tempDir("slam_node_temple");
  const std::string input = recordSequence(dir, temple, 20);
  const SequenceFolder seq = SequenceFolder::open(temple);
  ASSERT_EQ(payloads(input, "CAMERA").size(), seq.size()) << "the recording lost frames";

  const std::string run1 = replayThroughSlam(dir, input, "run1");
  const std::vector<PoseMessage> poses = readPoses(run1);
  // Exactly one pose per frame, in order.
  ASSERT_EQ(poses.size(), seq.size());
  for (size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(poses[i].msg.seq, static_cast<int32_t>(i));

  // The views come in five arcs with jumps of 40-160 degrees between them: SLAM must relocalise
  // or start new maps. Bound: ATE under 3 cm (the ring is 1.1 m across; 0.4% of the 7.2 m path)
  // and at least 85% of the views located when they are handled.
  const SlamRecording recording = readSlamRecording(run1, Channels());
  const nlohmann::json m = evaluateSlam(recording, seq, SlamEvalOptions());
  EXPECT_LT(m["ate_rmse"].get<double>(), 0.03) << m.dump(2);
  EXPECT_GE(m["tracked_pct"].get<double>(), 85.0) << m.dump(2);
  EXPECT_GT(m["semi_dense_points"].get<int64_t>(), 5000) << m.dump(2);

  // Lockstep: the same log gives the same bytes.
  const std::string run2 = replayThroughSlam(dir, input, "run2");
  EXPECT_EQ(payloads(run1, "SLAM_POSE"), payloads(run2, "SLAM_POSE"));
  EXPECT_EQ(payloads(run1, "SLAM_KEYFRAME"), payloads(run2, "SLAM_KEYFRAME"));
  EXPECT_EQ(payloads(run1, "SLAM_MAP"), payloads(run2, "SLAM_MAP"));
}

TEST(SlamNode, LockstepReplayOfTheBundledSampleIsAccurate) {
  const std::string log = test::sourcePath("logs/sample.lcm");
  if (!std::filesystem::exists(log)) GTEST_SKIP() << "logs/sample.lcm is not there (make sample)";
  const std::string dir = test::tempDir("slam_node_sample");
  const std::string out = replayThroughSlam(dir, log, "sample");
  const std::vector<PoseMessage> poses = readPoses(out);
  // Ground truth: the generator's camera path for the sample scene (no rendering needed).
  const synth::SceneOptions options =
      synth::loadSceneOptions(test::sourcePath("config/scenes/sample.yaml"));
  const synth::SyntheticScene scene(options);
  std::map<int, Eigen::Vector3d> truth;
  double path = 0;
  for (int i = 0; i < scene.frames(); ++i) {
    truth[i] = scene.pose(i).translation();
    if (i > 0) path += (truth[i] - truth[i - 1]).norm();
  }
  ASSERT_EQ(static_cast<int>(poses.size()), scene.frames());
  int tracked = 0, used = 0;
  for (const auto& p : poses)
    tracked += p.msg.state == pose_t::STATE_TRACKING || p.msg.state == pose_t::STATE_RELOCALIZED;
  const double ate = ateRmse(poses, truth, &used);
  // Bound: 98% of the frames tracked, ATE under 1% of the path length (the suite's targets).
  EXPECT_GE(tracked, 0.98 * scene.frames());
  EXPECT_LT(ate, 0.01 * path) << "ATE " << ate << " m over a " << path << " m path";
}

namespace {

// No silent jumps: between consecutive poses that both claim continuity (TRACKING after
// TRACKING / RELOCALIZED, same map), the camera moves less than the temple's views do (7.7
// degrees, ~0.14 map units) by a wide margin; a LOST pose repeats the last valid one.
void expectNoSilentJumps(const std::vector<PoseMessage>& poses) {
  for (size_t i = 1; i < poses.size(); ++i) {
    const pose_t& a = poses[i - 1].msg;
    const pose_t& b = poses[i].msg;
    if (b.state == pose_t::STATE_LOST) {
      // A LOST pose repeats the last valid one.
      if (a.state != pose_t::STATE_INITIALIZING) {
        for (int k = 0; k < 3; ++k)
          EXPECT_DOUBLE_EQ(a.position[k], b.position[k]) << "LOST pose moved at seq " << b.seq;
      }
      continue;
    }
    if (b.state != pose_t::STATE_TRACKING || a.map_id != b.map_id) continue;
    if (a.state != pose_t::STATE_TRACKING && a.state != pose_t::STATE_RELOCALIZED) continue;
    const SE3 Ta = se3FromArrays(a.position, a.orientation),
              Tb = se3FromArrays(b.position, b.orientation);
    EXPECT_LT((Ta.translation() - Tb.translation()).norm(), 0.5)
        << "jump without a state change at seq " << b.seq;
    EXPECT_LT(angleBetween(Ta, Tb) * 180 / M_PI, 25.0)
        << "jump without a state change at seq " << b.seq;
  }
}

}  // namespace

TEST(SlamNode, BadInputKeepsItRunningAndEveryJumpComesWithAStateChange) {
  const std::string temple = test::sharedData("sequences/middlebury_temple_ring");
  SKIP_WITHOUT_SHARED_DATA(temple);
  const std::string dir = test::tempDir("slam_node_bad_input");
  const SequenceFolder seq = SequenceFolder::open(temple);
  const CameraModel& cam = seq.info().camera;

  // An input log written by hand: frames 12-26 of the temple ring (one continuous arc) with bad
  // input spliced in.
  const std::string log = dir + "/bad_input.lcm";
  int64_t clock = 1000000;
  int32_t next_seq = 0;
  int frames_sent = 0;
  {
    lcm::LogFile file(log, "w");
    ASSERT_TRUE(file.good());
    auto write = [&](const std::string& channel, const std::vector<uint8_t>& bytes) {
      lcm::LogEvent ev;
      ev.eventnum = 0;
      ev.timestamp = (clock += 10000);
      ev.channel = channel;
      ev.datalen = static_cast<int32_t>(bytes.size());
      ev.data = const_cast<uint8_t*>(bytes.data());
      file.writeEvent(&ev);
    };
    auto encode = [](const auto& msg) {
      std::vector<uint8_t> b(static_cast<size_t>(msg.getEncodedSize()));
      msg.encode(b.data(), 0, static_cast<int>(b.size()));
      return b;
    };
    camera_info_t info;
    info.width = cam.width();
    info.height = cam.height();
    info.fx = cam.fx();
    info.fy = cam.fy();
    info.cx = cam.cx();
    info.cy = cam.cy();
    for (double& d : info.distortion) d = 0;
    info.source = "test";
    write("CAMERA_INFO", encode(info));
    int64_t utime = 0;
    auto frameMsg = [&](const cv::Mat& bgr) {
      utime += 1000000;
      return makeImageMessage(bgr, utime, next_seq++, image_t::PIXEL_FORMAT_JPEG, 95);
    };
    auto sendFrame = [&](const image_t& m) {
      write("CAMERA", encode(m));
      ++frames_sent;
    };
    int view = 12;
    auto good = [&]() { sendFrame(frameMsg(readImage(seq.framePath(view++)))); };
    for (int i = 0; i < 5; ++i) good();  // initialise, track
    sendFrame(frameMsg(cv::Mat(cam.height(), cam.width(), CV_8UC3, cv::Scalar(0, 0, 0))));  // black
    good();
    const image_t repeated = frameMsg(readImage(seq.framePath(view++)));
    sendFrame(repeated);
    sendFrame(repeated);  // the same message twice
    image_t corrupt = frameMsg(readImage(seq.framePath(view)));
    corrupt.data.resize(corrupt.data.size() / 3);  // a truncated JPEG
    corrupt.size = static_cast<int32_t>(corrupt.data.size());
    sendFrame(corrupt);
    good();
    cv::Mat small;
    cv::resize(readImage(seq.framePath(view)), small, cv::Size(320, 240));
    sendFrame(frameMsg(small));  // the wrong size
    good();
    const cv::Mat same = readImage(seq.framePath(view - 1));
    sendFrame(frameMsg(same));  // a frozen camera
    image_t back = frameMsg(readImage(seq.framePath(view++)));
    back.utime -= 5000000;  // time goes backwards
    sendFrame(back);
    write("CAMERA", {1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11,
                     12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22});  // not an image_t
    write("CAMERA_INFO", {0xde, 0xad, 0xbe, 0xef});                 // not a camera_info_t
    image_t rgb = makeImageMessage(readImage(seq.framePath(view)), utime + 1000000, next_seq++,
                                   image_t::PIXEL_FORMAT_RGB8);
    utime += 1000000;
    rgb.data.resize(100);  // RGB8 with too few bytes
    rgb.size = 100;
    sendFrame(rgb);
    for (int i = 0; i < 4; ++i) good();
  }

  const std::string out = replayThroughSlam(dir, log, "run");
  const std::vector<PoseMessage> poses = readPoses(out);
  // One pose per image message (the duplicate is answered twice).
  ASSERT_EQ(static_cast<int>(poses.size()), frames_sent);

  // States: the black, corrupt and wrong-size frames are LOST; the first frame located after a
  // LOST one says RELOCALIZED (or starts a new map).
  std::map<int32_t, int8_t> state_of;
  for (const auto& p : poses) state_of[p.msg.seq] = p.msg.state;
  EXPECT_EQ(state_of[5], pose_t::STATE_LOST) << "black frame";
  EXPECT_EQ(state_of[8], pose_t::STATE_LOST) << "corrupt JPEG";
  EXPECT_EQ(state_of[10], pose_t::STATE_LOST) << "wrong size";
  EXPECT_EQ(state_of[14], pose_t::STATE_LOST) << "RGB8 with missing bytes";
  int located = 0;
  for (const auto& p : poses)
    located += p.msg.state == pose_t::STATE_TRACKING || p.msg.state == pose_t::STATE_RELOCALIZED;
  EXPECT_GE(located, 10) << "of 15 good frames";

  expectNoSilentJumps(poses);

  // Everything that was wrong is counted in SLAM_STATUS.
  const auto status = lastStatus(out);
  EXPECT_GE(status.count("rejected.CAMERA") ? status.at("rejected.CAMERA") : 0,
            4);  // corrupt, size, bytes, RGB8
  EXPECT_GE(status.count("rejected.CAMERA_INFO") ? status.at("rejected.CAMERA_INFO") : 0, 1);
  EXPECT_GE(status.count("frames_duplicate") ? status.at("frames_duplicate") : 0, 1);
  EXPECT_GE(status.count("time_discontinuities") ? status.at("time_discontinuities") : 0, 1);
  EXPECT_GE(status.count("frames_corrupt") ? status.at("frames_corrupt") : 0, 2);
  EXPECT_GE(status.count("frames_wrong_size") ? status.at("frames_wrong_size") : 0, 1);
}
