#include "procs/camera/register_sources.h"

#include "procs/camera/log_source.h"
#include "tools/synth/synth_source.h"

namespace slamaware::camera {
void registerBuiltinSourceSchemes() {
  registerLogSource();
  synth::registerSynthSource();
}
}  // namespace slamaware::camera
