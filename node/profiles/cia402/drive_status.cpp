// What the master reads of the drive: the statusword (6041h) with the bits of the mode
// displayed, velocity actual (606Ch) and the digital inputs (60FDh).
#include <cmath>
#include <cstdlib>

#include "node/profiles/cia402/drive.hpp"

namespace stepnode::cia402 {

int32_t Drive::velocity_actual() const {
  const motion::StepGenerator& g = core_.generator();
  return static_cast<int32_t>(std::lround(g.velocity() * g.direction()));
}

uint32_t Drive::digital_inputs() const {
  const motion::InputLevels& m = core_.inputs();
  return (m.lower_limit() ? 1u : 0u) | (m.upper_limit() ? 2u : 0u) | (m.home() ? 4u : 0u);
}

uint16_t Drive::statusword() const {
  uint16_t s = machine_.statusword();
  if (internal_limit_) s |= sw::kInternalLimitActive;
  switch (mode_display_) {
    case Mode::ProfilePosition:
      if (target_reached_) s |= sw::kTargetReached;
      if (acknowledged_ || (active_ && next_)) s |= sw_mode::kSetPointAcknowledge;
      break;
    case Mode::ProfileVelocity: {
      const motion::StepGenerator& g = core_.generator();
      const bool moving = core_.moving();
      const int64_t want = std::llabs(int64_t{target_velocity_});
      // Velocity reached: running at the target (its level), or stopped for a 0 target.
      // Quick stop active (605Ah 5..8): reached once the quick stop has stopped the axis
      // (6041h bit 10; it showed 0 there: found in review).
      const bool reached =
          halted_ || machine_.state() == State::QuickStopActive
              ? !moving
              : (want == 0 ? !moving
                           : moving && core_.owned_by(*this) && g.level() == want * grid_ &&
                                 g.phase() != motion::MotionPhase::Accelerating &&
                                 g.phase() != motion::MotionPhase::Decelerating);
      if (reached) s |= sw::kTargetReached;
      if (!moving) s |= sw_mode::kSpeedZero;
      break;
    }
    case Mode::Homing:
      // CiA 402-2 homing status: 13/12/10 = 0/0/1 not started or interrupted, 0/0/0 in
      // progress, 0/1/1 completed, 1/0/x error (bit 10: the velocity is 0).
      switch (homing_) {
        case Homing::Idle: s |= core_.owned_by(*this) ? 0 : sw::kTargetReached; break;
        case Homing::InProgress: break;
        case Homing::Attained: s |= sw_mode::kHomingAttained | sw::kTargetReached; break;
        case Homing::Error:
          s |= sw_mode::kHomingError | (core_.moving() ? 0 : sw::kTargetReached);
          break;
      }
      break;
    case Mode::CyclicSyncPosition:
    case Mode::CyclicSyncVelocity: {
      // Bit 12: the drive follows the command value (enabled, not halted, no other front
      // end's job); bit 13 (CSP): following error.
      const bool follows =
          machine_.operation_enabled() && !halted_ && (!core_.busy() || core_.owned_by(*this));
      if (follows) s |= sw_mode::kDriveFollows;
      if (following_error_ && mode_display_ == Mode::CyclicSyncPosition)
        s |= sw_mode::kFollowingError;
      break;
    }
    case Mode::InterpolatedPosition:
      if (machine_.operation_enabled() && (controlword_ & kEnableIp)) s |= sw_mode::kIpModeActive;
      if (!core_.owned_by(*this) && core_.position() == seg_to_) s |= sw::kTargetReached;
      if (following_error_) s |= sw_mode::kFollowingError;
      break;
    default: break;
  }
  return s;
}

}  // namespace stepnode::cia402
