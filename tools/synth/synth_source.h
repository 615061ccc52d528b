#pragma once
// The "synth:" camera source: renders a scene config on the fly, frame by frame, exactly as
// `slamaware-synth scene` writes it (same pixels, same JPEG bytes, seq = frame index,
// utime = frame index / fps).
//   synth:CONFIG                 the config's seed and frame count
//   synth:CONFIG?seed=N&frames=M another seed; only the first M frames
#include <memory>
#include <string>

#include "common/frame_source.h"

namespace slamaware::synth {

/// Opens "CONFIG[?seed=N&frames=M]" (the part after "synth:"); throws SourceError naming the
/// argument for a bad config or query.
std::unique_ptr<FrameSource> openSynthSource(const std::string& arg);

/// Registers the "synth" scheme with the source registry (common/frame_source.h).
void registerSynthSource();

}  // namespace slamaware::synth
