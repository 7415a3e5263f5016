// stepctl drive: the statusword in words and the controlword steps (tools/stepctl/
// drive_words.*) against CiA 402-2 / IEC 61800-7-201 as the standard prints it: the
// statusword state coding table (6041h), the controlword command coding table (6040h) and
// the transitions of the power drive system state machine (Table 26), written out here as
// a small model drive that the steps must lead through.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tools/stepctl/drive_words.hpp"

namespace stepnode::tools::drive {
namespace {

// A bit pattern as the standard writes it, most significant bit first ("x0xx 0000", spaces
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

// ---- 6041h: the state coding table (bits 6..0) ---------------------------------------------

const std::vector<std::pair<State, const char*>> kStateTable = {
    {State::NotReadyToSwitchOn, "0xx 0000"},  {State::SwitchOnDisabled, "1xx 0000"},
    {State::ReadyToSwitchOn, "01x 0001"},     {State::SwitchedOn, "01x 0011"},
    {State::OperationEnabled, "01x 0111"},    {State::QuickStopActive, "00x 0111"},
    {State::FaultReactionActive, "0xx 1111"}, {State::Fault, "0xx 1000"},
};

TEST(DriveStatusword, EveryStatuswordIsTheStateWhoseRowItMatches) {
  for (uint32_t sw = 0; sw <= 0xFFFF; ++sw) {
    std::vector<State> rows;
    for (const auto& [state, bits] : kStateTable)
      if (pattern(bits).matches(static_cast<uint16_t>(sw))) rows.push_back(state);
    ASSERT_LE(rows.size(), 1u) << "the table's rows overlap at " << sw;
    EXPECT_EQ(decode_state(static_cast<uint16_t>(sw)), rows.empty() ? State::Unknown : rows[0])
        << "6041h " << sw;
  }
}

TEST(DriveStatusword, StatesAreNamedAsTheStandardNamesThem) {
  // Statuswords as a drive sends them: remote (bit 9), voltage enabled (bit 4) when powered.
  EXPECT_STREQ(name(decode_state(0x0200)), "Not ready to switch on");
  EXPECT_STREQ(name(decode_state(0x0250)), "Switch on disabled");
  EXPECT_STREQ(name(decode_state(0x0231)), "Ready to switch on");
  EXPECT_STREQ(name(decode_state(0x0233)), "Switched on");
  EXPECT_STREQ(name(decode_state(0x1637)),
               "Operation enabled");  // + target reached, set-point ack.
  EXPECT_STREQ(name(decode_state(0x0217)), "Quick stop active");
  EXPECT_STREQ(name(decode_state(0x021F)), "Fault reaction active");
  EXPECT_STREQ(name(decode_state(0x0208)), "Fault");
  EXPECT_STREQ(name(decode_state(0x0228)), "Fault");          // bit 5 is open ("x") in Fault
  EXPECT_STREQ(name(decode_state(0x0201)), "unknown state");  // x0x0 0001: no row
  EXPECT_TRUE(fault(State::Fault) && fault(State::FaultReactionActive) &&
              !fault(State::QuickStopActive));
}

TEST(DriveStatusword, BitsInWordsByMode) {
  using V = std::vector<std::string>;
  // 0x1637 in profile position: remote, target reached, set-point acknowledge.
  EXPECT_EQ(status_bits(0x1637, 1),
            (V{"voltage enabled", "remote", "target reached", "set-point acknowledge"}));
  // The same bits in profile velocity: velocity reached, speed zero.
  EXPECT_EQ(status_bits(0x1637, 3),
            (V{"voltage enabled", "remote", "velocity reached", "speed zero"}));
  // Homing: bit 12 homing attained, bit 13 homing error.
  EXPECT_EQ(status_bits(0x3637, 6),
            (V{"voltage enabled", "remote", "target reached", "homing attained", "homing error"}));
  EXPECT_EQ(status_bits(0x2A37, 1),
            (V{"voltage enabled", "remote", "internal limit active", "following error"}));
  EXPECT_EQ(status_bits(0x0288, 0), (V{"fault", "warning", "remote"}));
  EXPECT_EQ(status_bits(0xC100, 0),
            (V{"manufacturer-specific bit 8", "manufacturer-specific bit 14",
               "manufacturer-specific bit 15"}));
  EXPECT_TRUE(status_bits(0x0040, 1).empty());
}

TEST(DriveStatusword, HomingStatusIsTheTableOfBits13_12_10) {
  // bit 13, bit 12, bit 10 -> the homing mode statusword table.
  const std::map<int, std::string> table = {
      {0b000, "homing procedure is in progress"},
      {0b001, "homing procedure is interrupted or not started"},
      {0b010, "homing is attained, but target is not reached"},
      {0b011, "homing procedure is completed successfully"},
      {0b100, "homing error occurred, velocity is not 0"},
      {0b101, "homing error occurred, velocity is 0"},
  };
  for (const auto& [bits, text] : table) {
    const uint16_t sw =
        static_cast<uint16_t>(0x0237 | ((bits & 4) ? 1u << 13 : 0) | ((bits & 2) ? 1u << 12 : 0) |
                              ((bits & 1) ? 1u << 10 : 0));
    EXPECT_EQ(homing_status(sw), text) << bits;
  }
  EXPECT_NE(homing_status(0x3237).find("reserved"), std::string::npos);
}

TEST(DriveStatusword, ModesAndErrorCodesByName) {
  EXPECT_EQ(mode_name(1), "Profile position");
  EXPECT_EQ(mode_name(3), "Profile velocity");
  EXPECT_EQ(mode_name(6), "Homing");
  EXPECT_EQ(mode_name(8), "Cyclic synchronous position");
  EXPECT_EQ(mode_name(0), "no mode assigned");
  EXPECT_EQ(mode_name(-2), "manufacturer-specific mode -2");
  EXPECT_EQ(mode_name(11), "reserved mode 11");
  EXPECT_EQ(error_code_text(0), "no error");
  EXPECT_EQ(error_code_text(0x8612), "reference limit");
  EXPECT_EQ(error_code_text(0x8130), "life guard or heartbeat error");
}

// ---- 6040h and Table 26: a model drive written from the standard ----------------------------

enum class Cmd {
  None,
  Shutdown,
  SwitchOn,
  SwitchOnEnable,
  DisableVoltage,
  QuickStop,
  DisableOperation,
  EnableOperation,
  FaultReset
};

// The command coding table (bits 7, 3..0); the shared codes are told apart by the state.
Cmd command(uint16_t cw, uint16_t previous, State s) {
  if ((cw & 0x80) && !(previous & 0x80)) return Cmd::FaultReset;  // 0 -> 1 of bit 7
  if (cw & 0x80) return Cmd::None;
  if (pattern("0xxx x110").matches(cw)) return Cmd::Shutdown;
  if (pattern("0xxx 0111").matches(cw))
    return s == State::OperationEnabled ? Cmd::DisableOperation : Cmd::SwitchOn;
  if (pattern("0xxx 1111").matches(cw))
    return s == State::ReadyToSwitchOn ? Cmd::SwitchOnEnable : Cmd::EnableOperation;
  if (pattern("0xxx xx0x").matches(cw)) return Cmd::DisableVoltage;
  if (pattern("0xxx x01x").matches(cw)) return Cmd::QuickStop;
  return Cmd::None;
}

struct Transition {
  State from;
  Cmd command;
  State to;
  int number;
};
// Table 26, the transitions a command makes (605Ah = 2, the default: a quick stop ends in
// Switch on disabled, transition 12 after the ramp; the model drive's ramp is instant).
const std::vector<Transition> kTransitions = {
    {State::SwitchOnDisabled, Cmd::Shutdown, State::ReadyToSwitchOn, 2},
    {State::ReadyToSwitchOn, Cmd::SwitchOn, State::SwitchedOn, 3},
    {State::ReadyToSwitchOn, Cmd::SwitchOnEnable, State::OperationEnabled, 34},  // 3 + 4
    {State::SwitchedOn, Cmd::EnableOperation, State::OperationEnabled, 4},
    {State::OperationEnabled, Cmd::DisableOperation, State::SwitchedOn, 5},
    {State::SwitchedOn, Cmd::Shutdown, State::ReadyToSwitchOn, 6},
    {State::ReadyToSwitchOn, Cmd::QuickStop, State::SwitchOnDisabled, 7},
    {State::ReadyToSwitchOn, Cmd::DisableVoltage, State::SwitchOnDisabled, 7},
    {State::OperationEnabled, Cmd::Shutdown, State::ReadyToSwitchOn, 8},
    {State::OperationEnabled, Cmd::DisableVoltage, State::SwitchOnDisabled, 9},
    {State::SwitchedOn, Cmd::DisableVoltage, State::SwitchOnDisabled, 10},
    {State::SwitchedOn, Cmd::QuickStop, State::SwitchOnDisabled, 10},
    {State::OperationEnabled, Cmd::QuickStop, State::QuickStopActive, 11},
    {State::QuickStopActive, Cmd::DisableVoltage, State::SwitchOnDisabled, 12},
    {State::Fault, Cmd::FaultReset, State::SwitchOnDisabled, 15},
};

struct ModelDrive {
  State state;
  uint16_t controlword = 0;
  std::vector<int> transitions;

