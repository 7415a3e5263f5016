// The CiA 402 PDS FSA (node/profiles/cia402/drive_state.*) against the standard's tables,
// written here as the standard prints them: the controlword command coding (6040h, bits 7
// and 3..0), the statusword state coding (6041h), the transitions 0..16 (CiA 402-2 Table 26)
// and the option codes 605Ah..605Eh and 6007h.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "node/profiles/cia402/drive_state.hpp"

namespace stepnode::cia402 {
namespace {

// A bit pattern as the standard writes it, most significant bit first ("0xxx x110", spaces
// ignored): the bits given and their values.
struct Pattern {
  uint16_t mask = 0, value = 0;
  bool matches(uint16_t word) const { return (word & mask) == value; }
};
Pattern pattern(const std::string& text) {
  Pattern p;
  int bit = 0;
  for (auto c = text.rbegin(); c != text.rend(); ++c) {
    if (*c == ' ') continue;
    if (*c != 'x') p.mask = static_cast<uint16_t>(p.mask | (1u << bit));
    if (*c == '1') p.value = static_cast<uint16_t>(p.value | (1u << bit));
    ++bit;
  }
  return p;
}

// The controlwords of the command coding table with every open bit 0.
constexpr uint16_t kShutdown = 0x0006, kSwitchOn = 0x0007, kEnable = 0x000F,
                   kDisableVoltage = 0x0000, kQuickStop = 0x0002, kFaultReset = 0x0080;

// ---- controlword: the command coding table ----------------------------------------------

struct CommandRow {
  Command command;
  const char* bits;  // bits 7, 3, 2, 1, 0
};
// Bit 7 must be 0 for every row but the fault reset (its rising edge, tested below).
const std::vector<CommandRow> kCommandTable = {
    {Command::Shutdown, "0x110"},          {Command::SwitchOn, "00111"},
    {Command::SwitchOnAndEnable, "01111"}, {Command::DisableVoltage, "0xx0x"},
    {Command::QuickStop, "0x01x"},         {Command::DisableOperation, "00111"},
    {Command::EnableOperation, "01111"},
};

// The low byte of a controlword as bits 7, 3, 2, 1, 0.
uint16_t table_bits(uint16_t cw) { return static_cast<uint16_t>(((cw >> 3) & 0x10) | (cw & 0x0F)); }

TEST(ControlwordDecode, EveryControlwordIsExactlyTheRowsItMatches) {
  for (uint16_t cw = 0; cw < 0x80; ++cw) {  // bits 4-6 (mode-specific) take every value too
    std::vector<Command> rows;
    for (const CommandRow& row : kCommandTable)
      if (pattern(row.bits).matches(table_bits(cw))) rows.push_back(row.command);
    const Command decoded = decode(cw, 0);
    if (rows.size() == 1) {
      EXPECT_EQ(decoded, rows[0]) << "cw " << cw;
    } else {  // the two shared codes: switch on / disable operation, switch on + enable / enable
      ASSERT_EQ(rows.size(), 2u) << "cw " << cw;
      EXPECT_EQ(decoded,
                rows[0] == Command::SwitchOn ? Command::SwitchOn : Command::SwitchOnAndEnable)
          << cw;
      EXPECT_EQ(rows[1], rows[0] == Command::SwitchOn ? Command::DisableOperation
                                                      : Command::EnableOperation);
    }
  }
}

TEST(ControlwordDecode, TheStateDecidesTheSharedCodes) {
  EXPECT_EQ(decode(kSwitchOn, 0, State::ReadyToSwitchOn), Command::SwitchOn);
  EXPECT_EQ(decode(kSwitchOn, 0, State::OperationEnabled), Command::DisableOperation);
  EXPECT_EQ(decode(kEnable, 0, State::ReadyToSwitchOn), Command::SwitchOnAndEnable);
  for (State s : {State::SwitchedOn, State::OperationEnabled, State::QuickStopActive})
    EXPECT_EQ(decode(kEnable, 0, s), Command::EnableOperation) << name(s);
  EXPECT_EQ(decode(0x0076, 0, State::OperationEnabled),
            Command::Shutdown);  // bits 4-6 do not count
}

TEST(ControlwordDecode, FaultResetIsTheRisingEdgeOfBit7Only) {
  for (uint16_t low = 0; low < 0x80; ++low) {
    const auto cw = static_cast<uint16_t>(low | kFaultReset);
    EXPECT_EQ(decode(cw, low), Command::FaultReset) << cw;  // 0 -> 1, bits 3..0 whatever
    EXPECT_EQ(decode(cw, cw), Command::None) << cw;         // held at 1: no row matches
  }
  EXPECT_EQ(decode(kShutdown, kFaultReset), Command::Shutdown);  // 1 -> 0: an ordinary command
}

// ---- statusword: the state coding table ---------------------------------------------------

struct StateRow {
  State state;
  const char* bits;      // 6041h bits 7..0
  bool voltage_enabled;  // bit 4: this drive's choice, the motor powered
};
const std::vector<StateRow> kStateTable = {
    {State::NotReadyToSwitchOn, "x0xx 0000", false}, {State::SwitchOnDisabled, "x1xx 0000", false},
    {State::ReadyToSwitchOn, "x01x 0001", false},    {State::SwitchedOn, "x01x 0011", true},
    {State::OperationEnabled, "x01x 0111", true},    {State::QuickStopActive, "x00x 0111", true},
    {State::FaultReactionActive, "x0xx 1111", true}, {State::Fault, "x0xx 1000", false},
};

TEST(StatuswordBits, EachStateAsTheTable) {
  for (const StateRow& row : kStateTable) {
    const uint16_t bits = state_bits(row.state);
    EXPECT_TRUE(pattern(row.bits).matches(bits)) << name(row.state) << " " << bits;
    EXPECT_EQ((bits & sw::kVoltageEnabled) != 0, row.voltage_enabled) << name(row.state);
    EXPECT_EQ(powered(row.state), row.voltage_enabled) << name(row.state);
    EXPECT_NE(bits & sw::kRemote, 0) << name(row.state);      // bit 9: the controlword is processed
    EXPECT_EQ(bits & ~sw::kOwnedBits, 0) << name(row.state);  // 7, 8, 10-15 are the caller's
    // Every other state's pattern excludes this one: the coding is unambiguous.
    for (const StateRow& other : kStateTable) {
      if (other.state == row.state) continue;
      EXPECT_FALSE(pattern(other.bits).matches(bits)) << name(other.state);
    }
  }
}

// ---- transitions 0..16 ------------------------------------------------------------------

class Transition : public ::testing::Test {
 protected:
  // Brings the machine to `state` the way a master does (transitions 1, 2, 3, 4).
  void go(State state) {
    m.power_on();
    if (state == State::SwitchOnDisabled) return;
    m.on_controlword(kShutdown);
    if (state == State::ReadyToSwitchOn) return;
    m.on_controlword(kSwitchOn);
    if (state == State::SwitchedOn) return;
    m.on_controlword(kEnable);
    ASSERT_EQ(m.state(), State::OperationEnabled);
  }
  void expect(State state, int transition) {
    EXPECT_EQ(m.state(), state) << name(m.state());
    EXPECT_EQ(m.last_transition(), transition);
    EXPECT_EQ(m.statusword(), state_bits(state));
  }
  DriveStateMachine m;
};

TEST_F(Transition, T00_StartIntoNotReadyToSwitchOn) {
  expect(State::NotReadyToSwitchOn, 0);
  EXPECT_EQ(m.on_controlword(kShutdown),
            Stop::None);  // no command leaves it: transition 1 is automatic
  expect(State::NotReadyToSwitchOn, 0);
}

TEST_F(Transition, T01_InitialisedIntoSwitchOnDisabled) {
  m.power_on();
  expect(State::SwitchOnDisabled, 1);
  EXPECT_FALSE(m.powered());
  for (uint16_t cw : {kSwitchOn, kEnable}) m.on_controlword(cw);  // Shutdown comes first
  expect(State::SwitchOnDisabled, 1);
}

TEST_F(Transition, T02_ShutdownIntoReadyToSwitchOn) {
  go(State::SwitchOnDisabled);
  EXPECT_EQ(m.on_controlword(kShutdown), Stop::None);
  expect(State::ReadyToSwitchOn, 2);
  EXPECT_FALSE(m.powered());
}

TEST_F(Transition, T03_SwitchOnIntoSwitchedOn) {
  go(State::ReadyToSwitchOn);
  EXPECT_EQ(m.on_controlword(kSwitchOn), Stop::None);
  expect(State::SwitchedOn, 3);
  EXPECT_TRUE(m.powered());
  EXPECT_FALSE(m.operation_enabled());
}

TEST_F(Transition, T03And04_SwitchOnAndEnableFromReadyToSwitchOn) {
  go(State::ReadyToSwitchOn);
  m.on_controlword(kEnable);
  expect(State::OperationEnabled, 4);
}

TEST_F(Transition, T04_EnableOperationIntoOperationEnabled) {
  go(State::SwitchedOn);
  EXPECT_EQ(m.on_controlword(kEnable), Stop::None);
  expect(State::OperationEnabled, 4);
  EXPECT_TRUE(m.operation_enabled());
}

TEST_F(Transition, T05_DisableOperationAfterTheSlowDownRamp) {
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kSwitchOn), Stop::SlowDownRamp);  // 605Ch default 1
  expect(State::OperationEnabled, 4);  // the statusword stays until the ramp has ended
  EXPECT_FALSE(m.operation_enabled());
  m.motion_stopped();
  expect(State::SwitchedOn, 5);
  EXPECT_TRUE(m.powered());
}

