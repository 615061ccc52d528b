#pragma once

namespace slamaware {
/// Registers the source schemes built into the camera (e.g. "synth:" once linked). Idempotent.
void registerBuiltinSourceSchemes();
}  // namespace slamaware
