#include "node/profiles/horner/service.hpp"

#include <cmath>

#include "node/profiles/horner/objects.hpp"

namespace stepnode::node {

using namespace horner::obj;

HornerService::HornerService(od::Dictionary& dictionary, AxisBank& axes, EmcyProducer& emcy)
    : dictionary_(dictionary), axes_(axes), emcy_(emcy) {
  axes_.listen([this](unsigned a, const motion::AxisEvent& e) { on_axis_event(a, e); });
  install_hooks();
  for (unsigned a = 0; a < axes_.count(); ++a)
    refused_words_.push_back(std::make_unique<RefusedWords>(dictionary_, a));
}

void HornerService::load_words(unsigned a) {
  motion::CommandWords& w = axes_.axis(a).words();
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

void HornerService::load_config(unsigned a) {
  uint16_t c = index(a, kConfiguration);
  auto u8 = [&](uint8_t sub) { return dictionary_.get<uint8_t>(c, sub); };
  motion::AxisConfig cfg = axes_.axis(a).config();
  cfg.encoder = static_cast<motion::EncoderKind>(u8(horner::config_sub::kEncoderType));
  cfg.encoder_multiplier = u8(horner::config_sub::kMultiplier);
  cfg.encoder_divisor = u8(horner::config_sub::kDivisor);
  cfg.encoder_tolerance = u8(horner::config_sub::kTolerance);
  cfg.stall_detection = u8(horner::config_sub::kStallDetection) != 0;
  cfg.home_method = u8(horner::config_sub::kHomeMethod) ? motion::AxisConfig::HomeMethod::Simple
                                                        : motion::AxisConfig::HomeMethod::Normal;
  cfg.origin_source = u8(horner::config_sub::kOriginSource)
                          ? motion::AxisConfig::OriginSource::Marker
                          : motion::AxisConfig::OriginSource::HomeSwitch;
  cfg.limit_qualified_home = u8(horner::config_sub::kLimitQualified) != 0;
  cfg.limit_started_moves = u8(horner::config_sub::kLimitStartedMoves) != 0;
  cfg.indexed_moves = u8(horner::config_sub::kIndexedMoves) != 0;
  cfg.module = u8(horner::config_sub::kModuleModel) ? motion::AxisConfig::Module::Stp100
                                                    : motion::AxisConfig::Module::Spm30;
  cfg.quadrature_decoding = u8(horner::config_sub::kQuadratureDecoding);
  cfg.stpcalc_peak_short_moves = u8(horner::config_sub::kStpcalcPeakShortMoves) != 0;
  cfg.direction_setup_us = dictionary_.get<uint16_t>(c, horner::config_sub::kDirectionSetup);
  axes_.axis(a).set_config(cfg);
  axes_.machine().axes[a].config().encoder =
      cfg.encoder;  // the encoder is on the axis' first motor
}

void HornerService::install_hooks() {
  for (unsigned a = 0; a < axes_.count(); ++a) {
    // A command acts at once, with the words as they are now (SPM30 3.4: words may change
    // for the next move as soon as a command was taken).
    od::listen(dictionary_.at(index(a, kCommandBits), 0), [this, a] {
      load_words(a);
      axes_.axis(a).write_commands(dictionary_.get<uint16_t>(index(a, kCommandBits), 0),
                                   axes_.now());
      publish(a);
    });
    for (auto& [sub, e] : dictionary_.object(index(a, kConfiguration))->entries)
      if (sub) od::listen(e, [this, a] { load_config(a); });
  }
}

void HornerService::configure(uint64_t) {
  for (unsigned a = 0; a < axes_.count(); ++a) load_config(a);
}

void HornerService::power_up(uint64_t) {
  for (unsigned a = 0; a < axes_.count(); ++a) {
    refused_words_[a]->clear();
    load_words(a);
    publish(a);
  }
}

void HornerService::publish() {
  for (unsigned a = 0; a < axes_.count(); ++a) publish(a);
}

void HornerService::publish(unsigned a) {
  const motion::Axis& ax = axes_.axis(a);
  dictionary_.put<uint16_t>(index(a, kStatusBits), 0, ax.status());
  dictionary_.put<int32_t>(index(a, kMotorPosition), 0, ax.motor_position());
  dictionary_.put<int32_t>(index(a, kEncoderPosition), 0, ax.encoder_position());
  double v = ax.velocity() * (ax.dir_output_high() ? 1 : -1);
  dictionary_.put<int32_t>(index(a, kVelocity), 0, static_cast<int32_t>(std::lround(v)));
  dictionary_.put<uint8_t>(index(a, kMotionPhase), 0, static_cast<uint8_t>(ax.phase()));
  dictionary_.put<uint8_t>(index(a, kDirOutput), 0, ax.dir_output_high() ? 1 : 0);
}

void HornerService::on_axis_event(unsigned a, const motion::AxisEvent& e) {
  uint16_t code = static_cast<uint16_t>(0xFF00 + a + 1);
  if (e.kind == motion::AxisEvent::Error) {
    emcy_.raise(code, error_bits::kManufacturer,
                {static_cast<uint8_t>(e.error_bits), static_cast<uint8_t>(e.status),
                 static_cast<uint8_t>(e.status >> 8), static_cast<uint8_t>(a + 1), 0},
                axes_.now_us(), emcy_source::kAxis + a);
  } else if (!(e.status & motion::status::kErrors) && emcy_.active(code)) {
    emcy_.clear(code, axes_.now_us(), emcy_source::kAxis + a);
  }
}

}  // namespace stepnode::node
