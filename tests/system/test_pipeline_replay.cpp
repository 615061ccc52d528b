// The whole pipeline (camera -> slam -> proposals -> recognizer -> objectmap, every stage its own
// process) replayed lockstep on the bundled recording logs/sample.lcm, twice (one frame at a time,
// then with several in the pipeline: bus.lockstep_window), in a private network namespace: every
// frame gets its DETECTIONS, OBJECT_DETECTIONS and OBJECT_MAP (and the frame the SLAM map was
// initialised from, not located when it came, gets a second, late set with its boxes), the two runs
// publish byte-identical payloads on the three channels, and the recognised objects are there (not
// only empty messages); no two published boxes of a frame that are surest of the same object class
// overlap by IoU > 0.5 (docs/architecture.md §3, suppressed per class), though the proposals did.
// The object map re-run on the recording's inputs gives the node's messages byte for byte, and on
// the first half of them the same messages for that half: a fused label never depends on a later
// frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

#include "common/bus/log_reader.h"
#include "common/bus/system_config.h"
#include "common/geometry.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/object_map_t.hpp"
#include "slamaware/proposals_t.hpp"
#include "tests/support/test_support.h"
#include "tests/system/lockstep_pipeline.h"
#include "tools/eval/pipeline_run.h"
#include "tools/eval/recognition_metrics.h"

using namespace slamaware;
namespace fs = std::filesystem;

