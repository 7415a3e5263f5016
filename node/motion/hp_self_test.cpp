#include "node/motion/hp_self_test.hpp"

#include "node/motion/hp_position.hpp"
#include "node/motion/hp_profile.hpp"
#include "node/motion/hp_pulse_output.hpp"
#include "node/motion/step_generator.hpp"

namespace stepnode::motion::hp {
namespace {

bool pulse_outputs_decode() {
  // Every PULSE mode and sense, both directions: a driver wired as the mode says reads the
  // direction back, and the pulse is the other level than idle on the output it is on.
  for (PulseMode mode : {PulseMode::StepDirection, PulseMode::StepStep})
    for (bool pstp : {false, true})
      for (bool ndir : {false, true})
        for (int direction : {+1, -1}) {
          const PulseSetup setup{mode, pstp, ndir};
          const Pulse p = pulse_for(setup, direction);
          if (direction_of(setup, p) != direction) return false;
          const bool pulsed =
              p.output == Output::Pstp ? p.pstp_level != p.pstp_idle : p.ndir_level != p.ndir_idle;
          if (!pulsed) return false;
        }
  return true;
}

bool pulse_engine_moves() {
  // A 100-pulse MOVE of the power-on profile (0 to 250 Hz at 500 Hz/s): 100 pulses, in time
  // order, none closer than the period of max (one tick of rounding allowed).
  const Profile power_on;
  StepGenerator g;
  g.start(freq_ramp(power_on, power_on.max), 0, +1, 100);
  const Tick shortest = static_cast<Tick>(kClockHz / power_on.max) - 1;
  Step s;
  Tick last = -1;
  int count = 0;
  while (g.next(s)) {
    if (s.direction != +1 || (last >= 0 && s.time - last < shortest) || s.time <= last)
      return false;
    last = s.time;
    if (++count > 100) return false;
  }
  return count == 100;
}

bool position_counter_rounds() {
  // "PSCALE ROUND-OFF ERROR EXAMPLES" (3-10): at 2 degrees/step a 1 degree move is one step
  // (0.5 rounds up), the counter then reads 2; MOVE 2 ABS from there is no step.
  PositionCounter c;
  c.set_scale(2, 0);
  c.load(0, 0);
  return c.rel_steps(1) == 1 && c.abs_steps(1, 0) == 1 && c.units(1) == 2 && c.abs_steps(2, 1) == 0;
}

bool profile_rules_hold() {
  // The rows of "PROFILE FREQ Setting Conflicts" (3-9), in order, and the power-on profile.
  const Profile rows[] = {{ProfileMode::Freq, 100, 800, 0, 25e-6},
                          {ProfileMode::Freq, 0, 800, 0, 25e-6},
                          {ProfileMode::Freq, 0, 0, 0, 25e-6},
                          {ProfileMode::Freq, 0, 1000, 500, 2e-3},
                          {ProfileMode::Freq, 500, 100, 200, 2e-3}};
  for (int k = 0; k < 5; ++k)
    if (check_profile(rows[k]) != static_cast<Conflict>(k + 1)) return false;
  return check_profile(Profile{}) == Conflict::None;
}

}  // namespace

uint8_t run_self_test() {
  uint8_t failed = 0;
  if (!pulse_outputs_decode()) failed |= self_test_check::kPulseOutputs;
  if (!pulse_engine_moves()) failed |= self_test_check::kPulseEngine;
  if (!position_counter_rounds()) failed |= self_test_check::kPositionCounter;
  if (!profile_rules_hold()) failed |= self_test_check::kProfileRules;
  return failed;
}

}  // namespace stepnode::motion::hp
