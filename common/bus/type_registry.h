#pragma once
// Names of our message types by their LCM fingerprint (for tools that watch the whole bus).
#include <cstddef>
#include <cstdint>
#include <string>

namespace slamaware {

/// "slamaware.pose_t" for the fingerprint of pose_t, "" for a fingerprint that is not ours.
std::string typeNameOfMessage(const uint8_t* data, size_t size);
/// A one-line summary of a message's content ("seq 41 TRACKING map 1", "12 boxes", ...), "" if
/// unknown.
std::string summarizeMessage(const uint8_t* data, size_t size);

}  // namespace slamaware
