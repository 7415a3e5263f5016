#include "tools/stepcalc/engine_profile.hpp"

#include <algorithm>

namespace stepnode::tools {
namespace {

using motion::Tick;
using motion::ticks_to_ms;

// Length of ramp interval k (0-based): the generator's Bresenham over a rational Z (an
// integer Z for Horner ramps), so interval k ends floor((k+1) Z) ticks after the ramp began;
// at least one tick.
Tick interval_length(motion::Rational z, int64_t k) {
  return std::max<Tick>((k + 1) * z.num / z.den - k * z.num / z.den, 1);
}

// Pulses/s gained per second when the level rises by one every z ticks.
double rate_of(const motion::RampSpec& ramp, motion::Rational z) {
  return ramp.velocity_of(1) * static_cast<double>(motion::kClockHz) * static_cast<double>(z.den) /
         static_cast<double>(z.num);
}

}  // namespace

Curve engine_staircase(const motion::RampSpec& ramp, const motion::StepGenerator::Marks& m) {
  Curve c;
  auto flat = [&](Tick t0, Tick t1, int64_t level) {
    if (t1 <= t0) return;
    double v = ramp.velocity_of(level);
    if (c.empty()) c.emplace_back(ticks_to_ms(t0), 0.0);
    c.emplace_back(ticks_to_ms(t0), v);
    c.emplace_back(ticks_to_ms(t1), v);
  };
  const Tick end = m.end;
  const Tick accel_end = m.run_start >= 0 ? m.run_start : m.decel_start >= 0 ? m.decel_start : end;
  // Acceleration: base+1 .. peak, Z_A ticks each (the last one cut where the phase ends).
  Tick t = m.start, t1 = m.start;
  int64_t level = ramp.base_level + 1;
  for (int64_t k = 0; t < accel_end && level <= m.peak_level; ++k, ++level) {
    t1 += interval_length(ramp.accel_ticks_per_level, k);
    flat(t, std::min(t1, accel_end), level);
    t = std::min(t1, accel_end);
  }
  // Running at the peak until the deceleration begins.
  if (m.run_start >= 0) {
    const Tick run_end = m.decel_start >= 0 ? m.decel_start : end;
    flat(m.run_start, run_end, m.peak_level);
    t = run_end;
  }
  // Deceleration: peak .. base+1, Z_D ticks each, until the move ends.
  if (m.decel_start >= 0) {
    t = t1 = m.decel_start;
    level = m.peak_level;
    for (int64_t k = 0; t < end && level > ramp.base_level; ++k, --level) {
      t1 += interval_length(ramp.decel_ticks_per_level, k);
      flat(t, std::min(t1, end), level);
      t = std::min(t1, end);
    }
  }
  // Whatever the ramps leave: steps at the base velocity (at least one level).
  flat(t, end, std::max<int64_t>(ramp.base_level, 1));
  if (!c.empty()) c.emplace_back(c.back().first, 0.0);
  return c;
}

EngineProfile run_engine(const motion::StpcalcInput& in, bool stpcalc_peak) {
  motion::RampSpec ramp = motion::horner_ramp(in.aq3, in.aq4, in.aq5, in.aq6, in.aq7);
  if (stpcalc_peak) ramp.short_move = motion::RampSpec::ShortMove::StpcalcPeak;
  motion::StepGenerator g;
  g.start(ramp, 0, +1, in.total ? std::optional<int64_t>(*in.total) : std::nullopt);
  EngineProfile p;
  motion::Step step;
  while (g.next(step)) {
    ++p.steps;
    if (!in.total && g.phase() == motion::MotionPhase::Running) g.stop(step.time);
  }
  const auto& m = g.marks();
  p.marks = m;
  p.staircase = engine_staircase(ramp, m);

  ProfileValues& e = p.values;
  e.acceleration_rate = rate_of(ramp, ramp.accel_ticks_per_level);
  e.deceleration_rate = rate_of(ramp, ramp.decel_ticks_per_level);
  e.velocity_resolution = ramp.velocity_of(1);
  e.base_velocity = ramp.velocity_of(ramp.base_level);
  e.running_velocity = ramp.velocity_of(ramp.run_level);
  e.peak_velocity = ramp.velocity_of(m.peak_level);
  e.acceleration_pulses = static_cast<double>(m.accel_steps);
  e.deceleration_pulses = static_cast<double>(m.decel_steps + m.creep_steps);
  const Tick accel_end = m.run_start >= 0     ? m.run_start
                         : m.decel_start >= 0 ? m.decel_start
                                              : m.end;
  e.acceleration_time_ms = ticks_to_ms(accel_end - m.start);
  e.deceleration_time_ms = m.decel_start >= 0 ? ticks_to_ms(m.end - m.decel_start) : 0.0;
  if (in.total) {
    e.running_pulses = static_cast<double>(m.run_steps);
    e.running_time_ms =
        m.run_start >= 0 ? ticks_to_ms((m.decel_start >= 0 ? m.decel_start : m.end) - m.run_start)
                         : 0.0;
    e.total_time_ms = ticks_to_ms(m.end - m.start);
  } else {
    e.total_time_ms = e.acceleration_time_ms + e.deceleration_time_ms;  // B1.3.14
  }
  return p;
}

}  // namespace stepnode::tools
