#include "node/motion/hp_pulse_output.hpp"

namespace stepnode::motion::hp {

Pulse pulse_for(const PulseSetup& s, int direction) {
  Pulse p;
  // A pulse is the active level of its output's sense; idle is the other level.
  p.pstp_idle = !s.pstp_high;
  if (s.mode == PulseMode::StepDirection) {
    // SD: every pulse on PSTP; NDIR at its sense level for positive motion ("if HI is selected
    // for NDIRn_sense, a high on this output will set the motor driver for positive motion").
    p.output = Output::Pstp;
    p.pstp_level = s.pstp_high;
    p.ndir_level = direction > 0 ? s.ndir_high : !s.ndir_high;
    p.ndir_idle = p.ndir_level;  // the direction level holds between pulses
  } else {
    // SS: positive motion pulses on PSTP, negative on NDIR.
    p.ndir_idle = !s.ndir_high;
    p.output = direction > 0 ? Output::Pstp : Output::Ndir;
    p.pstp_level = direction > 0 ? s.pstp_high : p.pstp_idle;
    p.ndir_level = direction > 0 ? p.ndir_idle : s.ndir_high;
  }
  return p;
}

int direction_of(const PulseSetup& s, const Pulse& p) {
  if (s.mode == PulseMode::StepDirection) return p.ndir_level == s.ndir_high ? +1 : -1;
  return p.output == Output::Pstp ? +1 : -1;
}

}  // namespace stepnode::motion::hp
