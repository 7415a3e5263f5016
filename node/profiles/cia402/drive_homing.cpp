// Homing mode carried out on the motion core: the searches of the method (homing.hpp)
// one after the other, each ended by its input event, and the homing status.
#include <algorithm>
#include <cstddef>

#include "node/profiles/cia402/drive.hpp"

namespace stepnode::cia402 {

using motion::Tick;

HomingInputs Drive::homing_inputs() const {
  const motion::InputLevels& m = core_.inputs();
  return HomingInputs{m.lower_limit(), m.upper_limit(), m.home(), m.marker()};
}

void Drive::start_homing(Tick now) {
  if (core_.busy()) return;  // another front end's job, or still stopping
  auto plan = homing_plan(parameters_.homing_method, core_.inputs().home());
  if (!plan) {
    homing_ = Homing::Error;  // 6098h names no method this drive performs
    return;
  }
  // A hard stop is found with the encoder and the following error window (6065h): without
  // either the method cannot be performed here.
  const bool needs_block = std::any_of(plan->begin(), plan->end(), [](const HomingSearch& s) {
    return s.until == HomingEvent::Block;
  });
  if (needs_block &&
      (!core_.motor().has_encoder() || parameters_.following_error_window == UINT32_MAX)) {
    homing_ = Homing::Error;
    return;
  }
  searches_ = std::move(*plan);
  search_ = 0;
  search_stopping_ = false;
  homing_ = Homing::InProgress;
  if (searches_.empty()) return homing_done(true, now);  // 35, 37: here
  run_search(now);
}

void Drive::run_search(Tick now) {
  if (search_ >= searches_.size()) return homing_done(false, now);
  const HomingSearch& s = searches_[search_];
  const uint32_t speed = s.fast ? parameters_.homing_switch_speed : parameters_.homing_zero_speed;
  const int64_t v = std::clamp<int64_t>(speed, 1, std::max<uint32_t>(parameters_.max_velocity, 1));
  const int64_t acc = std::max<uint32_t>(parameters_.homing_acceleration, 1);
  grid_ = motion::profile_levels_per_hz(acc);
  last_inputs_ = homing_inputs();
  block_count_ = core_.motor().encoder_count();
  block_steps_ = 0;
  block_since_.reset();
  if (!core_.start(*this, motion::profile_ramp(v, acc, acc, grid_), s.direction, std::nullopt, now))
    homing_ = Homing::Idle;
}

void Drive::homing_step(const motion::Step& step) {
  const HomingInputs in = homing_inputs();
  const HomingInputs before = last_inputs_;
  last_inputs_ = in;
  if (search_stopping_) return;  // ramping down after an edge: the next search looks again
  const HomingSearch& s = searches_[search_];
  const bool block = s.until == HomingEvent::Block;
  if (block ? block_detected(step) : happened(s.until, before, in)) {
    switch (s.then) {
      case HomingSearch::Then::Stop:
        search_stopping_ = true;
        // Against a hard stop there is nothing to ramp down: the motion ends on this step.
        return block ? core_.halt_motion(step.time) : core_.stop(step.time);
      case HomingSearch::Then::Continue: ++search_; return;
      case HomingSearch::Then::Home:
        core_.halt(*this, step.time);
        return homing_done(true, step.time);
    }
  }
  // A limit switch the search does not look for: a search that may lead away from the
  // home switch turns back there once (the same search the other way, after the ramp);
  // otherwise the method cannot be performed here.
  const bool limit = step.direction < 0 ? in.negative_limit : in.positive_limit;
  const bool wanted =
      s.until == (step.direction < 0 ? HomingEvent::NegativeLimitOn : HomingEvent::PositiveLimitOn);
  if (limit && !wanted && s.reverse_at_limit) {
    HomingSearch back = s;
    back.direction = -s.direction;
    back.reverse_at_limit = false;
    searches_.insert(searches_.begin() + static_cast<std::ptrdiff_t>(search_) + 1, back);
    search_stopping_ = true;
    return core_.stop(step.time);
  }
  if (limit && !wanted) {
    core_.halt(*this, step.time);
    homing_done(false, step.time);
  }
}

// The load stopped following the steps: the encoder has not counted in the direction of
// travel for more than the following error window (6065h, in steps: it must exceed the
// steps per encoder count), and that has lasted the following error time-out (6066h). A
// stepper blocked by a hard stop loses these steps; its rotor stays at the block.
bool Drive::block_detected(const motion::Step& step) {
  const int64_t count = core_.motor().encoder_count();
  if ((count - block_count_) * step.direction > 0) {
    block_count_ = count;
    block_steps_ = 0;
    block_since_.reset();
    return false;
  }
  if (++block_steps_ <= parameters_.following_error_window) return false;
  if (!block_since_) block_since_ = step.time;
  const Tick timeout = Tick{parameters_.following_error_timeout_ms} * motion::kClockHz / 1000;
  return step.time - *block_since_ >= timeout;
}

void Drive::homing_done(bool ok, Tick now) {
  (void)now;
  homing_ = ok ? Homing::Attained : Homing::Error;
  // The home position is the home offset (607Ch): position actual reads it there.
  if (ok) core_.set_position(parameters_.home_offset);
}

}  // namespace stepnode::cia402