  void write(uint16_t cw) {
    const Cmd c = command(cw, controlword, state);
    controlword = cw;
    for (const Transition& t : kTransitions)
      if (t.from == state && t.command == c) {
        state = t.to;
        transitions.push_back(t.number);
        return;
      }
  }
  // What the drive does by itself: transition 1 after initialisation, 14 after the fault
  // reaction.
  void run() {
    if (state == State::NotReadyToSwitchOn)
      state = State::SwitchOnDisabled, transitions.push_back(1);
    if (state == State::FaultReactionActive) state = State::Fault, transitions.push_back(14);
  }
};

// Follows a planner's steps on the model drive; each step must lead where it says.
template <class Planner>
std::vector<int> follow(Planner plan, State from, uint16_t controlword = 0) {
  ModelDrive d{from, controlword, {}};
  for (int i = 0; i < 10; ++i) {
    auto step = plan(d.state, d.controlword);
    if (!step) return d.transitions;
    for (uint16_t cw : step->controlwords) d.write(cw);
    if (step->controlwords.empty()) d.run();
    EXPECT_NE(std::find(step->leads_to.begin(), step->leads_to.end(), d.state),
              step->leads_to.end())
        << step->command << " from " << name(from) << " ended in " << name(d.state);
  }
  ADD_FAILURE() << "no end from " << name(from);
  return d.transitions;
}

using Path = std::vector<int>;

TEST(DriveEnable, FromEveryStateToOperationEnabledByTheStandardsTransitions) {
  const std::vector<std::pair<State, Path>> paths = {
      {State::NotReadyToSwitchOn, {1, 2, 3, 4}},
      {State::SwitchOnDisabled, {2, 3, 4}},
      {State::ReadyToSwitchOn, {3, 4}},
      {State::SwitchedOn, {4}},
      {State::OperationEnabled, {}},
      {State::QuickStopActive, {12, 2, 3, 4}},
      {State::FaultReactionActive, {14, 15, 2, 3, 4}},
      {State::Fault, {15, 2, 3, 4}},
  };
  for (const auto& [from, path] : paths) {
    EXPECT_EQ(follow(enable_step, from), path) << name(from);
    EXPECT_EQ(follow(enable_step, from, 0x0080), path) << name(from) << " with bit 7 left at 1";
  }
}

TEST(DriveEnable, TheControlwordsAreTheCommandCodingTables) {
  EXPECT_EQ(enable_step(State::SwitchOnDisabled, 0)->controlwords, std::vector<uint16_t>{0x0006});
  EXPECT_EQ(enable_step(State::ReadyToSwitchOn, 0x0006)->controlwords,
            std::vector<uint16_t>{0x0007});
  EXPECT_EQ(enable_step(State::SwitchedOn, 0x0007)->controlwords, std::vector<uint16_t>{0x000F});
  // The fault reset is bit 7's rising edge: with bit 7 still 1 from before, 0 first.
  EXPECT_EQ(enable_step(State::Fault, 0x0000)->controlwords, std::vector<uint16_t>{0x0080});
  EXPECT_EQ(enable_step(State::Fault, 0x0080)->controlwords,
            (std::vector<uint16_t>{0x0000, 0x0080}));
  EXPECT_EQ(enable_step(State::Fault, 0)->command, "Fault reset");
  // Waiting for the drive's own transitions: nothing written; the fault reaction may ramp.
  EXPECT_TRUE(enable_step(State::NotReadyToSwitchOn, 0)->controlwords.empty());
  EXPECT_TRUE(enable_step(State::FaultReactionActive, 0)->controlwords.empty());
  EXPECT_TRUE(enable_step(State::FaultReactionActive, 0)->ramp);
  EXPECT_FALSE(enable_step(State::SwitchOnDisabled, 0)->ramp);
  EXPECT_FALSE(enable_step(State::OperationEnabled, 0x000F));
  EXPECT_FALSE(enable_step(State::Unknown, 0));
}

TEST(DriveDisable, DisableOperationThenShutdownToReadyToSwitchOn) {
  EXPECT_EQ(follow(disable_step, State::OperationEnabled, 0x000F), (Path{5, 6}));
  EXPECT_EQ(disable_step(State::OperationEnabled, 0x000F)->controlwords,
            std::vector<uint16_t>{0x0007});
  EXPECT_TRUE(disable_step(State::OperationEnabled, 0x000F)->ramp);  // 605Ch 1: slow down first
  EXPECT_EQ(follow(disable_step, State::SwitchedOn, 0x0007), (Path{6}));
  EXPECT_EQ(follow(disable_step, State::QuickStopActive, 0x000B), (Path{12}));
  EXPECT_EQ(follow(disable_step, State::FaultReactionActive), (Path{14}));
  for (State s :
       {State::ReadyToSwitchOn, State::SwitchOnDisabled, State::NotReadyToSwitchOn, State::Fault})
    EXPECT_FALSE(disable_step(s, 0)) << name(s);
}

TEST(DriveQuickStop, QuickStopFromThePoweredStates) {
  // 0x0B is the Quick stop command of the coding table in every state.
  for (State s : {State::OperationEnabled, State::SwitchedOn, State::ReadyToSwitchOn})
    EXPECT_EQ(command(0x000B, 0x000F, s), Cmd::QuickStop);
  EXPECT_EQ(quick_stop_step(State::OperationEnabled, 0x000F)->controlwords,
            std::vector<uint16_t>{0x000B});
  EXPECT_EQ(follow(quick_stop_step, State::OperationEnabled, 0x000F), (Path{11}));
  EXPECT_EQ(follow(quick_stop_step, State::SwitchedOn, 0x0007), (Path{10}));
  EXPECT_EQ(follow(quick_stop_step, State::ReadyToSwitchOn, 0x0006), (Path{7}));
  for (State s : {State::SwitchOnDisabled, State::NotReadyToSwitchOn, State::QuickStopActive,
                  State::Fault, State::FaultReactionActive})
    EXPECT_FALSE(quick_stop_step(s, 0)) << name(s);
}

TEST(DriveFaultReset, RisingEdgeOfBit7FromFault) {
  EXPECT_EQ(follow(fault_reset_step, State::Fault, 0x0000), (Path{15}));
  EXPECT_EQ(follow(fault_reset_step, State::Fault, 0x0080), (Path{15}));  // 0x00, then 0x80
  EXPECT_EQ(follow(fault_reset_step, State::Fault, 0x008F), (Path{15}));
  EXPECT_EQ(follow(fault_reset_step, State::FaultReactionActive), (Path{14, 15}));
  for (State s : {State::SwitchOnDisabled, State::ReadyToSwitchOn, State::OperationEnabled,
                  State::QuickStopActive})
    EXPECT_FALSE(fault_reset_step(s, 0)) << name(s);
}

TEST(DriveProfilePosition, SetPointControlwordBits) {
  // Enable operation 0x0F + bit 4 new set-point, bit 5 change set immediately, bit 6 relative.
  EXPECT_EQ(set_point_controlword(false, false), 0x001F);
  EXPECT_EQ(set_point_controlword(true, false), 0x003F);
  EXPECT_EQ(set_point_controlword(false, true), 0x005F);
  EXPECT_EQ(set_point_controlword(true, true), 0x007F);
  // Still Enable operation to the state machine (bits 4..6 are the mode's).
  EXPECT_EQ(command(set_point_controlword(true, true), 0x000F, State::OperationEnabled),
            Cmd::EnableOperation);
}

}  // namespace
}  // namespace stepnode::tools::drive
