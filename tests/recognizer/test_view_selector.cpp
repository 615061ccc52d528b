// View selection (procs/recognizer/view_selector.h): which boxes of a frame are classified and
// which carry their candidate's last result.
#include <gtest/gtest.h>

#include <cmath>

#include "procs/recognizer/view_selector.h"

namespace slamaware::recognizer {
namespace {

// Candidate `id` seen from `deg` degrees round the vertical axis, at `depth`, with a w x h box.
CandidateView seen(int32_t id, double deg, float depth = 1.f, float w = 100.f, float h = 80.f) {
  const double a = deg * M_PI / 180.0;
  return CandidateView{
      id, Eigen::Vector3f(static_cast<float>(std::sin(a)), 0.f, static_cast<float>(std::cos(a))),
      depth, w, h};
}

ViewSelectionOptions options(double angle_deg = 10, double scale = 0.15) {
  ViewSelectionOptions o;
  o.angle_deg = angle_deg;
  o.scale = scale;
  return o;
}

// One frame: select, then remember what was classified with a row naming the frame.
std::vector<const CarriedView*> frame(ViewSelector& s, int32_t map_id, int32_t seq,
                                      const std::vector<CandidateView>& views) {
  auto carried = s.select(map_id, seq, views);
  for (size_t i = 0; i < views.size(); ++i)
    if (!carried[i]) s.remember(map_id, seq, views[i], {static_cast<float>(-seq), -1.f});
  return carried;
}

TEST(ViewSelector, ACandidateSeenFromTheSameViewCarriesItsResult) {
  ViewSelector s(options());
  EXPECT_EQ(frame(s, 1, 0, {seen(5, 0)})[0], nullptr);  // first sighting: classified
  const auto carried = frame(s, 1, 1, {seen(5, 4)});    // 4 degrees on: carried
  ASSERT_NE(carried[0], nullptr);
  EXPECT_EQ(carried[0]->seq, 0);
  EXPECT_EQ(carried[0]->log_prob, (std::vector<float>{-0.f, -1.f}));
  ASSERT_NE(frame(s, 1, 2, {seen(5, 9)})[0], nullptr);   // 9 degrees from the view of frame 0
  EXPECT_EQ(frame(s, 1, 3, {seen(5, 11)})[0], nullptr);  // 11 degrees: a new view, classified
  const auto after = frame(s, 1, 4, {seen(5, 15)});      // 4 degrees from frame 3's view
  ASSERT_NE(after[0], nullptr);
  EXPECT_EQ(after[0]->seq, 3);
}

TEST(ViewSelector, ANearerOrFartherViewOrAGrownBoxIsNew) {
  ViewSelector s(options());
  frame(s, 1, 0, {seen(5, 0, 1.f, 100, 80)});
  EXPECT_NE(frame(s, 1, 1, {seen(5, 0, 1.1f, 91, 73)})[0],
            nullptr);  // 10 % farther, same metric size
  EXPECT_EQ(frame(s, 1, 2, {seen(5, 0, 1.2f, 83, 67)})[0], nullptr);  // 20 % farther: new
  EXPECT_EQ(frame(s, 1, 3, {seen(5, 0, 1.2f, 83, 90)})[0],
            nullptr);  // box 34 % taller at that depth: new
  EXPECT_NE(frame(s, 1, 4, {seen(5, 0, 1.2f, 86, 92)})[0], nullptr);  // within 15 % of frame 3
}

TEST(ViewSelector, ACandidateThatLeftTheViewIsClassifiedAgainWhenItReturns) {
  ViewSelector s(options());
  frame(s, 1, 0, {seen(5, 0), seen(6, 0)});
  EXPECT_NE(frame(s, 1, 1, {seen(5, 0), seen(6, 0)})[1], nullptr);
  frame(s, 1, 2, {seen(5, 0)});  // 6 occluded
  EXPECT_EQ(s.size(), 1u);       // only the candidates of the last frame are remembered
  const auto back = frame(s, 1, 3, {seen(5, 0), seen(6, 0)});
  EXPECT_NE(back[0], nullptr);
  EXPECT_EQ(back[1], nullptr);
}

TEST(ViewSelector, CandidatesOfAnotherMapOrWithoutGeometryAreClassified) {
  ViewSelector s(options());
  frame(s, 1, 0, {seen(5, 0)});
  EXPECT_EQ(frame(s, 2, 1, {seen(5, 0)})[0], nullptr);  // same id, another SLAM map
  EXPECT_NE(frame(s, 2, 2, {seen(5, 0)})[0], nullptr);
  CandidateView unknown = seen(5, 0);
  unknown.direction.setZero();  // old recordings, or no direction
  EXPECT_EQ(frame(s, 2, 3, {unknown})[0], nullptr);
  EXPECT_EQ(frame(s, 2, 4, {unknown})[0], nullptr);
  EXPECT_EQ(frame(s, 2, 5, {seen(-1, 0)})[0], nullptr);  // no candidate
  EXPECT_EQ(frame(s, 2, 6, {seen(-1, 0)})[0], nullptr);
  frame(s, 2, 7, {seen(7, 0), seen(7, 0)});  // one candidate boxed twice
  const auto twice = frame(s, 2, 8, {seen(7, 0), seen(7, 0)});
  EXPECT_EQ(twice[0], nullptr);
  EXPECT_EQ(twice[1], nullptr);
}

TEST(ViewSelector, AnOlderFrameIsClassifiedInFullAndChangesNothing) {
  ViewSelector s(options());
  frame(s, 1, 5, {seen(5, 0)});
  EXPECT_EQ(frame(s, 1, 3, {seen(5, 0)})[0], nullptr);  // late: classified, not remembered
  const auto next = frame(s, 1, 6, {seen(5, 0)});
  ASSERT_NE(next[0], nullptr);
  EXPECT_EQ(next[0]->seq, 5);
  s.clear();  // a restarted camera: its seqs start again
  frame(s, 1, 0, {seen(5, 0)});
  const auto after = frame(s, 1, 1, {seen(5, 0)});
  ASSERT_NE(after[0], nullptr);
  EXPECT_EQ(after[0]->seq, 0);
}

// A frame that real time has no time to classify gets the last results of its candidates,
// whatever its view: those of the last frame selected, of the candidate's map; none for a
// candidate that frame did not have.
TEST(ViewSelector, TheLastResultOfACandidateIsThatOfTheLastFrameSelected) {
  ViewSelector s(options());
  frame(s, 1, 0, {seen(5, 0), seen(6, 0)});
  frame(s, 1, 1, {seen(5, 30)});  // 6 left the view; 5 classified again from another side
  const CarriedView* r = s.lastResult(1, 5);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->seq, 1);
  EXPECT_EQ(r->log_prob, (std::vector<float>{-1.f, -1.f}));
  EXPECT_EQ(s.lastResult(1, 6), nullptr);
  EXPECT_EQ(s.lastResult(2, 5), nullptr);  // another map's candidate 5
  s.clear();
  EXPECT_EQ(s.lastResult(1, 5), nullptr);
}

TEST(ViewSelector, DisabledOrClearedEveryBoxIsClassified) {
  ViewSelectionOptions off = options();
  off.enabled = false;
  ViewSelector s(off);
  frame(s, 1, 0, {seen(5, 0)});
  EXPECT_EQ(frame(s, 1, 1, {seen(5, 0)})[0], nullptr);
  ViewSelector t(options());
  frame(t, 1, 0, {seen(5, 0)});
  t.clear();  // another model
  EXPECT_EQ(frame(t, 1, 1, {seen(5, 0)})[0], nullptr);
}

}  // namespace
}  // namespace slamaware::recognizer
