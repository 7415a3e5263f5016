// What an axis drives and senses: the step sink (every step with its exact time and
// direction) and the inputs it reads. The simulated machine implements it (node/sim); a
// hardware backend (GPIO, a pulse generator) will implement the same interface.
#pragma once
#include <cstdint>

#include "node/motion/timebase.hpp"

namespace stepnode::motion {

// One step as the HP 44714A's outputs carry it (PULSE SD|SS, HP manual 3-7): the output it
// appears at and the NDIR level during it, with what the driver wired to them reads as
// positive motion.
struct OutputPulse {
  bool step_direction = false;       // SD: every pulse on PSTP, NDIR is the direction
  bool on_ndir = false;              // SS: this pulse is on NDIR (negative motion)
  bool ndir_level = false;           // NDIR during the pulse
  bool ndir_positive_level = false;  // SD: the NDIR level that means positive motion
  bool pstp_level = false;           // PSTP during the pulse (its pulse sense)
};

// The direction a driver set up for `p`'s mode reads from it (+1 / -1).
constexpr int direction_of(const OutputPulse& p) {
  if (p.step_direction) return p.ndir_level == p.ndir_positive_level ? +1 : -1;
  return p.on_ndir ? -1 : +1;
}

class MotorPort {
 public:
  virtual ~MotorPort() = default;
  // One step pulse at `time` (+1 up, -1 down).
  virtual void step(Tick time, int direction) = 0;
  // One step given as output signals (the HP channel's PULSE modes): a driver decodes the
  // direction from the outputs, so the motor follows the wiring, not the engine's intent.
  virtual void output_pulse(Tick time, const OutputPulse& p) { step(time, direction_of(p)); }
  virtual bool home() const = 0;
  virtual bool lower_limit() const = 0;
  virtual bool upper_limit() const = 0;
  virtual bool index() const = 0;
  virtual bool marker() const = 0;
  // Encoder counts (0 without an encoder): for a quadrature encoder every edge of A and B,
  // 4 per line, as a quadrature decoder counts them at its finest.
  virtual int64_t encoder_count() const = 0;
};

}  // namespace stepnode::motion
