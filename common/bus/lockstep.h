#pragma once
// What a lockstep source (the camera, the replayer) needs: wait until the pipeline's stages are up,
// then publish a frame only while fewer than `bus.lockstep_window` published frames wait for the
// last stage's answer (1: frame n+1 after the answer to frame n; docs/architecture.md §4).
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <vector>

namespace slamaware {

class Bus;

/// Tracks the highest seq seen on a channel of per-frame messages, and the frames published and
/// not answered yet.
class LockstepGate {
 public:
  /// `window`: frames that may wait for their answer at once (at least 1).
  LockstepGate(Bus& bus, const std::string& channel, int window = 1);
  const std::string& channel() const { return channel_; }

  /// The source published frame `seq`.
  void published(int32_t seq) { waiting_.push_back(seq); }
  /// Handles the bus until another frame may be published (fewer than `window` unanswered), or
  /// with `all` until every published frame was answered. On a timeout the oldest frame waited
  /// for is given up (its seq in *timed_out) and false returned; false too on shutdown.
  bool waitForRoom(bool all, double timeout_s, const std::function<void()>& idle,
                   int32_t* timed_out);

 private:
  /// Handles the bus until a message with seq >= `seq` arrived on the channel. Calls idle()
  /// between waits. Returns false on timeout or shutdown.
  bool waitFor(int32_t seq, double timeout_s, const std::function<void()>& idle);

  Bus& bus_;
  std::string channel_;
  size_t window_;
  int32_t acked_ = -1;
  std::deque<int32_t> waiting_;  ///< published, not answered, oldest first
};

/// Handles the bus until a message arrived on each of `channels` (e.g. the stages' *_STATUS) or
/// timeout_s passed. Returns the channels not heard from.
std::vector<std::string> waitForChannels(Bus& bus, const std::vector<std::string>& channels,
                                         double timeout_s, const std::function<void()>& idle);

/// "a,b,,c" -> {"a", "b", "c"}
std::vector<std::string> splitList(const std::string& comma_separated);

}  // namespace slamaware
