// The encoder an axis reads (the configuration object 0x2n09 sub 1): the axis' rules
// depend on it (SPM30 5.4 position validation, the marker as origin), and a back end
// (the simulated machine, hardware) provides the counts.
#pragma once
#include <cstdint>

namespace stepnode::motion {

enum class EncoderKind : uint8_t { None = 0, Quadrature = 1, UpDown = 2, QuadratureNoMarker = 3 };

}  // namespace stepnode::motion