TEST_F(Transition, T06_ShutdownFromSwitchedOn) {
  go(State::SwitchedOn);
  EXPECT_EQ(m.on_controlword(kShutdown), Stop::None);
  expect(State::ReadyToSwitchOn, 6);
  EXPECT_FALSE(m.powered());
}

TEST_F(Transition, T07_DisableVoltageOrQuickStopFromReadyToSwitchOn) {
  for (uint16_t cw : {kDisableVoltage, kQuickStop}) {
    go(State::ReadyToSwitchOn);
    EXPECT_EQ(m.on_controlword(cw), Stop::None);
    expect(State::SwitchOnDisabled, 7);
  }
}

TEST_F(Transition, T08_ShutdownFromOperationEnabled) {
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kShutdown), Stop::DisableDrive);  // 605Bh default 0: at once
  expect(State::ReadyToSwitchOn, 8);
  EXPECT_FALSE(m.powered());
}

TEST_F(Transition, T09_DisableVoltageFromOperationEnabled) {
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kDisableVoltage), Stop::DisableDrive);
  expect(State::SwitchOnDisabled, 9);
  EXPECT_FALSE(m.powered());
}

TEST_F(Transition, T10_DisableVoltageOrQuickStopFromSwitchedOn) {
  for (uint16_t cw : {kDisableVoltage, kQuickStop}) {
    go(State::SwitchedOn);
    EXPECT_EQ(m.on_controlword(cw), Stop::None);
    expect(State::SwitchOnDisabled, 10);
    EXPECT_FALSE(m.powered());
  }
}

