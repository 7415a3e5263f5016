#include "node/profiles/hp44714a/service.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "node/profiles/hp44714a/objects.hpp"

namespace stepnode::node {

using namespace hp44714a::obj;
namespace hp = motion::hp;
using od::SdoAbort;

namespace {

double real(std::span<const uint8_t> d) { return od::decode<double>(d); }
uint8_t u8(std::span<const uint8_t> d) { return od::decode<uint8_t>(d); }

// Appendix A: "Total number output pulses/channel in MOVE mode: ±2,147,483,647". A MOVE of
// more (1e300 units, or 1e10 at PSCALE 1e-300) is a range abort, not a move.
bool move_in_range(const hp::Channel& ch, double d, bool absolute) {
  if (!std::isfinite(d)) return false;
  const double steps = (absolute ? d - ch.pos_query() : d) / ch.scale();
  return std::fabs(steps) < 2147483647.5;
}

}  // namespace

HpService::HpService(od::Dictionary& dictionary, AxisBank& axes, EmcyProducer& emcy)
    : dictionary_(dictionary), axes_(axes), emcy_(emcy) {
  for (unsigned a = 0; a < axes_.count(); ++a) {
    channels_.push_back(std::make_unique<hp::Channel>(axes_.core(a)));
    hp::Channel& ch = *channels_.back();
    ch.on_interrupt = [this, a](uint8_t event, motion::Tick) {
      // Halts and limits also go out as EMCY (condition 3, 4, 5 -> 0xFF43..0xFF45).
      uint8_t condition = 0;
      for (uint8_t b = event; b; b >>= 1) ++condition;
      if (condition >= 3)
        emcy_.report(static_cast<uint16_t>(hp44714a::kInterruptEmcyBase + condition),
                     error_bits::kManufacturer, {event, static_cast<uint8_t>(a + 1), 0, 0, 0},
                     axes_.now_us());
    };
    install_hooks(a);
  }
  // TRIG CHAN0: "triggering channels 1 and 2 off of channel 0" (3-27).
  if (!channels_.empty())
    channels_[0]->on_triggered = [this](motion::Tick at) {
      for (size_t k = 1; k < channels_.size(); ++k) channels_[k]->chan0_triggered(at);
    };
}

SdoAbort HpService::result(unsigned a, hp::Error e) {
  if (e == hp::Error::None) return SdoAbort::None;
  if (e == hp::Error::ValueOutOfRange) return SdoAbort::InvalidValue;  // no HP error number
  uint8_t n = static_cast<uint8_t>(e);
  emcy_.report(static_cast<uint16_t>(hp44714a::kErrorEmcyBase + n), error_bits::kManufacturer,
               {n, static_cast<uint8_t>(a + 1), 0, 0, 0}, axes_.now_us());
  publish(a);
  return SdoAbort::DeviceState;
}

void HpService::hook(unsigned a, uint16_t offset, uint8_t sub,
                     std::function<SdoAbort(std::span<const uint8_t>)> f) {
  // A command is a write: it acts once the value is stored (for an RPDO, once the whole
  // PDO is), on the stored value; a refusal puts the previous value back and is the abort.
  od::Entry& entry = dictionary_.at(index(a, offset), sub);
  od::react(entry, [this, a, f = std::move(f), &entry] {
    SdoAbort r = f(entry.value);
    publish(a);
    return r;
  });
}

void HpService::setting_hook(unsigned a, uint16_t offset, uint8_t sub,
                             std::function<void(std::span<const uint8_t>)> apply) {
  hook(a, offset, sub, [this, a, apply = std::move(apply)](std::span<const uint8_t> d) {
    if (hp::Error e = channels_[a]->setting_command(); e != hp::Error::None) return result(a, e);
    apply(d);
    return SdoAbort::None;
  });
}

void HpService::install_hooks(unsigned a) {
  install_command_hooks(a);
  install_output_hooks(a);
  install_counter_hooks(a);
}

// PROFILE, PSCALE, MOVE, SUSTAIN, TRIG, DELAY.
void HpService::install_command_hooks(unsigned a) {
  hp::Channel& ch = *channels_[a];
  auto hook = [this, a](uint16_t offset, uint8_t sub,
                        std::function<SdoAbort(std::span<const uint8_t>)> f) {
    this->hook(a, offset, sub, std::move(f));
  };
  // PROFILE: subs 1-5 are staged; writing 1 to sub 6 gives the PROFILE command.
  hook(kProfile, hp44714a::profile_sub::kApply, [this, a, &ch](std::span<const uint8_t> d) {
    if (u8(d) != 1) return SdoAbort::None;
    uint16_t p = index(a, kProfile);
    hp::Profile prof{
        static_cast<hp::ProfileMode>(dictionary_.get<uint8_t>(p, hp44714a::profile_sub::kMode)),
        dictionary_.get<double>(p, hp44714a::profile_sub::kMin),
        dictionary_.get<double>(p, hp44714a::profile_sub::kMax),
        dictionary_.get<double>(p, hp44714a::profile_sub::kSlope),
        dictionary_.get<double>(p, hp44714a::profile_sub::kLast)};
    hp::Error e = hp::Error::None;
    hp::Conflict c = ch.profile(prof, now(), &e);
    if (e != hp::Error::None) return result(a, e);
    if (c != hp::Conflict::None) return SdoAbort::ParameterIncompatible;
    dictionary_.put<double>(p, hp44714a::profile_sub::kGivenAtPscale, ch.pscale_value());
    return SdoAbort::None;
  });
  hook(kPscale, 0, [this, a, &ch](std::span<const uint8_t> d) {
    double s = real(d);
    if (s == 0 || !std::isfinite(s)) return SdoAbort::InvalidValue;
    return result(a, ch.pscale(s));
  });
  auto nowait = [this, a] {
    return dictionary_.get<uint8_t>(index(a, kMove), hp44714a::move_sub::kNowait) != 0;
  };
  hook(kMove, hp44714a::move_sub::kRelative, [this, a, &ch, nowait](std::span<const uint8_t> d) {
    return move_in_range(ch, real(d), false) ? result(a, ch.move(real(d), false, nowait(), now()))
                                             : SdoAbort::InvalidValue;
  });
  hook(kMove, hp44714a::move_sub::kAbsolute, [this, a, &ch, nowait](std::span<const uint8_t> d) {
    return move_in_range(ch, real(d), true) ? result(a, ch.move(real(d), true, nowait(), now()))
                                            : SdoAbort::InvalidValue;
  });
  hook(kSustain, 0, [this, a, &ch, nowait](std::span<const uint8_t> d) {
    return std::isfinite(real(d)) ? result(a, ch.sustain(real(d), nowait(), now()))
                                  : SdoAbort::InvalidValue;
  });
  hook(kTrig, 0, [this, a, &ch](std::span<const uint8_t> d) {
    return result(a, ch.trig(static_cast<hp::TrigMode>(u8(d)), now()));
  });
  dictionary_.at(index(a, kTrig), 0).on_read = [&ch](od::Bytes& v) {
    v = od::encode<uint8_t>(static_cast<uint8_t>(ch.trig_mode()));
  };
  setting_hook(a, kDelay, 0,
               [&ch](std::span<const uint8_t> d) { ch.delay(od::decode<uint16_t>(d)); });
}

// STANDBY, PULSE, HARDLIM, HALT.
void HpService::install_output_hooks(unsigned a) {
  hp::Channel& ch = *channels_[a];
  auto hook = [this, a](uint16_t offset, uint8_t sub,
                        std::function<SdoAbort(std::span<const uint8_t>)> f) {
    this->hook(a, offset, sub, std::move(f));
  };
  uint16_t out = index(a, kOutput);
  auto standby = [this, a, &ch](uint8_t mode, uint8_t sense) {
    return result(a, ch.standby(static_cast<hp::StandbyMode>(mode), sense != 0, now()));
  };
  hook(kOutput, hp44714a::output_sub::kStandbyMode,
       [this, out, standby](std::span<const uint8_t> d) {
         return standby(u8(d), dictionary_.get<uint8_t>(out, hp44714a::output_sub::kStandbySense));
       });
  hook(kOutput, hp44714a::output_sub::kStandbySense,
       [this, out, standby](std::span<const uint8_t> d) {
         return standby(dictionary_.get<uint8_t>(out, hp44714a::output_sub::kStandbyMode), u8(d));
       });
  for (uint8_t sub : {hp44714a::output_sub::kPulseMode, hp44714a::output_sub::kPstpSense,
                      hp44714a::output_sub::kNdirSense})
    setting_hook(a, kOutput, sub, [this, out, sub, &ch](std::span<const uint8_t> d) {
      auto get = [&](uint8_t s) { return s == sub ? u8(d) : dictionary_.get<uint8_t>(out, s); };
      ch.pulse(hp::PulseSetup{static_cast<hp::PulseMode>(get(hp44714a::output_sub::kPulseMode)),
                              get(hp44714a::output_sub::kPstpSense) != 0,
                              get(hp44714a::output_sub::kNdirSense) != 0});
    });
  uint16_t lim = index(a, kLimits);
  for (uint8_t sub : {hp44714a::limits_sub::kPlimSense, hp44714a::limits_sub::kNlimSense})
    setting_hook(a, kLimits, sub, [this, lim, sub, &ch](std::span<const uint8_t> d) {
      auto get = [&](uint8_t s) { return s == sub ? u8(d) : dictionary_.get<uint8_t>(lim, s); };
      ch.hardlim(get(hp44714a::limits_sub::kPlimSense) != 0,
                 get(hp44714a::limits_sub::kNlimSense) != 0);
    });
  hook(kLimits, hp44714a::limits_sub::kHaltMode, [this, &ch](std::span<const uint8_t> d) {
    ch.halt_mode(static_cast<hp::HaltMode>(u8(d)), now());
    return SdoAbort::None;
  });
  hook(kLimits, hp44714a::limits_sub::kHaltSgl, [this, &ch](std::span<const uint8_t> d) {
    if (u8(d)) ch.halt_sgl(now());
    return SdoAbort::None;
  });
}

// POS, the quadrature counter, interrupts, and the simulated terminal inputs.
void HpService::install_counter_hooks(unsigned a) {
  hp::Channel& ch = *channels_[a];
  od::Dictionary& od = dictionary_;
  auto hook = [this, a](uint16_t offset, uint8_t sub,
                        std::function<SdoAbort(std::span<const uint8_t>)> f) {
    this->hook(a, offset, sub, std::move(f));
  };
  hook(kPosition, 0, [this, a, &ch](std::span<const uint8_t> d) {
    // "This value can be any number from -2,147,483,648 to +2,147,483,647 specified in the
    // units of the PSCALE command" (3-18): outside it a range abort, as for a MOVE.
    const double v = real(d);
    return v >= -2147483648.0 && v <= 2147483647.0 ? result(a, ch.pos(v)) : SdoAbort::InvalidValue;
  });
  od.at(index(a, kPosition), 0).on_read = [&ch](od::Bytes& v) {
    v = od::encode<double>(ch.pos_query());
  };
  uint16_t q = index(a, kQuadrature);
  hook(kQuadrature, hp44714a::quad_sub::kQscale, [this, a, &ch](std::span<const uint8_t> d) {
    if (!std::isfinite(real(d))) return SdoAbort::InvalidValue;
    if (hp::Error e = ch.setting_command(); e != hp::Error::None) return result(a, e);
    ch.qscale(real(d));
    return SdoAbort::None;
  });
  setting_hook(a, kQuadrature, hp44714a::quad_sub::kQindex, [&ch](std::span<const uint8_t> d) {
    ch.qindex(static_cast<hp::QIndexMode>(u8(d)));
  });
  od.at(q, hp44714a::quad_sub::kQindex).on_read = [&ch](od::Bytes& v) {
    v = od::encode<uint8_t>(static_cast<uint8_t>(ch.qindex_mode()));
  };
  od.at(q, hp44714a::quad_sub::kQpos).on_read = [&ch](od::Bytes& v) {
    v = od::encode<double>(ch.qpos_query());
  };
  setting_hook(a, kInterrupt, hp44714a::intr_sub::kEnable, [&ch](std::span<const uint8_t> d) {
    if (u8(d)) ch.enable_intr();
    else ch.disable_intr();
  });
  od.at(index(a, kInterrupt), hp44714a::intr_sub::kEnable).on_read = [&ch](od::Bytes& v) {
    v = od::encode<uint8_t>(ch.intr_enabled() ? 1 : 0);
  };
  hook(kTest, hp44714a::test_sub::kRun, [this, a, &ch, &od](std::span<const uint8_t> d) {
    if (u8(d) != 1) return SdoAbort::None;
    uint8_t failed = 0;
    if (hp::Error e = ch.test(failed); e != hp::Error::None) return result(a, e);
    od.put<uint8_t>(index(a, kTest), hp44714a::test_sub::kResult, failed ? 1 : 0);
    od.put<uint8_t>(index(a, kTest), hp44714a::test_sub::kFailedChecks, failed);
    return SdoAbort::None;
  });
  uint16_t sim = sim_index(a);
  od::listen(od.at(sim, hp44714a::sim_sub::kHaltInputHigh), [this, a, sim] {
    // The simulated HALT switch is an input of the motor's port: the channel sees its edge.
    axes_.machine().axes.at(a).set_halt_input(
        dictionary_.get<uint8_t>(sim, hp44714a::sim_sub::kHaltInputHigh) != 0);
    axes_.advance(axes_.now_us());
    publish(a);
  });
  od::listen(od.at(sim, hp44714a::sim_sub::kTestJumper), [this, sim, &ch] {
    ch.set_test_jumper(dictionary_.get<uint8_t>(sim, hp44714a::sim_sub::kTestJumper) != 0);
  });
}

void HpService::apply_stored(unsigned a, motion::Tick t) {
  hp::Channel& ch = *channels_[a];
  uint16_t p = index(a, kProfile), out = index(a, kOutput), lim = index(a, kLimits);
  auto g8 = [&](uint16_t i, uint8_t s) { return dictionary_.get<uint8_t>(i, s); };
  // The stored PROFILE is given at the PSCALE it was given at (its FREQ values are in that
  // PSCALE's units, 3-9), then the stored PSCALE: "PSCALE 0.5; PROFILE FREQ 100 ..." runs
  // at 200 pulses/s again after a restart (it ran at 100: found in review). One the channel
  // refuses (stored by a build with other limits) leaves the power-on profile, and its
  // objects show that one again; EMCY 0x5530 says a stored value was refused.
  const double at = dictionary_.get<double>(p, hp44714a::profile_sub::kGivenAtPscale);
  if (at != 0 && std::isfinite(at)) ch.pscale(at);
  hp::Conflict c =
      ch.profile(hp::Profile{static_cast<hp::ProfileMode>(g8(p, hp44714a::profile_sub::kMode)),
                             dictionary_.get<double>(p, hp44714a::profile_sub::kMin),
                             dictionary_.get<double>(p, hp44714a::profile_sub::kMax),
                             dictionary_.get<double>(p, hp44714a::profile_sub::kSlope),
                             dictionary_.get<double>(p, hp44714a::profile_sub::kLast)},
                 t);
  if (c != hp::Conflict::None) {
    spdlog::warn(
        "stored PROFILE of HP channel {} is refused (conflict row {}); the power-on profile "
        "applies",
        a, static_cast<int>(c));
    dictionary_.reset_to_defaults(p, p);
    ch.pscale(1.0);  // the power-on profile is in pulses/s
    emcy_.report(emcy_code::kDataStorage, error_bits::kGeneric,
                 {static_cast<uint8_t>(p), static_cast<uint8_t>(p >> 8), 0, 1, 0}, axes_.now_us());
  }
  double s = dictionary_.get<double>(index(a, kPscale), 0);
  if (s != 0 && std::isfinite(s)) ch.pscale(s);
  ch.delay(dictionary_.get<uint16_t>(index(a, kDelay), 0));
  ch.standby(static_cast<hp::StandbyMode>(g8(out, hp44714a::output_sub::kStandbyMode)),
             g8(out, hp44714a::output_sub::kStandbySense) != 0, t);
  ch.pulse(hp::PulseSetup{static_cast<hp::PulseMode>(g8(out, hp44714a::output_sub::kPulseMode)),
                          g8(out, hp44714a::output_sub::kPstpSense) != 0,
                          g8(out, hp44714a::output_sub::kNdirSense) != 0});
  ch.hardlim(g8(lim, hp44714a::limits_sub::kPlimSense) != 0,
             g8(lim, hp44714a::limits_sub::kNlimSense) != 0);
  ch.halt_mode(static_cast<hp::HaltMode>(g8(lim, hp44714a::limits_sub::kHaltMode)), t);
  ch.qscale(dictionary_.get<double>(index(a, kQuadrature), hp44714a::quad_sub::kQscale));
  axes_.machine().axes.at(a).set_halt_input(g8(sim_index(a), hp44714a::sim_sub::kHaltInputHigh) !=
                                            0);
  axes_.advance(axes_.now_us());
  ch.set_test_jumper(g8(sim_index(a), hp44714a::sim_sub::kTestJumper) != 0);
}

void HpService::publish(unsigned a) {
  const hp::Channel& ch = *channels_[a];
  od::Dictionary& od = dictionary_;
  od.put<int8_t>(index(a, kDone), 0, static_cast<int8_t>(ch.done()));
  od.put<uint8_t>(index(a, kError), 0, static_cast<uint8_t>(ch.last_error()));
  od.put<uint8_t>(index(a, kConflict), 0, static_cast<uint8_t>(ch.last_conflict()));
  od.put<uint8_t>(index(a, kInterrupt), hp44714a::intr_sub::kEvents, ch.interrupt_events());
  uint16_t out = index(a, kOutput);
  od.put<uint8_t>(out, hp44714a::output_sub::kStbyLevel, ch.stby_output_high() ? 1 : 0);
  od.put<uint8_t>(out, hp44714a::output_sub::kMotorPowered, ch.motor_powered() ? 1 : 0);
  // In the simulation the STBY output drives motor power (issue 4): with STANDBY ON a
  // Horner move still counts its steps, but the load does not move.
  axes_.machine().axes.at(a).set_powered(ch.pulses_reach_powered_motor());
  od.put<uint32_t>(out, hp44714a::output_sub::kPstpPulses,
                   static_cast<uint32_t>(ch.pulses(hp::Output::Pstp)));
  od.put<uint32_t>(out, hp44714a::output_sub::kNdirPulses,
                   static_cast<uint32_t>(ch.pulses(hp::Output::Ndir)));
  od.put<double>(out, hp44714a::output_sub::kPulseWidth, ch.current_width());
  od.put<uint32_t>(sim_index(a), hp44714a::sim_sub::kLastPulseWidthNs,
                   axes_.machine().axes.at(a).last_pulse_width_ns());
  od.put<double>(index(a, kPosition), 0, ch.pos_query());
  od.put<int32_t>(index(a, kQuadrature), hp44714a::quad_sub::kCount, ch.quadrature_count());
  uint16_t t = index(a, kTiming);
  if (auto trig = ch.trigger_time()) {
    od.put<uint32_t>(t, hp44714a::timing_sub::kTriggerUs,
                     static_cast<uint32_t>(axes_.micros(*trig)));
    auto first = ch.first_step_time();
    od.put<uint32_t>(t, hp44714a::timing_sub::kFirstStepUs,
                     first ? static_cast<uint32_t>(axes_.micros(*first)) : 0);
    od.put<int32_t>(t, hp44714a::timing_sub::kFirstStepAfterTriggerUs,
                    first ? static_cast<int32_t>(axes_.micros(*first) - axes_.micros(*trig)) : -1);
  }
}

uint64_t HpService::next_advance_us(uint64_t now_us) {
  uint64_t next = kNoDeadline;
  // The job's steps (and a Horner job's) are the axes' deadlines (AxisBank); what is left is
  // each channel's own timed work: a DELAY's end, a WIDTH ramp reaching its width, STANDBY
  // AUTO's power-off. A job waiting for its trigger waits for a frame (TRIGGER, a SYNC, or
  // channel 0's trigger, which fans out in the same advance).
  for (const auto& ch : channels_)
    if (const std::optional<motion::Tick> at = ch->next_event(now()))
      next = earliest(next, std::max(axes_.micros_at_or_after(*at), now_us + 1));
  return next;
}

void HpService::advance(uint64_t) {
  for (auto& ch : channels_) ch->advance_to(now());
}

void HpService::publish() {
  for (unsigned a = 0; a < channels_.size(); ++a) publish(a);
}

void HpService::power_up(uint64_t) {
  for (unsigned a = 0; a < channels_.size(); ++a) {
    channels_[a]->power_up(now());
    apply_stored(a, now());
    publish(a);
  }
}

void HpService::sync(uint64_t now_us, uint64_t frame_us) {
  motion::Tick at = axes_.ticks(std::min(frame_us, now_us));
  for (auto& ch : channels_) ch->sync(at);
}

}  // namespace stepnode::node
