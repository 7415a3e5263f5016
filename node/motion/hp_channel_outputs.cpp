// hp::Channel: what its outputs carry: each pulse's output, levels and width (PULSE 3-7,
// PROFILE pwidth 3-8, the WIDTH-mode width ramp 3-25..3-27).
#include "node/motion/hp_channel.hpp"

#include <algorithm>
#include <cmath>

namespace stepnode::motion::hp {
namespace {

Tick seconds_to_ticks(double s) {
  return static_cast<Tick>(std::llround(s * static_cast<double>(kClockHz)));
}

}  // namespace

OutputPulse Channel::pulse(const Step& s) const {
  // PULSE SD|SS: the output the pulse appears at and the levels (3-7, Figure 3-1).
  const Pulse p = pulse_for(pulse_, s.direction);
  OutputPulse out;
  out.step_direction = pulse_.mode == PulseMode::StepDirection;
  out.on_ndir = p.output == Output::Ndir;
  out.ndir_level = p.ndir_level;
  out.ndir_positive_level = pulse_.ndir_high;
  out.pstp_level = p.pstp_level;
  // How long it lasts: the PROFILE's pwidth (FREQ) or the width ramped to by this step's
  // time (WIDTH). Asked ahead of time too: a new SUSTAIN width re-plans the queued pulses.
  out.width_ns = width_ns_at(s.time);
  return out;
}

uint32_t Channel::width_ns_at(Tick t) const {
  if (run_ == Run::Idle) return 0;
  const double seconds = profile_.mode == ProfileMode::Freq ? profile_.last : current_width_at(t);
  // Appendix A: "Pulse Width ... Resolution 1 usec".
  return static_cast<uint32_t>(std::llround(seconds * 1e6)) * 1000u;
}

void Channel::pulse_sent(const Step& s) {
  last_pulse_ = pulse_for(pulse_, s.direction);
  ++pulse_count_[static_cast<unsigned>(last_pulse_.output)];
}

double Channel::current_width_at(Tick t) const {
  if (profile_.mode != ProfileMode::Width || run_ == Run::Idle) return 0;
  double elapsed = static_cast<double>(t - width_since_) / static_cast<double>(kClockHz);
  double change = profile_.slope * elapsed;
  if (width_target_ >= width_from_) return std::min(width_target_, width_from_ + change);
  return std::max(width_target_, width_from_ - change);
}

double Channel::current_width() const { return width_ns_at(core_.generator().time()) * 1e-9; }

void Channel::replan_widths(Tick at) {
  // The width is a function of time the queued pulses were given: from `at` it changes, so
  // the pulses queued after `at` are planned again (the same steps on the same grid).
  if (core_.owned_by(*this) && core_.moving()) core_.regrid(at, core_.generator().ramp());
}

std::optional<Tick> Channel::width_reach() const {
  if (profile_.mode != ProfileMode::Width || (run_ != Run::Sustain && run_ != Run::SustainStopping))
    return std::nullopt;
  if (run_ == Run::Sustain && sustain_reached_) return std::nullopt;
  // The exact tick the width reaches its target.
  double span = std::fabs(width_target_ - width_from_);
  return width_since_ + (profile_.slope > 0 ? seconds_to_ticks(span / profile_.slope) : 0);
}

void Channel::width_advance(Tick now) {
  const std::optional<Tick> at = width_reach();
  if (!at || *at > now) return;
  const Tick reach = *at;
  core_.advance_to(reach);
  if (run_ == Run::SustainStopping) {
    core_.halt(*this, reach);
    return end(Done::Completed, intr::kMoveDone, reach);
  }
  sustain_reached_ = true;
  blocking_ = false;
  interrupt(intr::kSustainReached, reach);
}

}  // namespace stepnode::motion::hp
