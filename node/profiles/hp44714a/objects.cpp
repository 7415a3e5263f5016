#include "node/profiles/hp44714a/objects.hpp"

#include <string>

#include "od/pdo_mapping.hpp"

namespace stepnode::hp44714a {
namespace {

using DT = od::DataType;
using AC = od::Access;
using od::encode;
using od::Entry;
using od::limits;
using od::Object;

// A command object: acting on it is the point, storing it is not.
Entry& command(Entry& e) {
  e.persistent = false;
  return e;
}

std::string name(unsigned a, const char* what) {
  return "Axis " + std::to_string(a + 1) + " HP " + what;
}

// STANDBY and PULSE (the outputs, 3-25..3-29) and HARDLIM/HALT (the limit inputs).
void add_outputs_and_limits(od::Dictionary& od, unsigned a) {
  using namespace obj;
  Object& out = od.record(index(a, kOutput), name(a, "STANDBY and PULSE"));
  limits<uint8_t>(out.add(output_sub::kStandbyMode, "STANDBY mode (0 OFF, 1 ON, 2 AUTO)",
                          DT::Unsigned8, AC::ReadWrite, {2}),
                  0, 2);
  limits<uint8_t>(out.add(output_sub::kStandbySense, "STANDBY sense (0 LO, 1 HI)", DT::Unsigned8,
                          AC::ReadWrite, {1}),
                  0, 1);
  limits<uint8_t>(
      out.add(output_sub::kPulseMode, "PULSE mode (0 SD, 1 SS)", DT::Unsigned8, AC::ReadWrite, {1}),
      0, 1);
  limits<uint8_t>(out.add(output_sub::kPstpSense, "PSTP sense (0 LO/HL, 1 HI/LH)", DT::Unsigned8,
                          AC::ReadWrite, {0}),
                  0, 1);
  limits<uint8_t>(out.add(output_sub::kNdirSense, "NDIR sense (0 LO/HL, 1 HI/LH)", DT::Unsigned8,
                          AC::ReadWrite, {0}),
                  0, 1);
  out.add(output_sub::kStbyLevel, "STBY output level", DT::Unsigned8, AC::ReadOnly, {1}, true);
  out.add(output_sub::kMotorPowered, "Motor powered", DT::Unsigned8, AC::ReadOnly, {0}, true);
  out.add(output_sub::kPstpPulses, "Pulses on PSTP", DT::Unsigned32, AC::ReadOnly,
          encode<uint32_t>(0), true)
      .pdo_sampled = true;
  out.add(output_sub::kNdirPulses, "Pulses on NDIR", DT::Unsigned32, AC::ReadOnly,
          encode<uint32_t>(0), true)
      .pdo_sampled = true;
  // The width of the pulses at the outputs now (3-25..3-29): pwidth (FREQ) or the ramped width
  // (WIDTH).
  out.add(output_sub::kPulseWidth, "Pulse width now (s)", DT::Real64, AC::ReadOnly,
          encode<double>(0), true)
      .pdo_sampled = true;

  Object& lim = od.record(index(a, kLimits), name(a, "HARDLIM and HALT"));
  limits<uint8_t>(lim.add(limits_sub::kPlimSense, "HARDLIM PLIM sense (0 LO, 1 HI)", DT::Unsigned8,
                          AC::ReadWrite, {0}),
                  0, 1);
  limits<uint8_t>(lim.add(limits_sub::kNlimSense, "HARDLIM NLIM sense (0 LO, 1 HI)", DT::Unsigned8,
                          AC::ReadWrite, {0}),
                  0, 1);
  limits<uint8_t>(lim.add(limits_sub::kHaltMode, "HALT mode (0 LO, 1 HI, 2 OFF)", DT::Unsigned8,
                          AC::ReadWrite, {0}),
                  0, 2);
  limits<uint8_t>(command(lim.add(limits_sub::kHaltSgl, "HALT SGL (write 1)", DT::Unsigned8,
                                  AC::ReadWrite, {0}, true)),
                  0, 1);
}

void add_channel(od::Dictionary& od, unsigned a) {
  using namespace obj;
  // Defaults are the manual's power-on state (3-2).
  Object& prof = od.record(index(a, kProfile), name(a, "PROFILE"));
  limits<uint8_t>(
      prof.add(profile_sub::kMode, "Mode (0 FREQ, 1 WIDTH)", DT::Unsigned8, AC::ReadWrite, {0}), 0,
      1);
  prof.add(profile_sub::kMin, "Min (units/s or s)", DT::Real64, AC::ReadWrite, encode<double>(0));
  prof.add(profile_sub::kMax, "Max (units/s or s)", DT::Real64, AC::ReadWrite, encode<double>(250));
  prof.add(profile_sub::kSlope, "Slope (units/s2 or s/s)", DT::Real64, AC::ReadWrite,
           encode<double>(500));
  prof.add(profile_sub::kLast, "Pulse width or period (s)", DT::Real64, AC::ReadWrite,
           encode<double>(50e-6));
  limits<uint8_t>(
      command(prof.add(profile_sub::kApply, "Apply (write 1)", DT::Unsigned8, AC::ReadWrite, {0})),
      0, 1);
  // FREQ values are in units of the PSCALE in effect when PROFILE is given (3-9): the one the
  // profile in effect was given at, stored with it, so a restart gives it at that PSCALE.
  prof.add(profile_sub::kGivenAtPscale, "PSCALE the profile was given at", DT::Real64, AC::ReadOnly,
           encode<double>(1.0))
      .persistent = true;

  od.var(index(a, kPscale), name(a, "PSCALE units per step"), DT::Real64, AC::ReadWrite,
         encode<double>(1.0));

  Object& mv = od.record(index(a, kMove), name(a, "MOVE"));
  command(mv.add(move_sub::kRelative, "MOVE distance REL", DT::Real64, AC::ReadWrite,
                 encode<double>(0), true));
  command(mv.add(move_sub::kAbsolute, "MOVE position ABS", DT::Real64, AC::ReadWrite,
                 encode<double>(0), true));
  limits<uint8_t>(mv.add(move_sub::kNowait, "NOWAIT (MOVE and SUSTAIN)", DT::Unsigned8,
                         AC::ReadWrite, {0}, true),
                  0, 1);

  command(od.var(index(a, kSustain), name(a, "SUSTAIN velocity or width"), DT::Real64,
                 AC::ReadWrite, encode<double>(0), true));
  limits<uint8_t>(
      command(od.var(index(a, kTrig), name(a, "TRIG (0 HOLD, 1 AUTO, 2 SGL, 3 SYS, 4 CHAN0)"),
                     DT::Unsigned8, AC::ReadWrite, {1}, true)),
      0, 4);
  od.var(index(a, kDelay), name(a, "DELAY ms"), DT::Unsigned16, AC::ReadWrite, encode<uint16_t>(0));

  add_outputs_and_limits(od, a);

  od.var(index(a, kDone), name(a, "DONE?"), DT::Integer8, AC::ReadOnly, {0}, true);
  od.var(index(a, kError), name(a, "error number"), DT::Unsigned8, AC::ReadOnly, {0}, true);
  od.var(index(a, kConflict), name(a, "PROFILE settings conflict"), DT::Unsigned8, AC::ReadOnly,
         {0}, true);
  command(od.var(index(a, kPosition), name(a, "POS / POS?"), DT::Real64, AC::ReadWrite,
                 encode<double>(0), true))
      .pdo_sampled = true;
}

// The quadrature counter, interrupts, timing, TEST and the simulated terminal inputs.
void add_channel_counters(od::Dictionary& od, unsigned a) {
  using namespace obj;
  Object& q = od.record(index(a, kQuadrature), name(a, "quadrature counter"));
  q.add(quad_sub::kQscale, "QSCALE units per count", DT::Real64, AC::ReadWrite,
        encode<double>(1.0));
  limits<uint8_t>(command(q.add(quad_sub::kQindex, "QINDEX (0 OFF, 1 ONCE, 2 SGL)", DT::Unsigned8,
                                AC::ReadWrite, {0})),
                  0, 2);
  q.add(quad_sub::kQpos, "QPOS?", DT::Real64, AC::ReadOnly, encode<double>(0));
  q.add(quad_sub::kCount, "Quadrature count", DT::Integer32, AC::ReadOnly, encode<int32_t>(0), true)
      .pdo_sampled = true;

  Object& in = od.record(index(a, kInterrupt), name(a, "interrupts"));
  limits<uint8_t>(command(in.add(intr_sub::kEnable, "ENABLE INTR (1) / DISABLE INTR (0)",
                                 DT::Unsigned8, AC::ReadWrite, {0}, true)),
                  0, 1);
  in.add(
      intr_sub::kEvents,
      "Interrupt event (1 move done, 2 sustain reached, 4 hard limit, 8 HALT SGL, 16 HALT switch)",
      DT::Unsigned8, AC::ReadOnly, {0}, true);

  Object& t = od.record(index(a, kTiming), name(a, "timing"));
  t.add(timing_sub::kTriggerUs, "Last trigger (node clock us, low 32 bits)", DT::Unsigned32,
        AC::ReadOnly, encode<uint32_t>(0), true);
  t.add(timing_sub::kFirstStepUs, "First step of the last move (node clock us, low 32 bits)",
        DT::Unsigned32, AC::ReadOnly, encode<uint32_t>(0), true);
  t.add(timing_sub::kFirstStepAfterTriggerUs, "First step after the trigger (us, -1 none yet)",
        DT::Integer32, AC::ReadOnly, encode<int32_t>(-1), true);

  // TEST (Command Summary 4-3): a pass/fail self test; the answer of the last one.
  Object& test = od.record(index(a, kTest), name(a, "TEST"));
  limits<uint8_t>(
      command(test.add(test_sub::kRun, "TEST (write 1)", DT::Unsigned8, AC::ReadWrite, {0})), 0, 1);
  test.add(test_sub::kResult, "TEST result (0 passed, 1 failed)", DT::Unsigned8, AC::ReadOnly, {0},
           true);
  test.add(test_sub::kFailedChecks,
           "TEST failed checks (1 outputs, 2 pulse engine, 4 position counter, 8 PROFILE rules)",
           DT::Unsigned8, AC::ReadOnly, {0}, true);

  Object& sim =
      od.record(sim_index(a), "Simulated axis " + std::to_string(a + 1) + " HP terminal inputs");
  limits<uint8_t>(command(sim.add(sim_sub::kHaltInputHigh, "HALT input level (1 high: switch open)",
                                  DT::Unsigned8, AC::ReadWrite, {1})),
                  0, 1);
  limits<uint8_t>(
      command(sim.add(sim_sub::kTestJumper, "TEST jumper set", DT::Unsigned8, AC::ReadWrite, {0})),
      0, 1);
  // What the simulated drive received: the width of the last pulse (0: a step without one).
  sim.add(sim_sub::kLastPulseWidthNs, "Width of the last pulse received (ns)", DT::Unsigned32,
          AC::ReadOnly, encode<uint32_t>(0), true)
      .pdo_sampled = true;
}

// TPDO 4n+4: DONE?, the error number and the interrupt event word (24 bits), on change.
void map_tpdo(od::Dictionary& od, unsigned a) {
  od::set_default_mapping(od, od::tpdo_mapping(4 * a + 3),
                          {od::mapping_word(obj::index(a, obj::kDone), 0, 8),
                           od::mapping_word(obj::index(a, obj::kError), 0, 8),
                           od::mapping_word(obj::index(a, obj::kInterrupt), intr_sub::kEvents, 8)});
}

}  // namespace

void add_objects(od::Dictionary& od, unsigned axes) {
  for (unsigned a = 0; a < axes; ++a) {
    add_channel(od, a);
    add_channel_counters(od, a);
    map_tpdo(od, a);
  }
}

const char* emcy_text(uint16_t code) {
  switch (code) {
    // Interrupts for halts and limits, and the error numbers of the manual's Error Message Summary
    // (3-3).
    case 0xFF43: return "HP interrupt: a hard limit stopped pulses";
    case 0xFF44: return "HP interrupt: HALT SGL stopped pulses";
    case 0xFF45: return "HP interrupt: the HALT switch stopped pulses";
    case 0xFF59: return "HP error 89 ACCESSORY BUSY";
    case 0xFF5A: return "HP error 90 NO ACTION DEFINED";
    case 0xFF5B: return "HP error 91 MUST STOP TO CHANGE DIRECTION";
    case 0xFF5C: return "HP error 92 NOT VALID IN WIDTH MODE";
    case 0xFF5D: return "HP error 93 TERMINAL CARD TEST JUMPER SET";
    case 0xFF5E: return "HP error 94 CANNOT MOVE WHILE STANDBY ON";
    default: return nullptr;
  }
}

}  // namespace stepnode::hp44714a
