#include "node/profiles/cia402/objects.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "od/pdo_mapping.hpp"

namespace stepnode::cia402 {
namespace {

using DT = od::DataType;
using od::Bytes;
using od::encode;
using od::Entry;
using od::limits;
using od::Object;
using od::SdoAbort;
constexpr od::Access RO = od::Access::ReadOnly, RW = od::Access::ReadWrite;
constexpr bool kPdo = true;

Bytes i8(int8_t v) { return encode<int8_t>(v); }
Bytes i16(int16_t v) { return encode<int16_t>(v); }
Bytes u16(uint16_t v) { return encode<uint16_t>(v); }
Bytes i32(int32_t v) { return encode<int32_t>(v); }
Bytes u32(uint32_t v) { return encode<uint32_t>(v); }

// A command or a set-point: acting on it is the point, storing it (0x1010) is not.
Entry& command(Entry& e) {
  e.persistent = false;
  return e;
}

// A value that changes with the motion (Entry::pdo_sampled): it streams, limited by the
// TPDO's inhibit time, but does not by itself send a TPDO that also carries an event.
Entry& sampled(Entry& e) {
  e.pdo_sampled = true;
  return e;
}

// An enumeration with holes: any other value is refused with 0x06090030 (value range of
// parameter exceeded), over SDO and in an RPDO alike.
template <class T>
Entry& one_of(Entry& e, std::vector<T> values) {
  e.validate = [values = std::move(values)](std::span<const uint8_t> data) {
    const bool known = std::find(values.begin(), values.end(), od::decode<T>(data)) != values.end();
    return known ? SdoAbort::None : SdoAbort::InvalidValue;
  };
  return e;
}

// The objects of axis `a`: index base + 0x800 * a, named "Axis n ...".
struct AxisTable {
  od::Dictionary& od;
  unsigned a;

