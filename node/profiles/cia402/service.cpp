#include "node/profiles/cia402/service.hpp"

#include <algorithm>
#include <cstdlib>

#include "node/profiles/cia402/objects.hpp"

namespace stepnode::node {

using namespace cia402::obj;

namespace {

uint32_t to_u32(int64_t v) { return static_cast<uint32_t>(std::clamp<int64_t>(v, 0, UINT32_MAX)); }
int32_t to_i32(int64_t v) {
  return static_cast<int32_t>(std::clamp<int64_t>(v, INT32_MIN, INT32_MAX));
}

}  // namespace

Cia402Service::Cia402Service(od::Dictionary& dictionary, AxisBank& axes, EmcyProducer& emcy)
    : dictionary_(dictionary), axes_(axes), emcy_(emcy) {
  for (unsigned a = 0; a < axes_.count(); ++a) {
    drives_.push_back(std::make_unique<cia402::Drive>(axes_.core(a)));
    units_.emplace_back();
    reported_.push_back(0);
    install_hooks(a);
  }
}

void Cia402Service::install_hooks(unsigned a) {
  auto entry = [this, a](uint16_t base, uint8_t sub = 0) -> od::Entry& {
    return dictionary_.at(index(a, base), sub);
  };
  od::listen(entry(kControlword), [this, a] {
    load_targets(a);  // a target in the same RPDO is stored before this runs
    // So is a mode: the controlword's bits are read in it (the default RPDO1 maps 6040h
    // before 6060h, whose reaction came after: a start bit was read in the old mode and its
    // edge used up there; found in review).
    const auto mode =
        static_cast<cia402::Mode>(dictionary_.get<int8_t>(index(a, kModesOfOperation), 0));
    if (mode != drives_[a]->mode()) drives_[a]->set_mode(mode, axes_.now());
    drives_[a]->controlword(dictionary_.get<uint16_t>(index(a, kControlword), 0), axes_.now());
    publish(a);
  });
  od::listen(entry(kModesOfOperation), [this, a] {
    drives_[a]->set_mode(
        static_cast<cia402::Mode>(dictionary_.get<int8_t>(index(a, kModesOfOperation), 0)),
        axes_.now());
    publish(a);
  });
  od::listen(entry(kTargetPosition), [this, a] { load_targets(a); });
  // The offsets a master streams with the cyclic set-points (60B0h: CSP, 60B1h: CSV), taken
  // at the next SYNC like the set-points.
  od::listen(entry(kPositionOffset), [this, a] { load_targets(a); });
  od::listen(entry(kVelocityOffset), [this, a] { load_targets(a); });
  od::listen(entry(kInterpolationData, cia402::ip_data_sub::kSetPoint), [this, a] {
    drives_[a]->set_ip_set_point(to_i32(units_[a].to_steps(
        dictionary_.get<int32_t>(index(a, kInterpolationData), cia402::ip_data_sub::kSetPoint))));
  });
  od::listen(entry(kTargetVelocity), [this, a] {
    drives_[a]->set_target_velocity(
        to_i32(units_[a].to_steps(dictionary_.get<int32_t>(index(a, kTargetVelocity), 0))),
        axes_.now());
    publish(a);
  });
  for (uint16_t base : {kMaxProfileVelocity, kProfileVelocity, kProfileAcceleration,
                        kProfileDeceleration, kQuickStopDeceleration, kPositionWindow,
                        kPositionWindowTime, kHomingMethod, kHomingAcceleration, kHomeOffset,
                        kFollowingErrorWindow, kFollowingErrorTimeout, kMotionProfileType})
    od::listen(entry(base), [this, a] { load_parameters(a); });
  for (uint16_t base : {kSoftwarePositionLimit, kPositionEncoderResolution, kGearRatio,
                        kFeedConstant, kHomingSpeeds, kInterpolationPeriod})
    for (uint8_t sub : {uint8_t{1}, uint8_t{2}})
      od::listen(entry(base, sub), [this, a] { load_parameters(a); });
  for (uint8_t sub = 1; sub <= 4; ++sub)
    od::listen(entry(kProfileJerk, sub), [this, a] { load_parameters(a); });
  for (uint16_t base : {kQuickStopOption, kShutdownOption, kDisableOperationOption, kHaltOption,
                        kFaultReactionOption})
    od::listen(entry(base), [this, a] { load_options(a); });
}

void Cia402Service::load_parameters(unsigned a) {
  auto u32 = [&](uint16_t base, uint8_t sub = 0) {
    return dictionary_.get<uint32_t>(index(a, base), sub);
  };
  units_[a] =
      cia402::UserUnits(u32(kPositionEncoderResolution, cia402::encoder_sub::kIncrements),
                        u32(kPositionEncoderResolution, cia402::encoder_sub::kMotorRevolutions),
                        u32(kGearRatio, cia402::gear_sub::kMotorRevolutions),
                        u32(kGearRatio, cia402::gear_sub::kShaftRevolutions),
                        u32(kFeedConstant, cia402::feed_sub::kFeed),
                        u32(kFeedConstant, cia402::feed_sub::kShaftRevolutions));
  const cia402::UserUnits& un = units_[a];
  cia402::Parameters& p = drives_[a]->parameters();
  p.max_velocity = to_u32(un.to_steps(u32(kMaxProfileVelocity)));
  p.profile_velocity = to_u32(un.to_steps(u32(kProfileVelocity)));
  p.acceleration = to_u32(un.to_steps(u32(kProfileAcceleration)));
  p.deceleration = to_u32(un.to_steps(u32(kProfileDeceleration)));
  p.quick_stop_deceleration = to_u32(un.to_steps(u32(kQuickStopDeceleration)));
  p.motion_profile_type = dictionary_.get<int16_t>(index(a, kMotionProfileType), 0);
  for (uint8_t sub = 1; sub <= 4; ++sub)
    p.jerk[sub - 1] = to_u32(un.to_steps(u32(kProfileJerk, sub)));
  p.position_window = to_u32(un.to_steps(u32(kPositionWindow)));
  p.position_window_time_ms = dictionary_.get<uint16_t>(index(a, kPositionWindowTime), 0);
  const int32_t low =
      dictionary_.get<int32_t>(index(a, kSoftwarePositionLimit), cia402::limit_sub::kMin);
  const int32_t high =
      dictionary_.get<int32_t>(index(a, kSoftwarePositionLimit), cia402::limit_sub::kMax);
  p.min_position_limit = to_i32(un.to_steps(low));
  p.max_position_limit = to_i32(un.to_steps(high));
  p.homing_method = dictionary_.get<int8_t>(index(a, kHomingMethod), 0);
  p.homing_switch_speed =
      to_u32(un.to_steps(u32(kHomingSpeeds, cia402::homing_speed_sub::kSwitchSearch)));
  p.homing_zero_speed =
      to_u32(un.to_steps(u32(kHomingSpeeds, cia402::homing_speed_sub::kZeroSearch)));
  p.homing_acceleration = to_u32(un.to_steps(u32(kHomingAcceleration)));
  p.home_offset = to_i32(un.to_steps(dictionary_.get<int32_t>(index(a, kHomeOffset), 0)));
  const uint32_t fe_window = u32(kFollowingErrorWindow);
  p.following_error_window = fe_window == UINT32_MAX ? UINT32_MAX : to_u32(un.to_steps(fe_window));
  p.following_error_timeout_ms = dictionary_.get<uint16_t>(index(a, kFollowingErrorTimeout), 0);
  // 60C2h: units * 10^index s.
  double period =
      dictionary_.get<uint8_t>(index(a, kInterpolationPeriod), cia402::ip_period_sub::kUnits);
  for (int8_t i =
           dictionary_.get<int8_t>(index(a, kInterpolationPeriod), cia402::ip_period_sub::kIndex);
       i < 0; ++i)
    period /= 10;
  for (int8_t i =
           dictionary_.get<int8_t>(index(a, kInterpolationPeriod), cia402::ip_period_sub::kIndex);
       i > 0; --i)
    period *= 10;
  p.interpolation_period = std::clamp<motion::Tick>(
      static_cast<motion::Tick>(period * motion::kClockHz), 1, motion::kClockHz);
}

void Cia402Service::load_options(unsigned a) {
  auto i16 = [&](uint16_t base) { return dictionary_.get<int16_t>(index(a, base), 0); };
  cia402::Options o;
  o.quick_stop = i16(kQuickStopOption);
  o.shutdown = i16(kShutdownOption);
  o.disable_operation = i16(kDisableOperationOption);
  o.halt = i16(kHaltOption);
  o.fault_reaction = i16(kFaultReactionOption);
  drives_[a]->set_options(o);
}

void Cia402Service::load_targets(unsigned a) {
  const auto steps = [&](uint16_t base) {
    return to_i32(units_[a].to_steps(dictionary_.get<int32_t>(index(a, base), 0)));
  };
  drives_[a]->set_target_position(steps(kTargetPosition));
  drives_[a]->set_position_offset(steps(kPositionOffset));
  drives_[a]->set_velocity_offset(steps(kVelocityOffset));
}

void Cia402Service::configure(uint64_t) {
  for (unsigned a = 0; a < drives_.size(); ++a) {
    load_parameters(a);
    load_options(a);
  }
}

void Cia402Service::power_up(uint64_t) {
  for (unsigned a = 0; a < drives_.size(); ++a) {
    drives_[a]->power_up(axes_.now(), static_cast<cia402::Mode>(
                                          dictionary_.get<int8_t>(index(a, kModesOfOperation), 0)));
    // Commands and targets are not stored: the master writes them after every start.
    dictionary_.put<uint16_t>(index(a, kControlword), 0, 0);
    if (reported_[a]) emcy_.clear(reported_[a], axes_.now_us(), emcy_source::kAxis + a);
    reported_[a] = 0;
    publish(a);
  }
}

void Cia402Service::master_lost(uint64_t) {
  for (unsigned a = 0; a < drives_.size(); ++a) {
    drives_[a]->connection_lost(dictionary_.get<int16_t>(index(a, kAbortConnectionOption), 0),
                                axes_.now());
    publish(a);
  }
}

void Cia402Service::sync(uint64_t now_us, uint64_t frame_us) {
  for (auto& d : drives_) d->sync(axes_.ticks(now_us), axes_.ticks(frame_us));
}

void Cia402Service::master_back(uint64_t) {
  for (auto& d : drives_) d->connection_restored();
}

uint64_t Cia402Service::next_advance_us(uint64_t now_us) {
  // The motion's steps and its end (a quick stop's ramp, a fault reaction's) are the axes'
  // deadlines (AxisBank); the drive adds its timers (6066h, 6068h) and the tick at which a
  // CSP/IP segment's following error leaves its window (6065h).
  uint64_t next = kNoDeadline;
  for (const auto& d : drives_) {
    if (const std::optional<motion::Tick> at = d->next_event(axes_.now()))
      next = earliest(next, std::max(axes_.micros_at_or_after(*at), now_us + 1));
  }
  return next;
}

void Cia402Service::publish() {
  for (unsigned a = 0; a < drives_.size(); ++a) publish(a);
}

void Cia402Service::publish(unsigned a) {
  const cia402::Drive& d = *drives_[a];
  const cia402::UserUnits& un = units_[a];
  dictionary_.put<uint16_t>(index(a, kStatusword), 0, d.statusword());
  dictionary_.put<int8_t>(index(a, kModesOfOperationDisplay), 0,
                          static_cast<int8_t>(d.mode_display()));
  dictionary_.put<int32_t>(index(a, kPositionDemand), 0, to_i32(un.to_units(d.position_demand())));
  dictionary_.put<int32_t>(index(a, kPositionActualInternal), 0, d.position_actual());
  dictionary_.put<int32_t>(index(a, kPositionActual), 0, to_i32(un.to_units(d.position_actual())));
  dictionary_.put<int32_t>(index(a, kVelocityActual), 0, to_i32(un.to_units(d.velocity_actual())));
  dictionary_.put<int32_t>(index(a, kFollowingErrorActual), 0,
                           to_i32(un.to_units(d.following_error())));
  dictionary_.put<uint32_t>(index(a, kDigitalInputs), 0, d.digital_inputs());
  dictionary_.put<uint16_t>(index(a, kErrorCode), 0, d.error_code());
  report_fault(a);
}

void Cia402Service::report_fault(unsigned a) {
  // A fault is an EMCY with its 603Fh code (error register: device profile specific); the
  // fault reset clears it.
  const bool fault = drives_[a]->state() == cia402::State::Fault ||
                     drives_[a]->state() == cia402::State::FaultReactionActive;
  const uint16_t code = fault ? drives_[a]->error_code() : 0;
  if (code == reported_[a]) return;
  if (reported_[a]) emcy_.clear(reported_[a], axes_.now_us(), emcy_source::kAxis + a);
  reported_[a] = code;
  if (code)
    emcy_.raise(code, error_bits::kGeneric | error_bits::kProfile,
                {static_cast<uint8_t>(a + 1), 0, 0, 0, 0}, axes_.now_us(), emcy_source::kAxis + a);
}

}  // namespace stepnode::node
