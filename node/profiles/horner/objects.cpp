#include "node/profiles/horner/objects.hpp"

#include <string>

#include "od/pdo_mapping.hpp"

namespace stepnode::horner {
namespace {

using DT = od::DataType;
using AC = od::Access;
using od::encode;
using od::Entry;
using od::limits;
using od::Object;

std::string axis_name(unsigned axis, const char* what) {
  return "Axis " + std::to_string(axis + 1) + " " + what;
}

// 0x2n09: how the axis is built (encoder, module model, homing and move options).
void add_configuration(od::Dictionary& od, unsigned a) {
  using namespace obj;
  Object& cfg = od.record(index(a, kConfiguration), axis_name(a, "configuration"));
  limits<uint8_t>(cfg.add(config_sub::kEncoderType,
                          "Encoder type (0 none, 1 quad, 2 up/down, 3 quad no marker)",
                          DT::Unsigned8, AC::ReadWrite, {0}),
                  0, 3);
  limits<uint8_t>(
      cfg.add(config_sub::kMultiplier, "Encoder multiplier", DT::Unsigned8, AC::ReadWrite, {1}), 1,
      255);
  limits<uint8_t>(
      cfg.add(config_sub::kDivisor, "Encoder divisor", DT::Unsigned8, AC::ReadWrite, {1}), 1, 16);
  cfg.add(config_sub::kTolerance, "Encoder tolerance", DT::Unsigned8, AC::ReadWrite, {0});
  cfg.add(config_sub::kStallDetection, "Stall detection", DT::Boolean, AC::ReadWrite, {0});
  cfg.add(config_sub::kHomeMethod, "Simple find-home method", DT::Boolean, AC::ReadWrite, {0});
  cfg.add(config_sub::kOriginSource, "Origin source is the encoder marker", DT::Boolean,
          AC::ReadWrite, {0});
  cfg.add(config_sub::kLimitQualified, "Limit-switch-qualified find home", DT::Boolean,
          AC::ReadWrite, {0});
  cfg.add(config_sub::kLimitStartedMoves, "Limit-switch-started moves", DT::Boolean, AC::ReadWrite,
          {0});
  cfg.add(config_sub::kIndexedMoves, "Indexed moves enabled", DT::Boolean, AC::ReadWrite, {1});
  // Where the manuals differ on the same feature (stall detection, the tolerance test,
  // QUAD homing), the module whose rules the axis follows.
  limits<uint8_t>(cfg.add(config_sub::kModuleModel, "Module model (0 SPM30, 1 STP100)",
                          DT::Unsigned8, AC::ReadWrite, {0}),
                  0, 1);
  Entry& decoding = cfg.add(config_sub::kQuadratureDecoding, "Quadrature counts per line (1, 2, 4)",
                            DT::Unsigned8, AC::ReadWrite, {1});
  limits<uint8_t>(decoding, 1, 4);
  cfg.add(config_sub::kStpcalcPeakShortMoves, "Short moves cruise at STPCALC's peak", DT::Boolean,
          AC::ReadWrite, {0});
  // SPM30 / STP100 specifications: "Direction Output Setup Time 2 ms".
  cfg.add(config_sub::kDirectionSetup, "Direction output setup time us", DT::Unsigned16,
          AC::ReadWrite, encode<uint16_t>(2000));
  decoding.validate = [](std::span<const uint8_t> v) {
    return v[0] == 3 ? od::SdoAbort::InvalidValue : od::SdoAbort::None;
  };
}

void add_registers(od::Dictionary& od, unsigned a) {
  using namespace obj;
  Entry& cmd = od.var(index(a, kCommandBits), axis_name(a, "command bits"), DT::Unsigned16,
                      AC::ReadWrite, encode<uint16_t>(0), true);
  cmd.persistent = false;  // commands are edges, never stored
  od.var(index(a, kStatusBits), axis_name(a, "status bits"), DT::Unsigned16, AC::ReadOnly,
         encode<uint16_t>(0x0080), true);
  Entry& dest = od.var(index(a, kDestination), axis_name(a, "destination position"), DT::Integer32,
                       AC::ReadWrite, encode<int32_t>(0), true);
  limits<int32_t>(dest, -8'388'608, 8'388'607);  // SPM30 3.4 / STP100 table 4.1
  dest.persistent = false;

  Object& prof = od.record(index(a, kProfile), axis_name(a, "motion profile"));
  limits<uint16_t>(prof.add(profile_sub::kVelocityDivisor, "Velocity divisor", DT::Unsigned16,
                            AC::ReadWrite, encode<uint16_t>(600), true),
                   20, 65535);
  limits<uint16_t>(prof.add(profile_sub::kBaseVelocity, "Base velocity", DT::Unsigned16,
                            AC::ReadWrite, encode<uint16_t>(100), true),
                   1, 8190);
  limits<uint16_t>(prof.add(profile_sub::kRunningVelocity, "Running velocity", DT::Unsigned16,
                            AC::ReadWrite, encode<uint16_t>(1000), true),
                   2, 8191);
  limits<uint16_t>(prof.add(profile_sub::kAcceleration, "Acceleration time ms", DT::Unsigned16,
                            AC::ReadWrite, encode<uint16_t>(500), true),
                   1, 27300);
  limits<uint16_t>(prof.add(profile_sub::kDeceleration, "Deceleration time ms", DT::Unsigned16,
                            AC::ReadWrite, encode<uint16_t>(0), true),
                   0, 27300);

  // The union of the two modules' ranges (STP113 C1.3.4: 0..8,388,607; STP100 table 4.1:
  // 1..16,777,215); the axis checks the module model's own range at MOVE INDEXED (Illegal
  // Move outside it). The window closes by default at the STP113's largest value.
  Object& idx = od.record(index(a, kIndexedMove), axis_name(a, "indexed move"));
  limits<uint32_t>(idx.add(indexed_sub::kDestination, "Indexed destination", DT::Unsigned32,
                           AC::ReadWrite, encode<uint32_t>(0), true),
                   0, 16'777'215);
  limits<uint16_t>(idx.add(indexed_sub::kDeceleration, "Indexed deceleration time ms",
                           DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(0), true),
                   0, 27300);
  limits<uint32_t>(idx.add(indexed_sub::kWindowOpen, "Index window open", DT::Unsigned32,
                           AC::ReadWrite, encode<uint32_t>(0), true),
                   0, 16'777'215);
  limits<uint32_t>(idx.add(indexed_sub::kWindowClose, "Index window close", DT::Unsigned32,
                           AC::ReadWrite, encode<uint32_t>(8'388'607), true),
                   0, 16'777'215);

  // Positions and velocity are sampled values (Entry::pdo_sampled).
  od.var(index(a, kMotorPosition), axis_name(a, "motor position"), DT::Integer32, AC::ReadOnly,
         encode<int32_t>(0), true)
      .pdo_sampled = true;
  od.var(index(a, kEncoderPosition), axis_name(a, "encoder position"), DT::Integer32, AC::ReadOnly,
         encode<int32_t>(0), true)
      .pdo_sampled = true;
  od.var(index(a, kVelocity), axis_name(a, "velocity steps/s"), DT::Integer32, AC::ReadOnly,
         encode<int32_t>(0), true)
      .pdo_sampled = true;
  od.var(index(a, kMotionPhase), axis_name(a, "motion phase"), DT::Unsigned8, AC::ReadOnly, {0},
         true);

  add_configuration(od, a);
  od.var(index(a, kDirOutput), axis_name(a, "DIR output"), DT::Boolean, AC::ReadOnly, {0}, true);
}

// Default PDOs of axis a: its four RPDOs and TPDOs (numbers 4a+1..4a+4). A master runs an
// axis with no SDO at all; axis 1 uses the pre-defined connection set IDs, the others
// start disabled (bit 31) so they cannot collide with another node's PDOs until the
// integrator gives them IDs.
void add_default_pdos(od::Dictionary& od, unsigned a) {
  using namespace obj;
  unsigned first = 4 * a;
  auto rmap = [&](unsigned k) { return od::rpdo_mapping(first + k); };
  auto tmap = [&](unsigned k) { return od::tpdo_mapping(first + k); };
  od::set_default_mapping(od, rmap(0),
                          {od::mapping_word(index(a, kCommandBits), 0, 16),
                           od::mapping_word(index(a, kDestination), 0, 32)});
  uint16_t p = index(a, kProfile);
  od::set_default_mapping(od, rmap(1),
                          {od::mapping_word(p, 1, 16), od::mapping_word(p, 2, 16),
                           od::mapping_word(p, 3, 16), od::mapping_word(p, 4, 16)});
  uint16_t ix = index(a, kIndexedMove);
  od::set_default_mapping(
      od, rmap(2),
      {od::mapping_word(p, 5, 16), od::mapping_word(ix, 2, 16), od::mapping_word(ix, 1, 32)});
  od::set_default_mapping(od, rmap(3), {od::mapping_word(ix, 3, 32), od::mapping_word(ix, 4, 32)});
  od::set_default_mapping(od, tmap(0),
                          {od::mapping_word(index(a, kStatusBits), 0, 16),
                           od::mapping_word(index(a, kMotorPosition), 0, 32)});
  od::set_default_mapping(od, tmap(1),
                          {od::mapping_word(index(a, kMotorPosition), 0, 32),
                           od::mapping_word(index(a, kEncoderPosition), 0, 32)});
  od::set_default_mapping(od, tmap(2),
                          {od::mapping_word(index(a, kVelocity), 0, 32),
                           od::mapping_word(index(a, kMotionPhase), 0, 8)});
  // Positions stream at most every 10 ms while moving (inhibit time, 100 us units).
  for (unsigned k : {1u, 2u}) {
    Entry& inhibit = od.at(static_cast<uint16_t>(0x1800 + first + k), 3);
    inhibit.default_value = inhibit.value = encode<uint16_t>(100);
  }
}

}  // namespace

void add_objects(od::Dictionary& od, unsigned axes) {
  for (unsigned a = 0; a < axes; ++a) {
    add_registers(od, a);
    add_default_pdos(od, a);
  }
}

}  // namespace stepnode::horner
