// The Horner front end's encoder (SPM30 chapter 5, STP100 6.2-6.3): the encoder position
// as the module decodes and scales it, position validation (%I9) and stall detection (%I5).
#include <algorithm>
#include <cstdlib>

#include "node/motion/axis.hpp"

namespace stepnode::motion {
namespace {

int64_t floor_div(int64_t a, int64_t b) {
  int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

}  // namespace

int64_t Axis::encoder_counts() const {
  int64_t counts = core_.motor(0).encoder_count();
  if (config_.encoder == EncoderKind::UpDown) return counts;
  // A quadrature port counts every edge of A and B (4 per line); the module counts lines,
  // or 2 / 4 per line when its decoding doubles or quadruples the resolution.
  return floor_div(counts * std::clamp<int64_t>(config_.quadrature_decoding, 1, 4), 4);
}

int32_t Axis::encoder_position() const {
  // The encoder belongs to the first motor (SPM30 3.3.2: axis 1's, whatever is selected).
  if (config_.encoder == EncoderKind::None)
    return core_.selected() == 0 ? core_.position() : saved_[0].position;
  int64_t steps = floor_div(encoder_counts() * config_.encoder_multiplier,
                            std::max<int64_t>(config_.encoder_divisor, 1));
  return static_cast<int32_t>(encoder_offset_ + steps);
}

bool Axis::encoder_rules_every_step() const {
  if (core_.selected() != 0) return false;
  return rules_.stall_detection ||
         (config_.encoder != EncoderKind::None && config_.encoder_tolerance > 0);
}

void Axis::check_position_valid() {
  if (config_.encoder == EncoderKind::None || config_.encoder_tolerance <= 0 ||
      core_.selected() != 0)
    return;
  int64_t difference = std::llabs(int64_t{core_.position()} - encoder_position());
  // SPM30 5.4: "reaches encoder tolerance"; STP100 6.3.2: "exceeds the configured Encoder
  // Tolerance value".
  if (rules_.invalid_at_tolerance ? difference >= config_.encoder_tolerance
                                  : difference > config_.encoder_tolerance)
    position_valid_ = false;
}

void Axis::restart_stall_windows(int direction) {
  int64_t counts = config_.encoder == EncoderKind::None ? 0 : encoder_counts();
  stall_short_ = stall_long_ = StallWindow{0, counts};
  stall_direction_ = direction;
}

bool Axis::stall_judged(const StallWindow& window, int64_t counts) const {
  int64_t mlt = config_.encoder_multiplier, div = std::max<int64_t>(config_.encoder_divisor, 1);
  int64_t measured = std::llabs(counts - window.counts_start);
  // STP100 6.3.3: a stall when the measured velocity is less than 10 % of the theoretical
  // one, here over the same commanded steps: measured counts < 10 % of steps * DIV / MLT.
  // The count difference of a moving encoder is at most one count short of its true
  // motion, so the test is on measured + 1: a motor at 10 % or more is never a stall, and a
  // window of 10 expected counts or fewer (10 % under that one count) never is one either.
  return (measured + 1) * 10 * mlt < window.steps * div;
}

bool Axis::stalled_over(StallWindow& window, int64_t counts_per_window) {
  // The window spans the commanded steps worth `counts_per_window` encoder counts.
  int64_t mlt = config_.encoder_multiplier, div = std::max<int64_t>(config_.encoder_divisor, 1);
  if (++window.steps * div < counts_per_window * mlt) return false;
  int64_t counts = encoder_counts();
  bool stalled = stall_judged(window, counts);
  window = StallWindow{0, counts};
  return stalled;
}

bool Axis::stalled_at_motion_end() {
  if (!rules_.stall_detection || core_.selected() != 0) return false;
  // STP100 3.2.3 checks for encoder pulses "after a move is requested", whatever its length:
  // the partly filled windows of a motion that ended are judged as the full ones are, or a
  // move (jog, FIND HOME run) shorter than a window would never be checked.
  int64_t counts = encoder_counts();
  bool stalled = stall_judged(stall_short_, counts) || stall_judged(stall_long_, counts);
  restart_stall_windows(stall_direction_);
  return stalled;
}

void Axis::check_stall(const Step& step) {
  if (!rules_.stall_detection || core_.selected() != 0) return;
  // A reversal (FIND HOME's runs at base velocity) begins new windows: net motion across
  // it says nothing about velocity.
  if (step.direction != stall_direction_) restart_stall_windows(step.direction);
  // 20 counts: a jammed encoder (no count at all) is caught within them; 1000 counts: a
  // slipping motor is judged to within 0.1 % of the threshold.
  bool stalled = stalled_over(stall_short_, 20);
  stalled = stalled_over(stall_long_, 1000) || stalled;
  if (stalled) latch(status::kMotorStalled, step.time);
}
}  // namespace stepnode::motion
