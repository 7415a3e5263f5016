// Sample structs -> IDL types, field by field; every status bit by name.
#include <gtest/gtest.h>

#include <tuple>

#include "bridge/dds/convert.hpp"

namespace stepnode::bridge::dds {
namespace {

TEST(Convert, EveryStatusBitByName) {
  struct Bit {
    uint16_t mask;
    bool (::stepnode::AxisStatus::*get)() const;
  };
  const Bit bits[] = {
      {1u << 0, &::stepnode::AxisStatus::emergency_stop},
      {1u << 1, &::stepnode::AxisStatus::lower_limit},
      {1u << 2, &::stepnode::AxisStatus::upper_limit},
      {1u << 3, &::stepnode::AxisStatus::illegal_move},
      {1u << 4, &::stepnode::AxisStatus::motor_stalled},
      {1u << 7, &::stepnode::AxisStatus::power_up_error},
      {1u << 8, &::stepnode::AxisStatus::position_valid},
      {1u << 9, &::stepnode::AxisStatus::resumable},
      {1u << 10, &::stepnode::AxisStatus::axis2_selected},
      {1u << 11, &::stepnode::AxisStatus::axis3_selected},
      {1u << 12, &::stepnode::AxisStatus::at_home},
      {1u << 13, &::stepnode::AxisStatus::accelerating},
      {1u << 14, &::stepnode::AxisStatus::decelerating},
      {1u << 15, &::stepnode::AxisStatus::moving},
  };
  for (const Bit& b : bits) {
    AxisStatusSample s;
    s.status_bits = b.mask;
    auto one = to_idl(s);
    for (const Bit& other : bits)
      EXPECT_EQ((one.*other.get)(), other.mask == b.mask)
          << std::hex << b.mask << " vs " << other.mask;
    EXPECT_EQ(one.status_bits(), b.mask);
  }
}

TEST(Convert, AxisStatusFields) {
  AxisStatusSample s;
  s.node = 5;
  s.axis = 3;
  s.status_bits = 0x81A5;  // %I1 %I3 %I6 %I8 %I9 %I16
  s.done_code = -2;
  s.hp_error = 91;
  s.can_time_ns = 1'700'000'000'123'456'789ull;
  auto d = to_idl(s);
  EXPECT_EQ(d.node(), 5);
  EXPECT_EQ(d.axis(), 3);
  EXPECT_EQ(d.status_bits(), 0x81A5);
  EXPECT_EQ(d.error_bits(), 0xA5);
  EXPECT_TRUE(d.emergency_stop());
  EXPECT_TRUE(d.upper_limit());
  EXPECT_TRUE(d.power_up_error());
  EXPECT_TRUE(d.position_valid());
  EXPECT_TRUE(d.moving());
  EXPECT_FALSE(d.lower_limit());
  EXPECT_FALSE(d.at_home());
  EXPECT_EQ(d.done_code(), -2);
  EXPECT_EQ(d.hp_error(), 91);
  EXPECT_EQ(d.can_time_ns(), 1'700'000'000'123'456'789ull);
  EXPECT_EQ(to_idl(AxisStatusSample{}).done_code(), -128);  // unknown
}

TEST(Convert, AxisPositionFields) {
  AxisPositionSample s;
  s.node = 127;
  s.axis = 8;
  s.motor_position = -2'000'000'000;
  s.encoder_position = 123456;
  s.motor_user_units = -12.5;
  s.encoder_user_units = 0.25;
  s.velocity = -24000;
  s.motion_phase = 3;
  s.sync_counter = 240;
  s.can_time_ns = 11;
  s.publish_time_ns = 22;
  auto d = to_idl(s);
  EXPECT_EQ(d.node(), 127);
  EXPECT_EQ(d.axis(), 8);
  EXPECT_EQ(d.motor_position(), -2'000'000'000);
  EXPECT_EQ(d.encoder_position(), 123456);
  EXPECT_DOUBLE_EQ(d.motor_user_units(), -12.5);
  EXPECT_DOUBLE_EQ(d.encoder_user_units(), 0.25);
  EXPECT_EQ(d.velocity(), -24000);
  EXPECT_EQ(d.motion_phase(), 3);
  EXPECT_EQ(d.sync_counter(), 240);
  EXPECT_EQ(d.can_time_ns(), 11u);
  EXPECT_EQ(d.publish_time_ns(), 22u);
}

TEST(Convert, NodeHealthFields) {
  NodeHealthSample s;
  s.node = 9;
  s.state = NodeState::Lost;
  s.is_stepnode = true;
  s.discovered = true;
  s.device_name = "stepnode";
  s.vendor_id = 1;
  s.product_code = 0x53544550;
  s.revision = 3;
  s.serial = 1234;
  s.axes = 3;
  s.heartbeat_age_ms = 3100;
  s.last_emcy_code = 0x8130;
  s.error_register = 0x11;
  s.frames = 100;
  s.bad_frames = 2;
  s.sdo_failures = 4;
  s.bus.frames = 1000;
  s.bus.bad_frames = 5;
  s.bus.undecoded = 10;
  s.bus.error_frames = 6;
  s.bus.error_passive = 7;
  s.bus.bus_off = 8;
  s.bus.overruns = 9;
  auto d = to_idl(s);
  EXPECT_EQ(d.node(), 9);
  EXPECT_EQ(d.state(), ::stepnode::NODE_LOST);
  EXPECT_TRUE(d.is_stepnode());
  EXPECT_TRUE(d.discovered());
  EXPECT_EQ(d.device_name(), "stepnode");
  EXPECT_EQ(d.vendor_id(), 1u);
  EXPECT_EQ(d.product_code(), 0x53544550u);
  EXPECT_EQ(d.revision(), 3u);
  EXPECT_EQ(d.serial(), 1234u);
  EXPECT_EQ(d.axes(), 3);
  EXPECT_EQ(d.heartbeat_age_ms(), 3100u);
  EXPECT_EQ(d.last_emcy_code(), 0x8130);
  EXPECT_EQ(d.error_register(), 0x11);
  EXPECT_EQ(d.frames(), 100u);
  EXPECT_EQ(d.bad_frames(), 2u);
  EXPECT_EQ(d.sdo_failures(), 4u);
  EXPECT_EQ(d.bus_frames(), 1000u);
  EXPECT_EQ(d.bus_bad_frames(), 5u);
  EXPECT_EQ(d.bus_undecoded(), 10u);
  EXPECT_EQ(d.bus_error_frames(), 6u);
  EXPECT_EQ(d.bus_error_passive(), 7u);
  EXPECT_EQ(d.bus_off(), 8u);
  EXPECT_EQ(d.bus_overruns(), 9u);
}

TEST(Convert, NodeStatesBothWays) {
  const std::pair<NodeState, ::stepnode::NodeState> pairs[] = {
      {NodeState::Unknown, ::stepnode::NODE_UNKNOWN},
      {NodeState::BootUp, ::stepnode::NODE_BOOT_UP},
      {NodeState::Stopped, ::stepnode::NODE_STOPPED},
      {NodeState::Operational, ::stepnode::NODE_OPERATIONAL},
      {NodeState::PreOperational, ::stepnode::NODE_PRE_OPERATIONAL},
      {NodeState::Lost, ::stepnode::NODE_LOST},
  };
  for (auto [plain, idl] : pairs) {
    EXPECT_EQ(to_idl(plain), idl);
    EXPECT_EQ(from_idl(idl), plain);
  }
  EXPECT_EQ(state_text(::stepnode::NODE_OPERATIONAL), "OPERATIONAL");
  EXPECT_EQ(state_text(::stepnode::NODE_PRE_OPERATIONAL), "PRE_OPERATIONAL");
  EXPECT_EQ(state_text(::stepnode::NODE_LOST), "LOST");
}

TEST(Convert, EmergencyFields) {
  EmergencySample s;
  s.node = 4;
  s.code = 0xFF01;
  s.error_register = 0x81;
  s.manufacturer = {1, 2, 3, 4, 5};
  s.text = "device specific: axis 1 motor stalled";
  s.can_time_ns = 77;
  auto d = to_idl(s);
  EXPECT_EQ(d.node(), 4);
  EXPECT_EQ(d.code(), 0xFF01);
  EXPECT_EQ(d.error_register(), 0x81);
  EXPECT_EQ(d.manufacturer(), (std::array<uint8_t, 5>{1, 2, 3, 4, 5}));
  EXPECT_EQ(d.text(), "device specific: axis 1 motor stalled");
  EXPECT_EQ(d.can_time_ns(), 77u);
}

TEST(Convert, DriveStatusOperationEnabledFromTheStandard) {
  // 0x0637: ready to switch on, switched on, operation enabled (state coding x01x 0111),
  // voltage enabled, quick stop (not active), remote, target reached.
  DriveStatusSample s;
  s.node = 5;
  s.axis = 2;
  s.statusword_known = true;
  s.statusword = 0x0637;
  s.mode_display = 1;
  s.position_actual = -1000;
  s.velocity_actual = 2500;
  s.following_error = -7;
  s.error_code = 0x8611;
  s.can_time_ns = 11;
  s.publish_time_ns = 22;
  auto d = to_idl(s);
  EXPECT_EQ(d.node(), 5);
  EXPECT_EQ(d.axis(), 2);
  EXPECT_EQ(d.statusword(), 0x0637);
  EXPECT_EQ(d.state(), ::stepnode::DRIVE_OPERATION_ENABLED);
  EXPECT_EQ(drive_state_text(d.state()), "Operation enabled");
  EXPECT_EQ(d.mode_display(), 1);
  EXPECT_EQ(d.position_actual(), -1000);
  EXPECT_EQ(d.velocity_actual(), 2500);
  EXPECT_EQ(d.following_error(), -7);
  EXPECT_EQ(d.error_code(), 0x8611);
  EXPECT_TRUE(d.ready_to_switch_on());
  EXPECT_TRUE(d.switched_on());
  EXPECT_TRUE(d.operation_enabled());
  EXPECT_FALSE(d.fault());
  EXPECT_TRUE(d.voltage_enabled());
  EXPECT_TRUE(d.quick_stop());
  EXPECT_FALSE(d.switch_on_disabled());
  EXPECT_FALSE(d.warning());
  EXPECT_TRUE(d.remote());
  EXPECT_TRUE(d.target_reached());
  EXPECT_FALSE(d.internal_limit_active());
  EXPECT_FALSE(d.bit12());
  EXPECT_FALSE(d.bit13());
  EXPECT_EQ(d.can_time_ns(), 11u);
  EXPECT_EQ(d.publish_time_ns(), 22u);
}

TEST(Convert, EveryDriveStatuswordBitByName) {
  struct Bit {
    uint16_t mask;
    bool (::stepnode::DriveStatus::*get)() const;
  };
  using D = ::stepnode::DriveStatus;
  const Bit bits[] = {
      {1u << 0, &D::ready_to_switch_on},
      {1u << 1, &D::switched_on},
      {1u << 2, &D::operation_enabled},
      {1u << 3, &D::fault},
      {1u << 4, &D::voltage_enabled},
      {1u << 5, &D::quick_stop},
      {1u << 6, &D::switch_on_disabled},
      {1u << 7, &D::warning},
      {1u << 9, &D::remote},
      {1u << 10, &D::target_reached},
      {1u << 11, &D::internal_limit_active},
      {1u << 12, &D::bit12},
      {1u << 13, &D::bit13},
  };
  for (const Bit& b : bits) {
    DriveStatusSample s;
    s.statusword_known = true;
    s.statusword = b.mask;
    auto one = to_idl(s);
    for (const Bit& other : bits)
      EXPECT_EQ((one.*other.get)(), other.mask == b.mask)
          << std::hex << b.mask << " vs " << other.mask;
  }
}

TEST(Convert, DriveStatesAndTheirNames) {
  const std::tuple<uint16_t, ::stepnode::DriveState, const char*> states[] = {
      {0x0200, ::stepnode::DRIVE_NOT_READY_TO_SWITCH_ON, "Not ready to switch on"},
      {0x0250, ::stepnode::DRIVE_SWITCH_ON_DISABLED, "Switch on disabled"},
      {0x0231, ::stepnode::DRIVE_READY_TO_SWITCH_ON, "Ready to switch on"},
      {0x0233, ::stepnode::DRIVE_SWITCHED_ON, "Switched on"},
      {0x1237, ::stepnode::DRIVE_OPERATION_ENABLED, "Operation enabled"},
      {0x0217, ::stepnode::DRIVE_QUICK_STOP_ACTIVE, "Quick stop active"},
      {0x021F, ::stepnode::DRIVE_FAULT_REACTION_ACTIVE, "Fault reaction active"},
      {0x0208, ::stepnode::DRIVE_FAULT, "Fault"},
      {0x0009, ::stepnode::DRIVE_UNKNOWN, "unknown"},  // no such state coding
  };
  for (auto [sw, state, text] : states) {
    DriveStatusSample s;
    s.statusword_known = true;
    s.statusword = sw;
    EXPECT_EQ(to_idl(s).state(), state) << std::hex << sw;
    EXPECT_EQ(drive_state_text(state), text);
  }
  DriveStatusSample never;  // no statusword seen yet (a TPDO with positions only)
  EXPECT_EQ(to_idl(never).state(), ::stepnode::DRIVE_UNKNOWN);
}

}  // namespace
}  // namespace stepnode::bridge::dds