TEST_F(Transition, T11_QuickStopFromOperationEnabled) {
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kQuickStop), Stop::QuickStopRamp);  // 605Ah default 2
  expect(State::QuickStopActive, 11);
  EXPECT_TRUE(m.powered());
  EXPECT_FALSE(m.operation_enabled());
}

TEST_F(Transition, T12_QuickStopCompletedOrDisableVoltage) {
  go(State::OperationEnabled);
  m.on_controlword(kQuickStop);
  m.motion_stopped();  // 605Ah 1..4: automatic once the quick stop is completed
  expect(State::SwitchOnDisabled, 12);
  go(State::OperationEnabled);
  m.on_controlword(kQuickStop);
  EXPECT_EQ(m.on_controlword(kDisableVoltage), Stop::DisableDrive);  // cuts the ramp short
  expect(State::SwitchOnDisabled, 12);
  EXPECT_FALSE(m.stopping());
}

TEST_F(Transition, T13_FaultIntoFaultReactionActive) {
  go(State::OperationEnabled);
  EXPECT_EQ(m.fault(0x8611), Stop::QuickStopRamp);  // 605Eh default 2
  expect(State::FaultReactionActive, 13);
  EXPECT_EQ(m.error_code(), 0x8611);
  EXPECT_TRUE(m.powered());
}

