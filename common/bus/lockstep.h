#pragma once
// What a lockstep source (the camera, the replayer) needs: wait until the pipeline's stages are up,
// then publish frame n+1 only after the last stage has answered frame n (docs/architecture.md §4).
#include <functional>
#include <string>
#include <vector>

namespace slamaware {

class Bus;

/// Tracks the highest seq seen on a channel of per-frame messages.
class LockstepGate {
 public:
  LockstepGate(Bus& bus, const std::string& channel);
  const std::string& channel() const { return channel_; }
  /// Handles the bus until a message with seq >= `seq` arrived on the channel. Calls idle()
  /// between waits. Returns false on timeout or shutdown.
  bool waitFor(int32_t seq, double timeout_s, const std::function<void()>& idle);

 private:
  Bus& bus_;
  std::string channel_;
  int32_t acked_ = -1;
};

/// Handles the bus until a message arrived on each of `channels` (e.g. the stages' *_STATUS) or
/// timeout_s passed. Returns the channels not heard from.
std::vector<std::string> waitForChannels(Bus& bus, const std::vector<std::string>& channels,
                                         double timeout_s, const std::function<void()>& idle);

/// "a,b,,c" -> {"a", "b", "c"}
std::vector<std::string> splitList(const std::string& comma_separated);

}  // namespace slamaware
