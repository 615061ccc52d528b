#pragma once

namespace slamaware::camera {
/// Registers the source schemes built into the camera (e.g. "synth:" once linked). Idempotent.
void registerBuiltinSourceSchemes();
}  // namespace slamaware::camera