namespace {

struct Recording {
  std::vector<std::vector<uint8_t>> detections, object_detections, object_maps;
  int camera_frames = 0;
  int64_t proposal_boxes = 0, overlapping_proposal_pairs = 0;
  std::vector<int32_t> proposal_seqs;  ///< in the order published
  std::vector<int32_t> late_seqs;      ///< proposals for a frame older than one proposed before
};

Recording record(const std::string& log_path, const Channels& ch) {
  Recording r;
  LogReader reader(log_path);
  while (auto m = reader.next()) {
    if (m->channel == ch.detections) r.detections.push_back(m->data);
    if (m->channel == ch.object_map) r.object_maps.push_back(m->data);
    if (m->channel == ch.object_detections) r.object_detections.push_back(m->data);
    proposals_t p;
    if (m->channel == ch.proposals &&
        p.decode(m->data.data(), 0, static_cast<int>(m->data.size())) > 0) {
      if (!r.proposal_seqs.empty() &&
          p.seq < *std::max_element(r.proposal_seqs.begin(), r.proposal_seqs.end())) {
        r.late_seqs.push_back(p.seq);
        EXPECT_GT(p.num_boxes, 0) << "late proposals for seq " << p.seq << " without boxes";
      }
      r.proposal_seqs.push_back(p.seq);
      r.proposal_boxes += p.num_boxes;
      for (size_t i = 0; i < p.boxes.size(); ++i)
        for (size_t j = i + 1; j < p.boxes.size(); ++j) {
          const box_t& a = p.boxes[i];
          const box_t& b = p.boxes[j];
          r.overlapping_proposal_pairs += rectIou(a.x, a.y, a.w, a.h, b.x, b.y, b.w, b.h) > 0.5;
        }
    }
    r.camera_frames += m->channel == ch.camera;
  }
  return r;
}

template <class Msg>
std::vector<uint8_t> bytes(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// Copies the events of a log up to (not including) its n+1-th DETECTIONS into `out`; returns the
// DETECTIONS kept.
int64_t truncateLog(const std::string& in, const std::string& out, const Channels& ch, int n) {
  lcm::LogFile writer(out, "w");
  LogReader reader(in);
  int64_t detections = 0, event = 0;
  while (auto m = reader.next()) {
    if (m->channel == ch.detections && detections++ == n) break;
    lcm::LogEvent e{};
    e.eventnum = event++;
    e.timestamp = m->timestamp;
    e.channel = m->channel;
    e.datalen = static_cast<int32_t>(m->data.size());
    e.data = const_cast<uint8_t*>(m->data.data());
    writer.writeEvent(&e);
  }
  return std::min<int64_t>(detections, n);
}

}  // namespace

TEST(PipelineReplay, TheBundledLogReplayedLockstepTwiceGivesByteIdenticalDetectionsAndObjectMaps) {
  SystemConfig sys;
  PipelineRunOptions options = test::lockstepPipeline(&sys);
  const std::string sample = test::sourcePath("logs/sample.lcm");
  ASSERT_TRUE(fs::exists(sample)) << sample;
  ASSERT_TRUE(fs::exists(test::sourcePath("models/recognizer.model")));
  const std::string dir = test::tempDir("pipeline_replay");

  // The first run one frame at a time, the second with the shipped lockstep window (several
  // frames in the pipeline at once): the outputs do not depend on it.
  std::vector<Recording> runs;
  const std::string shipped = test::sourcePath("config/system.yaml");
  ASSERT_GT(loadSystemConfig(shipped, false).bus.lockstep_window, 1)
      << "the test compares a window of 1 with the shipped one";
  const std::string one_at_a_time = dir + "/system-window-1.yaml";
  std::ofstream(one_at_a_time) << "bus:\n  lockstep_window: 1\n";
  for (int run = 0; run < 2; ++run) {
    const std::string log = dir + "/run" + std::to_string(run) + ".lcm";
    options.objectmap_dir = dir + "/map" + std::to_string(run);
    options.system_path = run == 0 ? one_at_a_time : shipped;
    const PipelineRun result = runPipeline(sample, log, sys, options);
    ASSERT_TRUE(result.ok) << result.error << " (process outputs: " << log << ".<stage>.txt)";
    ASSERT_EQ(result.stages,
              (std::vector<std::string>{"slam", "proposals", "recognizer", "objectmap"}));
    runs.push_back(record(log, sys.channels));
  }
  const int frames = record(sample, sys.channels).camera_frames;
  ASSERT_GT(frames, 100);
  for (const Recording& r : runs) {
    EXPECT_EQ(r.camera_frames, frames);
    EXPECT_EQ(r.late_seqs, std::vector<int32_t>{0}) << "the first map is initialised from frame 0";
    EXPECT_EQ(static_cast<int>(r.proposal_seqs.size()),
              frames + static_cast<int>(r.late_seqs.size()))
        << "one PROPOSALS per frame, and the late ones";
    EXPECT_EQ(r.detections.size(), r.proposal_seqs.size()) << "one DETECTIONS per PROPOSALS";
    EXPECT_EQ(r.object_maps.size(), r.detections.size()) << "one OBJECT_MAP per DETECTIONS";
    EXPECT_EQ(r.object_detections.size(), r.detections.size())
        << "one OBJECT_DETECTIONS per DETECTIONS";
  }
  ASSERT_EQ(runs[0].detections.size(), runs[1].detections.size());
  for (size_t i = 0; i < runs[0].detections.size(); ++i)
    ASSERT_EQ(runs[0].detections[i], runs[1].detections[i]) << "DETECTIONS #" << i << " differs";
  ASSERT_EQ(runs[0].object_maps.size(), runs[1].object_maps.size());
  for (size_t i = 0; i < runs[0].object_maps.size(); ++i)
    ASSERT_EQ(runs[0].object_maps[i], runs[1].object_maps[i]) << "OBJECT_MAP #" << i << " differs";
  ASSERT_EQ(runs[0].object_detections.size(), runs[1].object_detections.size());
  for (size_t i = 0; i < runs[0].object_detections.size(); ++i)
    ASSERT_EQ(runs[0].object_detections[i], runs[1].object_detections[i])
        << "OBJECT_DETECTIONS #" << i << " differs";

  // The object map re-run on the recorded inputs publishes what the node did, byte for byte...
  const std::string log0 = dir + "/run0.lcm";
  const objectmap::ObjectMapOptions
      map_options;  // config/objectmap.yaml equals the defaults (tested)
  const ObjectMapOutputs again = rerunObjectMap(log0, sys.channels, map_options);
  const ObjectMapOutputs recorded = readObjectMapOutputs(log0, sys.channels);
  ASSERT_EQ(again.frames.size(), recorded.frames.size());
  for (const auto& [seq, m] : recorded.frames)
    ASSERT_EQ(bytes(again.frames.at(seq)), bytes(m)) << "seq " << seq;
  EXPECT_EQ(bytes(again.last_map), bytes(recorded.last_map));
  // ...and on the first half of the recording, the same for that half: what a frame's boxes were
  // labelled depends on nothing later.
  const std::string half = dir + "/half.lcm";
  const int64_t kept =
      truncateLog(log0, half, sys.channels, static_cast<int>(recorded.frames.size() / 2));
  ASSERT_GT(kept, 10);
  const ObjectMapOutputs early = rerunObjectMap(half, sys.channels, map_options);
  ASSERT_EQ(static_cast<int64_t>(early.frames.size()), kept - 1)
      << "frame 0 is answered twice (late)";
  for (const auto& [seq, m] : early.frames)
    ASSERT_EQ(bytes(m), bytes(recorded.frames.at(seq)))
        << "seq " << seq << " changed by later frames";

  // What was replayed is the real thing: boxes were classified, and the map holds objects.
  int64_t boxes = 0;
  for (const auto& bytes : runs[0].detections) {
    detections_t d;
    ASSERT_EQ(d.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
              static_cast<int>(bytes.size()));
    boxes += d.num_boxes;
    // Suppression is per class (config/recognizer.yaml): two published boxes that overlap by more
    // than 0.5 are surest of different object classes (background last, not an object class).
    const auto surest = [&](int i) {
      const auto& lp = d.log_prob[static_cast<size_t>(i)];
      return std::max_element(lp.begin(), lp.end() - 1) - lp.begin();
    };
    for (int i = 0; i < d.num_boxes; ++i)
      for (int j = i + 1; j < d.num_boxes; ++j) {
        const box_t& a = d.boxes[static_cast<size_t>(i)];
        const box_t& b = d.boxes[static_cast<size_t>(j)];
        if (rectIou(a.x, a.y, a.w, a.h, b.x, b.y, b.w, b.h) > 0.5) {
          EXPECT_NE(surest(i), surest(j))
              << "DETECTIONS seq " << d.seq << ": boxes " << i << " and " << j;
        }
      }
  }
  EXPECT_GT(boxes, frames) << "fewer than one classified box per frame";
  // The proposals publish every box they draw; the recognizer suppressed the overlapping ones.
  EXPECT_GT(runs[0].overlapping_proposal_pairs, 0);
  EXPECT_LT(boxes, runs[0].proposal_boxes);
  object_map_t last;
  const auto& bytes = runs[0].object_maps.back();
  ASSERT_EQ(last.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_GE(last.num_objects, 1);
}
