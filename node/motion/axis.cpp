// The Horner front end of one axis (node/motion/axis.hpp): construction, the module model's
// rules, power-up, the status bits and the latching of errors. The commands are in
// axis_commands.cpp, the encoder in axis_encoder.cpp, the steps' rules in axis_motion.cpp.
#include "node/motion/axis.hpp"

namespace stepnode::motion {

Axis::Axis(AxisConfig config, AxisCore& core) : config_(config), core_(core) {
  saved_.resize(core_.motors());
  core_.listen(*this, this);
  set_config(config_);
  power_up(0);
}

Axis::Axis(AxisConfig config, const std::vector<MotorPort*>& motors)
    : config_(config), own_core_(std::make_unique<AxisCore>(motors)), core_(*own_core_) {
  saved_.resize(core_.motors());
  core_.listen(*this, this);
  set_config(config_);
  power_up(0);
}

Axis::Rules Axis::rules_of(const AxisConfig& c) {
  bool encoder = c.encoder != EncoderKind::None;
  if (c.module == AxisConfig::Module::Stp100)
    return Rules{.stall_detection = encoder && c.stall_detection,
                 .invalid_at_tolerance = false,
                 .marker_origin = c.origin_source == AxisConfig::OriginSource::Marker,
                 .limit_qualified = c.limit_qualified_home};
  // SPM30 5.4: "when ENCODER TOL is non-zero, the SPM30 uses the encoder feedback pulses to
  // verify motor velocity". SPM30 4 FIND HOME: with QUAD the marker is axis 1's home input
  // and step 3 stops on the end limit. The STP100 options still apply on top.
  bool quad = c.encoder == EncoderKind::Quadrature;
  return Rules{.stall_detection = encoder && c.encoder_tolerance > 0,
               .invalid_at_tolerance = true,
               .marker_origin = quad || c.origin_source == AxisConfig::OriginSource::Marker,
               .limit_qualified = quad || c.limit_qualified_home};
}

void Axis::set_config(const AxisConfig& config) {
  config_ = config;
  rules_ = rules_of(config_);
  // Another front end's steps matter to the module only for the position check.
  core_.watch_steps(*this, config_.encoder != EncoderKind::None && config_.encoder_tolerance > 0);
  core_.hooks_changed(*this);  // the encoder's rules may look at every step now, or no longer
}

void Axis::power_up(Tick now) {
  if (own_core_) core_.power_up(now);
  job_ = Job::None;
  move_stepping_ = false;
  errors_ = status::kPowerUp;  // SPM30 3.1: every bit off except %I8
  position_valid_ = false;
  resumable_ = false;
  waiting_for_limit_release_ = false;
  encoder_offset_ = 0;
  encoder_offset_ = -encoder_position();  // encoder position 0 at power-up
  for (auto& s : saved_) s = Saved{};
  previous_commands_ = commands_;
  last_status_ = status();
}

bool Axis::origin_active() const {
  // The marker is wired to axis 1's home input (SPM30 4 FIND HOME, 5.1); the other motors
  // of a multiplexed axis keep their home switches.
  bool marker = rules_.marker_origin && core_.selected() == 0;
  return marker ? inputs().marker() : inputs().home();
}

uint16_t Axis::status() const {
  uint16_t s = errors_;
  if (position_valid_) s |= status::kPositionValid;
  if (resumable_) s |= status::kResumable;
  if (core_.selected() == 1) s |= status::kAxis2Selected;
  if (core_.selected() == 2) s |= status::kAxis3Selected;
  if (origin_active()) s |= status::kAtHome;
  switch (core_.generator().phase()) {
    case MotionPhase::Accelerating: s |= status::kAccelerating | status::kMoving; break;
    case MotionPhase::Decelerating: s |= status::kDecelerating | status::kMoving; break;
    case MotionPhase::Running:
    case MotionPhase::Creeping: s |= status::kMoving; break;
    case MotionPhase::Idle: break;
  }
  if (waiting_for_limit_release_) s |= status::kMoving;  // the move is in progress
  return s;
}

void Axis::notify(AxisEvent::Kind kind, uint16_t error_bits) {
  uint16_t s = status();
  if (kind == AxisEvent::StatusChanged && s == last_status_) return;
  last_status_ = s;
  if (on_event) on_event(AxisEvent{kind, s, error_bits});
}

void Axis::latch(uint16_t error_bits, Tick now) {
  // Errors stop motion at once, whichever front end's job runs (the heartbeat loss
  // decelerates: see master_lost).
  const bool was_moving = core_.moving();
  core_.abort(this, now);
  latched(error_bits, was_moving, now);
}

void Axis::emergency_stop(Tick when, bool was_moving) {
  latched(status::kEmergencyStop, was_moving, when);
}

void Axis::end_job(Tick when) {
  move_done_steps_ = move_done_steps();  // the motion's steps, before another motion starts
  move_stepping_ = false;
  // STP100 5.3.5 NOTE: "at the end of an Indexed Move, DIR+ and DIR- are always taken Low
  // and High": DIR is its move-in-progress output, whatever ended the move.
  if (job_ == Job::Move && move_indexed_) core_.set_dir_output(false, when);
  job_ = Job::None;
}

void Axis::latched(uint16_t error_bits, bool was_moving, Tick when) {
  if (was_moving) position_valid_ = false;  // SPM30 3.3.1: a sudden stop invalidates the position
  end_job(when);
  waiting_for_limit_release_ = false;
  resumable_ = false;
  errors_ |= error_bits;
  notify(AxisEvent::Error, error_bits);
}
}  // namespace stepnode::motion