  std::string name(const char* what) const { return "Axis " + std::to_string(a + 1) + " " + what; }
  Entry& var(uint16_t base, const char* what, DT type, od::Access access, Bytes value,
             bool pdo = false) {
    return od.var(obj::index(a, base), name(what), type, access, std::move(value), pdo);
  }
  Object& array(uint16_t base, const char* what) {
    return od.record(obj::index(a, base), name(what), od::ObjectCode::Array);
  }
  // An ARRAY of two U32 ratio terms, each at least 1 (they divide).
  void ratio(uint16_t base, const char* what, const char* first, const char* second) {
    Object& r = array(base, what);
    limits<uint32_t>(r.add(1, first, DT::Unsigned32, RW, u32(1)), 1, 0xFFFF'FFFF);
    limits<uint32_t>(r.add(2, second, DT::Unsigned32, RW, u32(1)), 1, 0xFFFF'FFFF);
  }
};

// Device control (CiA 402-2 "device control" and the option codes). Ranges are the values
// the standard defines; the negative (manufacturer-specific) ones are refused: this drive
// defines none. Defaults are the standard's: 605Ah 2, 605Bh 0, 605Ch 1, 605Dh 1, 605Eh 2.
void add_device_control(AxisTable t) {
  using namespace obj;
  // 6007h: 0 no action, 1 fault signal, 2 disable voltage, 3 quick stop; default 1.
  limits<int16_t>(
      t.var(kAbortConnectionOption, "Abort connection option code", DT::Integer16, RW, i16(1)), 0,
      3);
  t.var(kErrorCode, "Error code", DT::Unsigned16, RO, u16(0), kPdo);
  command(t.var(kControlword, "Controlword", DT::Unsigned16, RW, u16(0), kPdo));
  // Until the service has run transitions 0 and 1: Not ready to switch on, remote (bit 9).
  t.var(kStatusword, "Statusword", DT::Unsigned16, RO, u16(0x0200), kPdo);
  limits<int16_t>(t.var(kQuickStopOption, "Quick stop option code", DT::Integer16, RW, i16(2)), 0,
                  8);
  limits<int16_t>(t.var(kShutdownOption, "Shutdown option code", DT::Integer16, RW, i16(0)), 0, 1);
  limits<int16_t>(
      t.var(kDisableOperationOption, "Disable operation option code", DT::Integer16, RW, i16(1)), 0,
      1);
  limits<int16_t>(t.var(kHaltOption, "Halt option code", DT::Integer16, RW, i16(1)), 1,
                  4);  // 0 is reserved
  limits<int16_t>(
      t.var(kFaultReactionOption, "Fault reaction option code", DT::Integer16, RW, i16(2)), 0, 4);
  // 6060h: the master selects the mode for its session, so it is not stored; 0 (no mode
  // assigned) until it does (the standard leaves the default to the vendor).
  Entry& modes = command(
      t.var(kModesOfOperation, "Modes of operation", DT::Integer8, RW, i8(mode::kNone), kPdo));
  modes.validate = [](std::span<const uint8_t> data) {
    return mode_supported(od::decode<int8_t>(data)) ? SdoAbort::None : SdoAbort::InvalidValue;
  };
  t.var(kModesOfOperationDisplay, "Modes of operation display", DT::Integer8, RO, i8(mode::kNone),
        kPdo);
  t.var(kSupportedDriveModes, "Supported drive modes", DT::Unsigned32, RO,
        u32(kSupportedDriveModesValue));
  t.var(kSingleDeviceType, "Single device type", DT::Unsigned32, RO, u32(kDeviceTypeStepper));
}

// Positions and velocities: the actual values are samples, the targets commands. Position
// units are steps and velocity units steps/s while the factor group is 1:1.
void add_position_objects(AxisTable t) {
  using namespace obj;
  sampled(t.var(kPositionDemand, "Position demand value", DT::Integer32, RO, i32(0), kPdo));
  sampled(t.var(kPositionActualInternal, "Position actual internal value", DT::Integer32, RO,
                i32(0), kPdo));
  sampled(t.var(kPositionActual, "Position actual value", DT::Integer32, RO, i32(0), kPdo));
  sampled(t.var(kVelocityActual, "Velocity actual value", DT::Integer32, RO, i32(0), kPdo));
  sampled(t.var(kFollowingErrorActual, "Following error actual value", DT::Integer32, RO, i32(0),
                kPdo));
  // Vendor defaults: the following error check off (FFFFFFFFh, as the standard codes it: an
  // open-loop stepper's actual position is its demand) and a position window of 0 (a target
  // is reached on its step).
  t.var(kFollowingErrorWindow, "Following error window", DT::Unsigned32, RW, u32(0xFFFF'FFFF));
  t.var(kFollowingErrorTimeout, "Following error time out", DT::Unsigned16, RW, u16(0));
  t.var(kPositionWindow, "Position window", DT::Unsigned32, RW, u32(0));
  t.var(kPositionWindowTime, "Position window time", DT::Unsigned16, RW, u16(0));
  command(t.var(kTargetPosition, "Target position", DT::Integer32, RW, i32(0), kPdo));
  command(t.var(kTargetVelocity, "Target velocity", DT::Integer32, RW, i32(0), kPdo));
  // 60B0h/60B1h: the offsets a master streams with the cyclic set-points (csp/csv).
  command(t.var(kPositionOffset, "Position offset", DT::Integer32, RW, i32(0), kPdo));
  command(t.var(kVelocityOffset, "Velocity offset", DT::Integer32, RW, i32(0), kPdo));
  t.var(kHomeOffset, "Home offset", DT::Integer32, RW, i32(0));
  // 607Dh: vendor default the whole range, i.e. no software limit in effect.
  Object& lim = t.array(kSoftwarePositionLimit, "Software position limit");
  lim.add(limit_sub::kMin, "Min position limit", DT::Integer32, RW,
          i32(std::numeric_limits<int32_t>::min()));
  lim.add(limit_sub::kMax, "Max position limit", DT::Integer32, RW,
          i32(std::numeric_limits<int32_t>::max()));
  t.var(kDigitalInputs, "Digital inputs", DT::Unsigned32, RO, u32(0), kPdo);
}

// The profile (pp, pv, hm): vendor defaults in steps, steps/s and steps/s^2; 607Fh is
// 10 000 steps/s, the HP 44714A front end's highest pulse rate on the same engine. 6081h is
// mappable: a pp master may send each move's velocity with its target.
void add_profile_objects(AxisTable t) {
  using namespace obj;
  t.var(kMaxProfileVelocity, "Max profile velocity", DT::Unsigned32, RW, u32(10'000));
  t.var(kProfileVelocity, "Profile velocity", DT::Unsigned32, RW, u32(1'000), kPdo);
  t.var(kProfileAcceleration, "Profile acceleration", DT::Unsigned32, RW, u32(1'000));
  t.var(kProfileDeceleration, "Profile deceleration", DT::Unsigned32, RW, u32(1'000));
  t.var(kQuickStopDeceleration, "Quick stop deceleration", DT::Unsigned32, RW, u32(10'000));
  // 6086h: 0 linear ramp (trapezoidal profile) and 3, DSP 402 V2.0's jerk-limited ramp
  // (S-curve, PP and PV); 1 sin^2 ramp and 2 jerk-free ramp are not offered (0x06090030).
  one_of<int16_t>(t.var(kMotionProfileType, "Motion profile type", DT::Integer16, RW, i16(0)),
                  {0, 3});
  // 60A4h: the jerks of the S-curve in steps/s^3, every UNSIGNED32 honoured (0: the jerk is
  // not limited, that phase takes no time); vendor default 10 000.
  Object& jerk = t.array(kProfileJerk, "Profile jerk");
  jerk.add(jerk_sub::kBeginAcceleration, "Begin acceleration jerk", DT::Unsigned32, RW,
           u32(10'000));
  jerk.add(jerk_sub::kBeginDeceleration, "Begin deceleration jerk", DT::Unsigned32, RW,
           u32(10'000));
  jerk.add(jerk_sub::kEndAcceleration, "End acceleration jerk", DT::Unsigned32, RW, u32(10'000));
  jerk.add(jerk_sub::kEndDeceleration, "End deceleration jerk", DT::Unsigned32, RW, u32(10'000));
  // 6098h: 0 (no homing method assigned) by default; the methods the standard defines: 1..35
  // and 37, without the reserved 15, 16, 31, 32 and 36, and the manufacturer's -1, -2, -17,
  // -18 on a hard stop (homing.hpp; the homing mode will refuse at its start a method the
  // axis cannot run).
  std::vector<int8_t> methods{-18, -17, -2, -1, 0, 37};
  for (int8_t m = 1; m <= 35; ++m)
    if (m != 15 && m != 16 && m != 31 && m != 32) methods.push_back(m);
  one_of<int8_t>(t.var(kHomingMethod, "Homing method", DT::Integer8, RW, i8(0)),
                 std::move(methods));
  Object& speeds = t.array(kHomingSpeeds, "Homing speeds");
  speeds.add(homing_speed_sub::kSwitchSearch, "Speed during search for switch", DT::Unsigned32, RW,
             u32(1'000));
  speeds.add(homing_speed_sub::kZeroSearch, "Speed during search for zero", DT::Unsigned32, RW,
             u32(100));
  t.var(kHomingAcceleration, "Homing acceleration", DT::Unsigned32, RW, u32(1'000));
}

// The factor group and the interpolated position mode. The factors default to 1:1 (vendor
// choice): an encoder increment, a position unit and a step are the same.
void add_factor_and_ip_objects(AxisTable t) {
  using namespace obj;
  t.ratio(kPositionEncoderResolution, "Position encoder resolution", "Encoder increments",
          "Motor revolutions");
  t.ratio(kGearRatio, "Gear ratio", "Motor revolutions", "Shaft revolutions");
  t.ratio(kFeedConstant, "Feed constant", "Feed", "Shaft revolutions");
  // 60C0h: 0 linear interpolation, the only sub-mode the standard defines.
  one_of<int16_t>(
      t.var(kInterpolationSubMode, "Interpolation sub mode select", DT::Integer16, RW, i16(0)),
      {0});
  Object& data = t.array(kInterpolationData, "Interpolation data record");
  command(data.add(ip_data_sub::kSetPoint, "Position set-point", DT::Integer32, RW, i32(0), kPdo));
  // 60C2h: the period is units * 10^index s, index -128..63; vendor default 1 ms (1, -3).
  Object& period =
      t.od.record(obj::index(t.a, kInterpolationPeriod), t.name("Interpolation time period"));
  period.add(ip_period_sub::kUnits, "Interpolation time period value", DT::Unsigned8, RW, {1});
  limits<int8_t>(
      period.add(ip_period_sub::kIndex, "Interpolation time index", DT::Integer8, RW, i8(-3)), -128,
      63);
}

}  // namespace

bool mode_supported(int8_t m) {
  // The modes the drive runs (node/profiles/cia402/drive.hpp), as 6502h says.
  using namespace mode;
  return m == kNone || m == kProfilePosition || m == kProfileVelocity || m == kHoming ||
         m == kInterpolatedPosition || m == kCyclicSyncPosition || m == kCyclicSyncVelocity;
}

void add_objects(od::Dictionary& od, unsigned axes) {
  for (unsigned a = 0; a < axes && a < kMaxAxes; ++a) {
    add_device_control({od, a});
    add_position_objects({od, a});
    add_profile_objects({od, a});
    add_factor_and_ip_objects({od, a});
  }
}

void set_default_pdos(od::Dictionary& od, unsigned a, unsigned first_rpdo, unsigned first_tpdo) {
  using namespace obj;
  auto word = [a](uint16_t base, uint8_t bits) {
    return od::mapping_word(index(a, base), 0, bits);
  };
  auto rmap = [first_rpdo](unsigned k) { return od::rpdo_mapping(first_rpdo + k); };
  auto tmap = [first_tpdo](unsigned k) { return od::tpdo_mapping(first_tpdo + k); };
  od::set_default_mapping(od, rmap(0), {word(kControlword, 16), word(kModesOfOperation, 8)});
  od::set_default_mapping(od, rmap(1), {word(kTargetPosition, 32), word(kTargetVelocity, 32)});
  od::set_default_mapping(od, tmap(0), {word(kStatusword, 16), word(kModesOfOperationDisplay, 8)});
  od::set_default_mapping(od, tmap(1), {word(kPositionActual, 32), word(kVelocityActual, 32)});
  // Event-driven (transmission type 254, the communication objects' default) like the Horner
  // PDOs: the status on every change, the positions at most every 10 ms while they change
  // (inhibit time, 100 us units).
  Entry& inhibit = od.at(od::tpdo_parameter(first_tpdo + 1), 3);
  inhibit.default_value = inhibit.value = u16(100);
}

}  // namespace stepnode::cia402
