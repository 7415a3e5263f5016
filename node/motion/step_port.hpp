// The step output of one motor, as Klipper separates planning (trapq) from step output
// (stepcompress): the motion core gives each step to the port ahead of its time (up to the
// port's horizon), tells it when the steps up to a time must have gone out (flush), takes
// back the steps after a time when the motion changes course (halt, e-stop, limit), and
// can ask where the motor was at a past time. A hardware back end (a pulse generator with
// a queue, a PRU, a microcontroller) implements it; the simulated machine (node/sim) is the
// default back end.
#pragma once
#include <cstdint>
#include <optional>

#include "node/motion/timebase.hpp"

namespace stepnode::motion {

// One step as the HP 44714A's outputs carry it (PULSE SD|SS, HP manual 3-7): the output it
// appears at and the NDIR level during it, with what the driver wired to them reads as
// positive motion, and how long the pulse lasts (PROFILE FREQ's pwidth, 3-8, or the width
// a WIDTH-mode SUSTAIN has ramped to, 3-25..3-27).
struct OutputPulse {
  bool step_direction = false;       // SD: every pulse on PSTP, NDIR is the direction
  bool on_ndir = false;              // SS: this pulse is on NDIR (negative motion)
  bool ndir_level = false;           // NDIR during the pulse
  bool ndir_positive_level = false;  // SD: the NDIR level that means positive motion
  bool pstp_level = false;           // PSTP during the pulse (its pulse sense)
  // The pulse's width in ns (1 us resolution and at most 65.535 ms by appendix A); 0: not
  // given (a step sink that makes its own pulse).
  uint32_t width_ns = 0;
};

// The direction a driver set up for `p`'s mode reads from it (+1 / -1).
constexpr int direction_of(const OutputPulse& p) {
  if (p.step_direction) return p.ndir_level == p.ndir_positive_level ? +1 : -1;
  return p.on_ndir ? -1 : +1;
}

class StepPort {
 public:
  virtual ~StepPort() = default;

  // How far ahead of its time the core gives a step (0: at its time, as it falls due).
  virtual Tick horizon() const { return 0; }
  // A step pulse at `time` (+1 up, -1 down), queued until `time` comes. Steps are given in
  // time order, each later than the one before.
  virtual void queue(Tick time, int direction) = 0;
  // The same given as output signals (the HP channel's PULSE modes): a driver decodes the
  // direction from the outputs, so the motor follows the wiring, not the engine's intent.
  // A back end that makes pulses of a given width (p.width_ns) overrides this.
  virtual void queue_pulse(Tick time, const OutputPulse& p) { queue(time, direction_of(p)); }
  // Every step queued up to `until` goes out (a hardware back end has sent it to the pulse
  // hardware; the simulation moves the motor); the back end's clock is at `until`.
  virtual void flush(Tick until) = 0;
  // The steps queued after `after` will not go out (the motion changed course at `after`).
  virtual void cancel_after(Tick after) = 0;
  // The motor's step count (every step that went out, net, since the back end started) at
  // `time`: a past time within the back end's history, or a future one within the queue.
  // nullopt when `time` is older than the history kept.
  virtual std::optional<int64_t> position_at(Tick time) const = 0;

  // A step whose time has come (horizon 0): queue and flush in one.
  virtual void step(Tick time, int direction) {
    queue(time, direction);
    flush(time);
  }
  virtual void output_pulse(Tick time, const OutputPulse& p) {
    queue_pulse(time, p);
    flush(time);
  }
};

}  // namespace stepnode::motion
