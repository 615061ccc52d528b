#include "procs/camera/register_sources.h"

#include "procs/synth/synth_source.h"

namespace slamaware {
void registerBuiltinSourceSchemes() { registerSynthSource(); }
}  // namespace slamaware