TEST_F(Transition, T14_FaultReactionCompletedIntoFault) {
  go(State::OperationEnabled);
  m.fault(0x8611);
  m.motion_stopped();
  expect(State::Fault, 14);
  EXPECT_FALSE(m.powered());
  // Where nothing moves the reaction is complete at once: 13 then 14 in the call.
  for (State s : {State::SwitchOnDisabled, State::ReadyToSwitchOn, State::SwitchedOn}) {
    go(s);
    EXPECT_EQ(m.fault(0x5000), Stop::None) << name(s);
    expect(State::Fault, 14);
  }
}

TEST_F(Transition, T15_FaultResetIntoSwitchOnDisabled) {
  go(State::SwitchedOn);
  m.fault(0x8611);
  EXPECT_EQ(m.on_controlword(kFaultReset), Stop::None);
  expect(State::SwitchOnDisabled, 15);
  EXPECT_EQ(m.error_code(), 0);
}

TEST_F(Transition, T16_EnableOperationFromQuickStopActive) {
  m.set_options({.quick_stop = 6});
  go(State::OperationEnabled);
  m.on_controlword(kQuickStop);
  m.motion_stopped();
  expect(State::QuickStopActive, 11);  // 605Ah 6: stays after the ramp
  EXPECT_EQ(m.on_controlword(kEnable), Stop::None);
  expect(State::OperationEnabled, 16);
  EXPECT_TRUE(m.operation_enabled());
}

// ---- option codes -----------------------------------------------------------------------

struct QuickStopRow {
  int16_t option;
  Stop stop;
  bool stays;  // 5..8: Quick stop active after the ramp, transition 16 possible
};
// 605Ah: 0 disable drive function; 1/5 slow-down ramp, 2/6 quick stop ramp, 3/7 current
// limit, 4/8 voltage limit; 1..4 then Switch on disabled, 5..8 stay in Quick stop active.
const std::vector<QuickStopRow> kQuickStopTable = {
    {0, Stop::DisableDrive, false}, {1, Stop::SlowDownRamp, false}, {2, Stop::QuickStopRamp, false},
    {3, Stop::Immediate, false},    {4, Stop::Immediate, false},    {5, Stop::SlowDownRamp, true},
    {6, Stop::QuickStopRamp, true}, {7, Stop::Immediate, true},     {8, Stop::Immediate, true},
};

TEST_F(Transition, QuickStopOptionCodes0To8) {
  for (const QuickStopRow& row : kQuickStopTable) {
    SCOPED_TRACE("605Ah = " + std::to_string(row.option));
    m.set_options({.quick_stop = row.option});
    go(State::OperationEnabled);
    EXPECT_EQ(m.on_controlword(kQuickStop), row.stop);
    if (row.stop == Stop::DisableDrive) {  // nothing to wait for: 11 then 12 in the call
      expect(State::SwitchOnDisabled, 12);
      continue;
    }
    expect(State::QuickStopActive, 11);  // during the ramp
    EXPECT_EQ(m.statusword() & sw::kQuickStop, 0);
    EXPECT_EQ(m.pending_stop(), row.stop);
    m.motion_stopped();
    if (row.stays) {
      expect(State::QuickStopActive, 11);
      m.on_controlword(kEnable);
      expect(State::OperationEnabled, 16);
    } else {
      expect(State::SwitchOnDisabled, 12);
    }
  }
}

