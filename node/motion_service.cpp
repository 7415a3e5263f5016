#include "node/motion_service.hpp"

#include <cmath>

#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"

namespace stepnode::node {

using namespace horner::obj;
namespace sim_obj = sim::obj;

MotionService::MotionService(od::Dictionary& dictionary, const DeviceLayout& layout, EmcyProducer& emcy)
    : dictionary_(dictionary), emcy_(emcy), count_(layout.axes), motors_(layout.motors()) {
  machine_.axes.resize(motors_);
  for (unsigned a = 0; a < count_; ++a) {
    std::vector<motion::MotorPort*> motors{&machine_.axes[a]};
    if (layout.spm30_multiplexed) motors = {&machine_.axes[0], &machine_.axes[1], &machine_.axes[2]};
    axes_.push_back(std::make_unique<motion::Axis>(motion::AxisConfig{}, motors, &machine_.emergency_stop));
    axes_.back()->on_event = [this, a](const motion::AxisEvent& e) { on_axis_event(a, e); };
  }
  install_hooks();
  for (unsigned a = 0; a < count_; ++a) refused_words_.push_back(std::make_unique<RefusedWords>(dictionary_, a));
}

motion::Tick MotionService::ticks(uint64_t now_us) const {
  // 4.9152 ticks per microsecond = 3072/625, exact in integers.
  uint64_t since = now_us >= epoch_us_ ? now_us - epoch_us_ : 0;
  return static_cast<motion::Tick>(since / 625 * 3072 + since % 625 * 3072 / 625);
}

void MotionService::load_words(unsigned a) {
  motion::CommandWords& w = axes_[a]->words();
  w.destination = dictionary_.get<int32_t>(index(a, kDestination), 0);
  uint16_t p = index(a, kProfile), ix = index(a, kIndexedMove);
  w.velocity_divisor = dictionary_.get<uint16_t>(p, horner::profile_sub::kVelocityDivisor);
  w.base_velocity = dictionary_.get<uint16_t>(p, horner::profile_sub::kBaseVelocity);
  w.running_velocity = dictionary_.get<uint16_t>(p, horner::profile_sub::kRunningVelocity);
  w.acceleration_ms = dictionary_.get<uint16_t>(p, horner::profile_sub::kAcceleration);
  w.deceleration_ms = dictionary_.get<uint16_t>(p, horner::profile_sub::kDeceleration);
  w.index_destination = dictionary_.get<uint32_t>(ix, horner::indexed_sub::kDestination);
  w.index_deceleration_ms = dictionary_.get<uint16_t>(ix, horner::indexed_sub::kDeceleration);
  w.index_window_open = dictionary_.get<uint32_t>(ix, horner::indexed_sub::kWindowOpen);
  w.index_window_close = dictionary_.get<uint32_t>(ix, horner::indexed_sub::kWindowClose);
  refused_words_[a]->overlay(w);
}

void MotionService::load_config(unsigned a) {
  uint16_t c = index(a, kConfiguration);
  auto u8 = [&](uint8_t sub) { return dictionary_.get<uint8_t>(c, sub); };
  motion::AxisConfig cfg = axes_[a]->config();
  cfg.encoder = static_cast<motion::EncoderKind>(u8(horner::config_sub::kEncoderType));
  cfg.encoder_multiplier = u8(horner::config_sub::kMultiplier);
  cfg.encoder_divisor = u8(horner::config_sub::kDivisor);
  cfg.encoder_tolerance = u8(horner::config_sub::kTolerance);
  cfg.stall_detection = u8(horner::config_sub::kStallDetection) != 0;
  cfg.home_method = u8(horner::config_sub::kHomeMethod) ? motion::AxisConfig::HomeMethod::Simple
                                                    : motion::AxisConfig::HomeMethod::Normal;
  cfg.origin_source = u8(horner::config_sub::kOriginSource) ? motion::AxisConfig::OriginSource::Marker
                                                        : motion::AxisConfig::OriginSource::HomeSwitch;
  cfg.limit_qualified_home = u8(horner::config_sub::kLimitQualified) != 0;
  cfg.limit_started_moves = u8(horner::config_sub::kLimitStartedMoves) != 0;
  cfg.indexed_moves = u8(horner::config_sub::kIndexedMoves) != 0;
  axes_[a]->set_config(cfg);
  machine_.axes[a].config().encoder = cfg.encoder;  // the encoder is on the axis' first motor
}

void MotionService::load_machine(unsigned a) {  // a: the motor
  uint16_t sw = sim_obj::index(a, sim_obj::kSwitches), enc = sim_obj::index(a, sim_obj::kEncoder),
           f = sim_obj::index(a, sim_obj::kFaults);
  auto i32 = [&](uint16_t i, uint8_t s) { return int64_t{dictionary_.get<int32_t>(i, s)}; };
  auto on = [&](uint16_t i, uint8_t s) { return dictionary_.get<uint8_t>(i, s) != 0; };
  sim::AxisMachineConfig& m = machine_.axes[a].config();
  using namespace sim;
  int64_t home_width = i32(sw, switches_sub::kHomeWidth);
  m.home = home_width > 0 ? std::optional<sim::Cam>(sim::Cam{i32(sw, switches_sub::kHomePosition), home_width})
                          : std::nullopt;
  int64_t index_width = i32(sw, switches_sub::kIndexWidth);
  m.index = index_width > 0 ? std::optional<sim::Cam>(sim::Cam{i32(sw, switches_sub::kIndexPosition), index_width})
                            : std::nullopt;
  m.lower_limit = on(sw, switches_sub::kLowerLimitEnabled) ? std::optional<int64_t>(i32(sw, switches_sub::kLowerLimit))
                                                          : std::nullopt;
  m.upper_limit = on(sw, switches_sub::kUpperLimitEnabled) ? std::optional<int64_t>(i32(sw, switches_sub::kUpperLimit))
                                                          : std::nullopt;
  m.steps_per_rev = i32(enc, encoder_sub::kStepsPerRev);
  m.encoder_lines = i32(enc, encoder_sub::kLines);
  m.marker_offset = i32(enc, encoder_sub::kMarkerOffset);
  m.marker_width = i32(enc, encoder_sub::kMarkerWidth);
  m.stall_below = on(f, faults_sub::kStallBelowEnabled) ? std::optional<int64_t>(i32(f, faults_sub::kStallBelow))
                                                        : std::nullopt;
  m.stall_above = on(f, faults_sub::kStallAboveEnabled) ? std::optional<int64_t>(i32(f, faults_sub::kStallAbove))
                                                        : std::nullopt;
  m.miss_every = dictionary_.get<uint32_t>(f, faults_sub::kMissEvery);
}

void MotionService::install_hooks() {
  for (unsigned a = 0; a < count_; ++a) {
    // A command acts at once, with the words as they are now (SPM30 3.4: words may change
    // for the next move as soon as a command was taken).
    dictionary_.at(index(a, kCommandBits), 0).on_written = [this, a] {
      load_words(a);
      axes_[a]->write_commands(dictionary_.get<uint16_t>(index(a, kCommandBits), 0), ticks(now_us_));
      publish(a);
    };
    for (auto& [sub, e] : dictionary_.object(index(a, kConfiguration))->entries)
      if (sub) e.on_written = [this, a] { load_config(a); };
  }
  for (unsigned m = 0; m < motors_; ++m) {
    for (uint16_t obj : {sim_obj::kSwitches, sim_obj::kEncoder, sim_obj::kFaults})
      for (auto& [sub, e] : dictionary_.object(sim_obj::index(m, obj))->entries)
        if (sub) e.on_written = [this, m] {
            load_machine(m);
            advance(now_us_);  // an input may have changed under a moving axis
          };
    dictionary_.at(sim_obj::index(m, sim_obj::kFaults), sim::faults_sub::kDisplace).on_written = [this, m] {
      machine_.axes[m].displace(dictionary_.get<int32_t>(sim_obj::index(m, sim_obj::kFaults),
                                                         sim::faults_sub::kDisplace));
      advance(now_us_);
    };
  }
  dictionary_.at(sim_obj::kEmergencyStop, 0).on_written = [this] {
    machine_.emergency_stop = dictionary_.get<uint8_t>(sim_obj::kEmergencyStop, 0) != 0;
    advance(now_us_);
  };
}

void MotionService::publish(unsigned a) {
  const motion::Axis& ax = *axes_[a];
  dictionary_.put<uint16_t>(index(a, kStatusBits), 0, ax.status());
  dictionary_.put<int32_t>(index(a, kMotorPosition), 0, ax.motor_position());
  dictionary_.put<int32_t>(index(a, kEncoderPosition), 0, ax.encoder_position());
  double v = ax.velocity() * (ax.dir_output_high() ? 1 : -1);
  dictionary_.put<int32_t>(index(a, kVelocity), 0, static_cast<int32_t>(std::lround(v)));
  dictionary_.put<uint8_t>(index(a, kMotionPhase), 0, static_cast<uint8_t>(ax.phase()));
  dictionary_.put<uint8_t>(index(a, kDirOutput), 0, ax.dir_output_high() ? 1 : 0);
}

void MotionService::publish_motor(unsigned a) {
  const sim::AxisMachine& m = machine_.axes[a];
  dictionary_.put<int32_t>(sim_obj::index(a, sim_obj::kMechanicalPosition), 0, static_cast<int32_t>(m.position()));
  uint8_t inputs = (m.home() ? 1 : 0) | (m.lower_limit() ? 2 : 0) | (m.upper_limit() ? 4 : 0) |
                   (m.index() ? 8 : 0) | (m.marker() ? 16 : 0);
  dictionary_.put<uint8_t>(sim_obj::index(a, sim_obj::kInputs), 0, inputs);
}

void MotionService::on_axis_event(unsigned a, const motion::AxisEvent& e) {
  uint16_t code = static_cast<uint16_t>(0xFF00 + a + 1);
  if (e.kind == motion::AxisEvent::Error) {
    emcy_.raise(code, error_bits::kManufacturer,
                {static_cast<uint8_t>(e.error_bits), static_cast<uint8_t>(e.status),
                 static_cast<uint8_t>(e.status >> 8), static_cast<uint8_t>(a + 1), 0},
                now_us_);
  } else if (!(e.status & motion::status::kErrors) && emcy_.active(code)) {
    emcy_.clear(code, now_us_);
  }
}

void MotionService::advance_axes(uint64_t now_us) {
  if (!epoch_set_) {
    epoch_us_ = now_us;
    epoch_set_ = true;
  }
  now_us_ = now_us;
  for (auto& axis : axes_) axis->advance_to(ticks(now_us));
}

void MotionService::advance(uint64_t now_us) {
  advance_axes(now_us);
  for (unsigned a = 0; a < count_; ++a) publish(a);
  for (unsigned m = 0; m < motors_; ++m) publish_motor(m);
}

void MotionService::power_up(uint64_t now_us) {
  advance(now_us);
  for (unsigned m = 0; m < motors_; ++m) load_machine(m);
  for (unsigned a = 0; a < count_; ++a) {
    load_config(a);
    axes_[a]->power_up(ticks(now_us));
    refused_words_[a]->clear();
    load_words(a);
    publish(a);
  }
  for (unsigned m = 0; m < motors_; ++m) publish_motor(m);
}

void MotionService::master_lost(uint64_t now_us) {
  now_us_ = now_us;
  for (auto& axis : axes_) axis->master_lost(ticks(now_us));
  for (unsigned a = 0; a < count_; ++a) publish(a);
  for (unsigned m = 0; m < motors_; ++m) publish_motor(m);
}

}  // namespace stepnode::node
