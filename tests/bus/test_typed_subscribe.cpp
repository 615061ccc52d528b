// The safe typed subscribe: every kind of malformed message is rejected and counted, good ones
// are delivered, handler exceptions are contained. In-process bus (memq://), no network.
#include <gtest/gtest.h>

#include <random>

#include "common/bus/bus.h"
#include "common/bus/frame_stamp.h"
#include "slamaware/detections_t.hpp"
#include "slamaware/image_t.hpp"
#include "slamaware/pose_t.hpp"

using namespace slamaware;

namespace {

std::vector<uint8_t> encode(const detections_t& m) {
  std::vector<uint8_t> buf(m.getEncodedSize());
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

detections_t sampleDetections() {
  detections_t d{};
  d.utime = 123456789;
  d.seq = 42;
  d.map_id = 1;
  d.class_names = {"bowl", "cap", "background"};
  d.num_classes = 3;
  d.num_boxes = 2;
  d.boxes.resize(2);
  d.boxes[0].x = 1;
  d.boxes[0].w = 30;
  d.candidate_ids = {7, 9};
  d.classified_seq = {d.seq, d.seq - 3};
  d.log_prob = {{-0.1f, -2.f, -3.f}, {-1.f, -0.5f, -2.f}};
  d.encode_ms = 12.5f;
  return d;
}

struct Fixture : ::testing::Test {
  Bus bus{"memq://"};
  std::vector<detections_t> got;
  void SetUp() override {
    bus.subscribe<detections_t>(
        "DETECTIONS", [this](const detections_t& m) { got.push_back(m); }, 4096);
  }
  void send(const std::vector<uint8_t>& bytes) {
    bus.publishRaw("DETECTIONS", bytes.data(), bytes.size());
    while (bus.handle(0) > 0) {
    }
  }
};

}  // namespace

TEST_F(Fixture, GoodMessageIsDelivered) {
  send(encode(sampleDetections()));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].seq, 42);
  EXPECT_EQ(got[0].class_names[2], "background");
  EXPECT_FLOAT_EQ(got[0].log_prob[1][1], -0.5f);
  EXPECT_EQ(bus.totalRejects(), 0);
}

TEST_F(Fixture, EveryKindOfMalformedMessageIsRejectedAndCounted) {
  const std::vector<uint8_t> good = encode(sampleDetections());
  std::vector<std::vector<uint8_t>> bad;
  // truncated
  bad.emplace_back(good.begin(), good.end() - 5);
  bad.emplace_back(good.begin(), good.begin() + 3);
  // wrong fingerprint: a pose_t on the DETECTIONS channel
  pose_t pose{};
  std::vector<uint8_t> p(pose.getEncodedSize());
  pose.encode(p.data(), 0, static_cast<int>(p.size()));
  bad.push_back(p);
  // huge length field: num_classes (after utime, seq, map_id) set to 2^31-1
  std::vector<uint8_t> huge = good;
  const size_t off = 8 + 8 + 4 + 4;
  huge[off] = 0x7f;
  huge[off + 1] = huge[off + 2] = huge[off + 3] = 0xff;
  bad.push_back(huge);
  // negative length field
  std::vector<uint8_t> negative = good;
  negative[off] = 0xff;
  bad.push_back(negative);
  // a string length of zero (must include its NUL)
  std::vector<uint8_t> zero_string = good;
  zero_string[off + 4] = zero_string[off + 5] = zero_string[off + 6] = zero_string[off + 7] = 0;
  bad.push_back(zero_string);
  // a string with a NUL inside, and one whose last byte is not its NUL: lcm-gen's decoder kept
  // them, and its encoder then wrote fewer bytes than getEncodedSize() (a relayed name would
  // not publish)
  const size_t first_name = off + 4 + 4;  // "bowl\0" after num_classes and its length
  std::vector<uint8_t> inner_nul = good;
  inner_nul[first_name + 1] = 0;
  bad.push_back(inner_nul);
  std::vector<uint8_t> unterminated = good;
  unterminated[first_name + 4] = 'x';
  bad.push_back(unterminated);
  // trailing bytes
  std::vector<uint8_t> trailing = good;
  trailing.push_back(0);
  trailing.push_back(1);
  bad.push_back(trailing);
  // random bytes, and random bytes behind the right fingerprint
  std::mt19937 rng(11);
  for (int i = 0; i < 50; ++i) {
    std::vector<uint8_t> r(1 + rng() % 300);
    for (auto& b : r) b = static_cast<uint8_t>(rng());
    bad.push_back(r);
    std::vector<uint8_t> r2(good.begin(), good.begin() + 8);
    r2.insert(r2.end(), r.begin(), r.end());
    bad.push_back(r2);
  }
  // over the channel's size cap
  bad.emplace_back(5000, 0);
  for (const auto& b : bad) send(b);
  EXPECT_EQ(got.size(), 0u) << "no malformed message may reach the handler";
  EXPECT_EQ(bus.rejects().at("DETECTIONS"), static_cast<int64_t>(bad.size()));
  EXPECT_NE(bus.lastProblem().find("DETECTIONS"), std::string::npos);
  send(good);
  EXPECT_EQ(got.size(), 1u) << "the subscription keeps working after rejects";
}

TEST_F(Fixture, HandlerExceptionIsContainedAndCounted) {
  bus.subscribe<pose_t>("POSE", [](const pose_t&) { throw std::runtime_error("boom"); });
  pose_t pose{};
  std::vector<uint8_t> p(pose.getEncodedSize());
  pose.encode(p.data(), 0, static_cast<int>(p.size()));
  for (int i = 0; i < 3; ++i) {
    bus.publishRaw("POSE", p.data(), p.size());
    while (bus.handle(0) > 0) {
    }
  }
  EXPECT_EQ(bus.handlerErrors().at("POSE"), 3);
  EXPECT_EQ(bus.totalRejects(), 3);
}

TEST(FrameStamp, ReadsUtimeAndSeqOfPerFrameTypesOnly) {
  const std::vector<uint8_t> d = encode(sampleDetections());
  auto s = peekFrameStamp(d.data(), d.size());
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->utime, 123456789);
  EXPECT_EQ(s->seq, 42);
  const std::vector<uint8_t> cut(d.begin(), d.end() - 1);
  EXPECT_FALSE(peekFrameStamp(cut.data(), cut.size()).has_value())
      << "a truncated message is not an answer";
  image_t img{};
  img.seq = -7;
  std::vector<uint8_t> b(img.getEncodedSize());
  img.encode(b.data(), 0, static_cast<int>(b.size()));
  EXPECT_EQ(peekFrameStamp(b.data(), b.size())->seq, -7);
  const uint8_t junk[32] = {1, 2, 3};
  EXPECT_FALSE(peekFrameStamp(junk, sizeof(junk)).has_value());
}