TEST_F(Transition, NoTransition16WithQuickStopOptions1To4) {
  go(State::OperationEnabled);
  m.on_controlword(kQuickStop);  // 605Ah 2
  EXPECT_EQ(m.on_controlword(kEnable), Stop::None);
  expect(State::QuickStopActive, 11);
  EXPECT_TRUE(m.stopping());  // the ramp goes on to Switch on disabled
  m.motion_stopped();
  expect(State::SwitchOnDisabled, 12);
}

TEST_F(Transition, ShutdownOptionCodes) {  // 605Bh: transition 8
  m.set_options({.shutdown = 1});
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kShutdown), Stop::SlowDownRamp);
  expect(State::OperationEnabled, 4);  // slow down, then disable the drive function
  m.motion_stopped();
  expect(State::ReadyToSwitchOn, 8);
  m.set_options({.shutdown = 0});
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kShutdown), Stop::DisableDrive);
  expect(State::ReadyToSwitchOn, 8);
}

TEST_F(Transition, DisableOperationOptionCodes) {  // 605Ch: transition 5
  m.set_options({.disable_operation = 0});
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kSwitchOn), Stop::DisableDrive);
  expect(State::SwitchedOn, 5);
  EXPECT_TRUE(m.powered());  // Switched on keeps the power section on
  m.set_options({.disable_operation = 1});
  go(State::OperationEnabled);
  EXPECT_EQ(m.on_controlword(kSwitchOn), Stop::SlowDownRamp);
  expect(State::OperationEnabled, 4);
  m.motion_stopped();
  expect(State::SwitchedOn, 5);
}

TEST_F(Transition, CommandsDuringASlowDownRamp) {
  go(State::OperationEnabled);
  m.on_controlword(kSwitchOn);                         // 605Ch 1: transition 5 waits
  EXPECT_EQ(m.on_controlword(kSwitchOn), Stop::None);  // the same command: no change
  EXPECT_EQ(m.on_controlword(kEnable), Stop::None);    // enable again: called off
  EXPECT_TRUE(m.operation_enabled());
  m.motion_stopped();
  expect(State::OperationEnabled, 4);
  m.on_controlword(kSwitchOn);
  EXPECT_EQ(m.on_controlword(kQuickStop), Stop::QuickStopRamp);  // replaces it: transition 11
  expect(State::QuickStopActive, 11);
  go(State::OperationEnabled);
  m.on_controlword(kSwitchOn);
  EXPECT_EQ(m.on_controlword(kDisableVoltage), Stop::DisableDrive);  // transition 9 at once
  expect(State::SwitchOnDisabled, 9);
}

TEST_F(Transition, FaultReactionOptionCodes) {  // 605Eh: transitions 13 and 14
  const Stop stops[] = {Stop::DisableDrive, Stop::SlowDownRamp, Stop::QuickStopRamp,
                        Stop::Immediate, Stop::Immediate};
  for (int16_t option = 0; option <= 4; ++option) {
    SCOPED_TRACE("605Eh = " + std::to_string(option));
    m.set_options({.fault_reaction = option});
    go(State::OperationEnabled);
    EXPECT_EQ(m.fault(0x2310), stops[option]);
    if (option == 0) {  // the motor is free to rotate at once
      expect(State::Fault, 14);
      continue;
    }
    expect(State::FaultReactionActive, 13);
    m.on_controlword(kDisableVoltage);  // no command leaves Fault reaction active
    expect(State::FaultReactionActive, 13);
    m.motion_stopped();
    expect(State::Fault, 14);
  }
}

TEST_F(Transition, FaultDuringAQuickStopReplacesItsRamp) {
  go(State::OperationEnabled);
  m.on_controlword(kQuickStop);
  EXPECT_EQ(m.fault(0x2310), Stop::QuickStopRamp);
  m.motion_stopped();
  expect(State::Fault, 14);
}

