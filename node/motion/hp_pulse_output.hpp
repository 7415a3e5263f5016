// PULSE SD | SS with the PSTP and NDIR senses ("Setting the Pulse Mode and Sense" 3-7,
// Figure 3-1, Figure 3-7): which output a step's pulse appears at and the levels of both
// outputs during it, and back (what a driver wired to these outputs makes of them).
#pragma once
#include <cstdint>

#include "node/motion/hp_settings.hpp"

namespace stepnode::motion::hp {

struct PulseSetup {
  PulseMode mode = PulseMode::StepStep;  // power-on: PULSE SS LO LO
  bool pstp_high = false;                // HI/LH: low-high-low pulses; LO/HL: high-low-high
  bool ndir_high = false;                // NDIR sense (defaults to PSTP's when not given)
};

enum class Output : uint8_t { Pstp = 0, Ndir = 1 };

struct Pulse {
  Output output = Output::Pstp;               // where the pulse appears
  bool pstp_level = false;                    // PSTP level during the pulse
  bool ndir_level = false;                    // NDIR level during the pulse (SD: the direction)
  bool pstp_idle = false, ndir_idle = false;  // levels between pulses
};

// The pulse of one step in `direction` (+1 positive motion, -1 negative).
Pulse pulse_for(const PulseSetup& setup, int direction);
// The direction a driver wired for `setup` reads from `pulse` (+1 / -1).
int direction_of(const PulseSetup& setup, const Pulse& pulse);

}  // namespace stepnode::motion::hp
