#include "procs/camera/register_sources.h"

namespace slamaware {
void registerBuiltinSourceSchemes() {}
}  // namespace slamaware
