#include "od/hp_objects.hpp"

#include <string>

namespace stepnode::od {
namespace {

using DT = DataType;
using AC = Access;

// A command object: acting on it is the point, storing it is not.
Entry& command(Entry& e) {
  e.persistent = false;
  return e;
}

std::string name(unsigned a, const char* what) { return "Axis " + std::to_string(a + 1) + " HP " + what; }

void add_channel(Dictionary& od, unsigned a) {
  using namespace hp_obj;
  // Defaults are the manual's power-on state (3-2).
  Object& prof = od.record(index(a, kProfile), name(a, "PROFILE"));
  limits<uint8_t>(prof.add(hp_profile_sub::kMode, "Mode (0 FREQ, 1 WIDTH)", DT::Unsigned8, AC::ReadWrite, {0}), 0, 1);
  prof.add(hp_profile_sub::kMin, "Min (units/s or s)", DT::Real64, AC::ReadWrite, encode<double>(0));
  prof.add(hp_profile_sub::kMax, "Max (units/s or s)", DT::Real64, AC::ReadWrite, encode<double>(250));
  prof.add(hp_profile_sub::kSlope, "Slope (units/s2 or s/s)", DT::Real64, AC::ReadWrite, encode<double>(500));
  prof.add(hp_profile_sub::kLast, "Pulse width or period (s)", DT::Real64, AC::ReadWrite, encode<double>(50e-6));
  limits<uint8_t>(command(prof.add(hp_profile_sub::kApply, "Apply (write 1)", DT::Unsigned8, AC::ReadWrite, {0})), 0, 1);

  od.var(index(a, kPscale), name(a, "PSCALE units per step"), DT::Real64, AC::ReadWrite, encode<double>(1.0));

  Object& mv = od.record(index(a, kMove), name(a, "MOVE"));
  command(mv.add(hp_move_sub::kRelative, "MOVE distance REL", DT::Real64, AC::ReadWrite, encode<double>(0), true));
  command(mv.add(hp_move_sub::kAbsolute, "MOVE position ABS", DT::Real64, AC::ReadWrite, encode<double>(0), true));
  limits<uint8_t>(mv.add(hp_move_sub::kNowait, "NOWAIT (MOVE and SUSTAIN)", DT::Unsigned8, AC::ReadWrite, {0}, true), 0, 1);

  command(od.var(index(a, kSustain), name(a, "SUSTAIN velocity or width"), DT::Real64, AC::ReadWrite,
                 encode<double>(0), true));
  limits<uint8_t>(command(od.var(index(a, kTrig), name(a, "TRIG (0 HOLD, 1 AUTO, 2 SGL, 3 SYS, 4 CHAN0)"),
                                 DT::Unsigned8, AC::ReadWrite, {1}, true)), 0, 4);
  od.var(index(a, kDelay), name(a, "DELAY ms"), DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(0));

  Object& out = od.record(index(a, kOutput), name(a, "STANDBY and PULSE"));
  limits<uint8_t>(out.add(hp_output_sub::kStandbyMode, "STANDBY mode (0 OFF, 1 ON, 2 AUTO)", DT::Unsigned8,
                          AC::ReadWrite, {2}), 0, 2);
  limits<uint8_t>(out.add(hp_output_sub::kStandbySense, "STANDBY sense (0 LO, 1 HI)", DT::Unsigned8, AC::ReadWrite, {1}), 0, 1);
  limits<uint8_t>(out.add(hp_output_sub::kPulseMode, "PULSE mode (0 SD, 1 SS)", DT::Unsigned8, AC::ReadWrite, {1}), 0, 1);
  limits<uint8_t>(out.add(hp_output_sub::kPstpSense, "PSTP sense (0 LO/HL, 1 HI/LH)", DT::Unsigned8, AC::ReadWrite, {0}), 0, 1);
  limits<uint8_t>(out.add(hp_output_sub::kNdirSense, "NDIR sense (0 LO/HL, 1 HI/LH)", DT::Unsigned8, AC::ReadWrite, {0}), 0, 1);
  out.add(hp_output_sub::kStbyLevel, "STBY output level", DT::Unsigned8, AC::ReadOnly, {1}, true);
  out.add(hp_output_sub::kMotorPowered, "Motor powered", DT::Unsigned8, AC::ReadOnly, {0}, true);
  out.add(hp_output_sub::kPstpPulses, "Pulses on PSTP", DT::Unsigned32, AC::ReadOnly, encode<uint32_t>(0), true)
      .pdo_sampled = true;
  out.add(hp_output_sub::kNdirPulses, "Pulses on NDIR", DT::Unsigned32, AC::ReadOnly, encode<uint32_t>(0), true)
      .pdo_sampled = true;

  Object& lim = od.record(index(a, kLimits), name(a, "HARDLIM and HALT"));
  limits<uint8_t>(lim.add(hp_limits_sub::kPlimSense, "HARDLIM PLIM sense (0 LO, 1 HI)", DT::Unsigned8, AC::ReadWrite, {0}), 0, 1);
  limits<uint8_t>(lim.add(hp_limits_sub::kNlimSense, "HARDLIM NLIM sense (0 LO, 1 HI)", DT::Unsigned8, AC::ReadWrite, {0}), 0, 1);
  limits<uint8_t>(lim.add(hp_limits_sub::kHaltMode, "HALT mode (0 LO, 1 HI, 2 OFF)", DT::Unsigned8, AC::ReadWrite, {0}), 0, 2);
  limits<uint8_t>(command(lim.add(hp_limits_sub::kHaltSgl, "HALT SGL (write 1)", DT::Unsigned8, AC::ReadWrite, {0}, true)), 0, 1);

  od.var(index(a, kDone), name(a, "DONE?"), DT::Integer8, AC::ReadOnly, {0}, true);
  od.var(index(a, kError), name(a, "error number"), DT::Unsigned8, AC::ReadOnly, {0}, true);
  od.var(index(a, kConflict), name(a, "PROFILE settings conflict"), DT::Unsigned8, AC::ReadOnly, {0}, true);
  command(od.var(index(a, kPosition), name(a, "POS / POS?"), DT::Real64, AC::ReadWrite, encode<double>(0), true))
      .pdo_sampled = true;

  Object& q = od.record(index(a, kQuadrature), name(a, "quadrature counter"));
  q.add(hp_quad_sub::kQscale, "QSCALE units per count", DT::Real64, AC::ReadWrite, encode<double>(1.0));
  limits<uint8_t>(command(q.add(hp_quad_sub::kQindex, "QINDEX (0 OFF, 1 ONCE, 2 SGL)", DT::Unsigned8, AC::ReadWrite, {0})), 0, 2);
  q.add(hp_quad_sub::kQpos, "QPOS?", DT::Real64, AC::ReadOnly, encode<double>(0));
  q.add(hp_quad_sub::kCount, "Quadrature count", DT::Integer32, AC::ReadOnly, encode<int32_t>(0), true).pdo_sampled = true;

  Object& in = od.record(index(a, kInterrupt), name(a, "interrupts"));
  limits<uint8_t>(command(in.add(hp_intr_sub::kEnable, "ENABLE INTR (1) / DISABLE INTR (0)", DT::Unsigned8,
                                 AC::ReadWrite, {0}, true)), 0, 1);
  in.add(hp_intr_sub::kEvents, "Interrupt event (1 move done, 2 sustain reached, 4 hard limit, 8 HALT SGL, 16 HALT switch)",
         DT::Unsigned8, AC::ReadOnly, {0}, true);

  Object& t = od.record(index(a, kTiming), name(a, "timing"));
  t.add(hp_timing_sub::kTriggerUs, "Last trigger (node clock us, low 32 bits)", DT::Unsigned32, AC::ReadOnly,
        encode<uint32_t>(0), true);
  t.add(hp_timing_sub::kFirstStepUs, "First step of the last move (node clock us, low 32 bits)", DT::Unsigned32,
        AC::ReadOnly, encode<uint32_t>(0), true);
  t.add(hp_timing_sub::kFirstStepAfterTriggerUs, "First step after the trigger (us, -1 none yet)", DT::Integer32,
        AC::ReadOnly, encode<int32_t>(-1), true);

  Object& sim = od.record(sim_index(a), "Simulated axis " + std::to_string(a + 1) + " HP terminal inputs");
  limits<uint8_t>(command(sim.add(hp_sim_sub::kHaltInputHigh, "HALT input level (1 high: switch open)", DT::Unsigned8,
                                  AC::ReadWrite, {1})), 0, 1);
  limits<uint8_t>(command(sim.add(hp_sim_sub::kTestJumper, "TEST jumper set", DT::Unsigned8, AC::ReadWrite, {0})), 0, 1);
}

// TPDO 4n+4: DONE?, the error number and the interrupt event word (24 bits), on change.
void map_tpdo(Dictionary& od, unsigned a) {
  uint16_t map = static_cast<uint16_t>(0x1A00 + 4 * a + 3);
  auto word = [](uint16_t index, uint8_t sub, uint8_t bits) {
    return (static_cast<uint32_t>(index) << 16) | (static_cast<uint32_t>(sub) << 8) | bits;
  };
  uint32_t words[] = {word(hp_obj::index(a, hp_obj::kDone), 0, 8), word(hp_obj::index(a, hp_obj::kError), 0, 8),
                      word(hp_obj::index(a, hp_obj::kInterrupt), hp_intr_sub::kEvents, 8)};
  uint8_t n = 0;
  for (uint32_t w : words) {
    Entry& e = od.at(map, ++n);
    e.default_value = e.value = encode<uint32_t>(w);
  }
  Entry& count = od.at(map, 0);
  count.default_value = count.value = {n};
}

}  // namespace

void add_hp_objects(Dictionary& od, const DeviceInfo& info) {
  for (unsigned a = 0; a < info.axes; ++a) {
    add_channel(od, a);
    map_tpdo(od, a);
  }
}

}  // namespace stepnode::od