TEST_F(Transition, ANewFaultInFaultOnlyRecordsItsCode) {
  go(State::OperationEnabled);
  m.fault(0x2310);
  EXPECT_EQ(m.fault(0x4310), Stop::None);  // in Fault reaction active
  expect(State::FaultReactionActive, 13);
  m.motion_stopped();
  EXPECT_EQ(m.fault(0x5000), Stop::None);  // in Fault
  expect(State::Fault, 14);
  EXPECT_EQ(m.error_code(), 0x5000);  // 603Fh: the last error
}

TEST_F(Transition, FaultResetOnTheRisingEdgeOnly) {
  go(State::SwitchedOn);
  m.on_controlword(kSwitchOn | kFaultReset);  // bit 7 already high when the fault comes
  m.fault(0x8611);
  m.on_controlword(kSwitchOn | kFaultReset);  // held: no edge
  expect(State::Fault, 14);
  m.on_controlword(kSwitchOn);
  expect(State::Fault, 14);                   // falling edge: nothing
  m.on_controlword(kSwitchOn | kFaultReset);  // rising edge
  expect(State::SwitchOnDisabled, 15);
}

TEST_F(Transition, AFaultResetWhileTheCausePersistsIsRefused) {
  go(State::OperationEnabled);
  m.set_fault_condition_active(true);
  m.fault(0x8611);
  m.motion_stopped();
  m.on_controlword(kFaultReset);
  expect(State::Fault, 14);
  EXPECT_EQ(m.error_code(), 0x8611);
  m.on_controlword(0);
  m.set_fault_condition_active(false);  // the cause has gone
  m.on_controlword(kFaultReset);
  expect(State::SwitchOnDisabled, 15);
  EXPECT_EQ(m.error_code(), 0);
}

TEST(HaltOptionCodes, Map605DToAStop) {  // 605Dh: 1 slow-down, 2 quick stop, 3/4 limits
  EXPECT_EQ(DriveStateMachine().halt_stop(), Stop::SlowDownRamp);  // default 1
  const Stop stops[] = {Stop::SlowDownRamp, Stop::QuickStopRamp, Stop::Immediate, Stop::Immediate};
  for (int16_t option = 1; option <= 4; ++option)
    EXPECT_EQ(DriveStateMachine({.halt = option}).halt_stop(), stops[option - 1]) << option;
}

TEST(OptionDefaults, AreTheStandards) {
  const Options o;
  EXPECT_EQ(o.quick_stop, 2);
  EXPECT_EQ(o.shutdown, 0);
  EXPECT_EQ(o.disable_operation, 1);
  EXPECT_EQ(o.halt, 1);
  EXPECT_EQ(o.fault_reaction, 2);
}

TEST_F(Transition, AbortConnectionOptionCodes) {  // 6007h
  go(State::OperationEnabled);
  EXPECT_EQ(m.abort_connection(0), Stop::None);  // no action
  expect(State::OperationEnabled, 4);
  EXPECT_EQ(m.abort_connection(1), Stop::QuickStopRamp);  // fault signal, 605Eh 2
  expect(State::FaultReactionActive, 13);
  EXPECT_EQ(m.error_code(), kConnectionLostError);
  go(State::OperationEnabled);
  EXPECT_EQ(m.abort_connection(2), Stop::DisableDrive);  // disable voltage command
  expect(State::SwitchOnDisabled, 9);
  go(State::OperationEnabled);
  EXPECT_EQ(m.abort_connection(3), Stop::QuickStopRamp);  // quick stop command
  expect(State::QuickStopActive, 11);
  go(State::SwitchedOn);
  m.abort_connection(3);
  expect(State::SwitchOnDisabled, 10);
}

TEST_F(Transition, PowerOnAgainStartsOver) {
  go(State::OperationEnabled);
  m.fault(0x2310);
  m.power_on();
  expect(State::SwitchOnDisabled, 1);
  EXPECT_EQ(m.error_code(), 0);
  EXPECT_FALSE(m.stopping());
}

}  // namespace
}  // namespace stepnode::cia402
