// stepwatch's model: rows per node and axis, JSON lines, the table and CSV rows.
#include <gtest/gtest.h>

#include "bridge/dds/convert.hpp"
#include "tools/stepwatch/watch_model.hpp"

namespace stepnode::stepwatch {
namespace {

::stepnode::AxisStatus status(uint8_t node, uint8_t axis, uint16_t bits) {
  bridge::AxisStatusSample s;
  s.node = node;
  s.axis = axis;
  s.status_bits = bits;
  return bridge::dds::to_idl(s);
}

::stepnode::AxisPosition position(uint8_t node, uint8_t axis, int32_t steps, int32_t velocity) {
  bridge::AxisPositionSample p;
  p.node = node;
  p.axis = axis;
  p.motor_position = steps;
  p.velocity = velocity;
  p.motion_phase = 2;
  return bridge::dds::to_idl(p);
}

::stepnode::NodeHealth health(uint8_t node, bridge::NodeState state) {
  bridge::NodeHealthSample h;
  h.node = node;
  h.state = state;
  h.device_name = "stepnode";
  h.axes = 2;
  return bridge::dds::to_idl(h);
}

::stepnode::DriveStatus drive(uint8_t node, uint8_t axis, uint16_t statusword, int8_t mode,
                              int32_t position) {
  bridge::DriveStatusSample d;
  d.node = node;
  d.axis = axis;
  d.statusword_known = true;
  d.statusword = statusword;
  d.mode_display = mode;
  d.position_actual = position;
  d.velocity_actual = 300;
  return bridge::dds::to_idl(d);
}

TEST(WatchModel, SnapshotIsNodesThenAxesInOrder) {
  WatchModel m;
  m.on_position(position(5, 2, 100, 50));
  m.on_status(status(5, 1, 0x8100));
  m.on_health(health(5, bridge::NodeState::Operational));
  m.on_status(status(3, 1, 0x0100));
  auto lines = m.snapshot();
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0]["type"], "node");
  EXPECT_EQ(lines[0]["node"], 5);
  EXPECT_EQ(lines[0]["state"], "OPERATIONAL");
  EXPECT_EQ(lines[0]["device_name"], "stepnode");
  EXPECT_TRUE(lines[0]["last_emcy"].is_null());
  EXPECT_EQ(lines[1]["type"], "axis");
  EXPECT_EQ(lines[1]["node"], 3);
  EXPECT_EQ(lines[1]["axis"], 1);
  EXPECT_TRUE(lines[1]["position"].is_null());
  EXPECT_EQ(lines[2]["node"], 5);
  EXPECT_EQ(lines[2]["axis"], 1);
  EXPECT_EQ(lines[2]["status"]["moving"], true);
  EXPECT_EQ(lines[2]["status"]["position_valid"], true);
  EXPECT_EQ(lines[2]["status"]["status_bits"], 0x8100);
  EXPECT_EQ(lines[3]["axis"], 2);
  EXPECT_EQ(lines[3]["position"]["motor_position"], 100);
  EXPECT_EQ(lines[3]["position"]["velocity"], 50);
  EXPECT_TRUE(lines[3]["status"].is_null());
}

TEST(WatchModel, LatestSampleWinsAndDisposeRemovesTheAxis) {
  WatchModel m;
  m.on_status(status(5, 1, 0x8100));
  m.on_status(status(5, 1, 0x1100));
  m.on_position(position(5, 1, 7, 0));
  ASSERT_EQ(m.axes().size(), 1u);
  EXPECT_EQ(m.axes().begin()->second.status->status_bits(), 0x1100);
  m.on_axis_disposed(5, 1);
  EXPECT_TRUE(m.axes().empty());
  EXPECT_EQ(m.samples(), 3u);
}

TEST(WatchModel, EmergencyShowsOnItsNode) {
  WatchModel m;
  m.on_health(health(4, bridge::NodeState::PreOperational));
  bridge::EmergencySample e;
  e.node = 4;
  e.code = 0xFF01;
  e.text = "axis 1: motor stalled";
  m.on_emergency(bridge::dds::to_idl(e));
  auto lines = m.snapshot();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0]["last_emcy"]["code"], 0xFF01);
  EXPECT_EQ(lines[0]["last_emcy"]["text"], "axis 1: motor stalled");
  EXPECT_NE(m.table().find("last EMCY FF01 axis 1: motor stalled"), std::string::npos) << m.table();
}

TEST(WatchModel, TableHasANodeLineAndOneLinePerAxis) {
  WatchModel m;
  m.on_health(health(5, bridge::NodeState::Lost));
  m.on_status(status(5, 1, 0xA110));  // %I5 stalled, %I9, %I14, %I16
  m.on_position(position(5, 1, -1234, -60));
  std::string t = m.table();
  EXPECT_NE(t.find("   5 LOST stepnode 2 axes"), std::string::npos) << t;
  EXPECT_NE(t.find("        1        -1234            0       -60     2   0x10  stalled "
                   "position_valid accelerating moving"),
            std::string::npos)
      << t;
}

TEST(WatchModel, StatusWords) {
  EXPECT_EQ(status_words(status(1, 1, 0)), "-");
  EXPECT_EQ(status_words(status(1, 1, 0xFF9F)),
            "estop lower_limit upper_limit illegal_move stalled power_up position_valid resumable "
            "axis2 axis3 at_home "
            "accelerating decelerating moving");
}

TEST(WatchModel, CsvRowsShareOneHeader) {
  std::string header = csv_header();
  EXPECT_EQ(header,
            "recv_time_ns,topic,node,axis,status_bits,motor_position,encoder_position,velocity,"
            "motion_phase,"
            "sync_counter,state,code,text,can_time_ns,publish_time_ns\n");
  EXPECT_EQ(csv_row(10, status(5, 1, 0x8100)),
            "10,AxisStatus,5,1,0x8100,,,,,,,,\"position_valid moving\",0,\n");
  EXPECT_EQ(csv_row(11, position(5, 2, 42, -7)), "11,AxisPosition,5,2,,42,0,-7,2,0,,,,0,0\n");
  EXPECT_EQ(csv_row(12, health(5, bridge::NodeState::Operational)),
            "12,NodeHealth,5,,,,,,,,OPERATIONAL,0x0000,\"stepnode\",,\n");
  bridge::EmergencySample e;
  e.node = 5;
  e.code = 0x8130;
  e.text = "heartbeat \"lost\"";
  EXPECT_EQ(csv_row(13, bridge::dds::to_idl(e)),
            "13,Emergency,5,,,,,,,,,0x8130,\"heartbeat \"\"lost\"\"\",0,\n");
  EXPECT_EQ(csv_disposed_row(14, "AxisStatus", 5, 1), "14,AxisStatus,5,1,,,,,,,DISPOSED,,,,\n");
  // Every row has the header's 15 columns.
  for (const std::string& row : {csv_row(10, status(5, 1, 0)), csv_row(11, position(5, 2, 42, -7))})
    EXPECT_EQ(std::count(row.begin(), row.end(), ','),
              std::count(header.begin(), header.end(), ','));
}

TEST(WatchModel, ACia402AxisShowsItsDriveState) {
  WatchModel m;
  m.on_health(health(6, bridge::NodeState::Operational));
  m.on_drive(drive(6, 1, 0x0637, 1, 4000));  // Operation enabled, target reached
  auto lines = m.snapshot();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[1]["drive"]["state"], "Operation enabled");
  EXPECT_EQ(lines[1]["drive"]["statusword"], 0x0637);
  EXPECT_EQ(lines[1]["drive"]["target_reached"], true);
  EXPECT_EQ(lines[1]["drive"]["position_actual"], 4000);
  EXPECT_TRUE(lines[1]["status"].is_null());
  std::string t = m.table();
  EXPECT_NE(t.find("        1         4000            -       300     -      -  402: Operation "
                   "enabled, pp target_reached"),
            std::string::npos)
      << t;
  // A Horner axis has no "drive" key (the JSON as before).
  m.on_status(status(6, 2, 0x0100));
  EXPECT_FALSE(m.snapshot()[2].contains("drive"));
  // Fault with its error code.
  m.on_drive(drive(6, 1, 0x0218, 1, 4000));
  EXPECT_EQ(drive_words(m.axes().begin()->second.drive.value()), "Fault, pp");
  EXPECT_EQ(csv_row(15, drive(6, 1, 0x0637, 8, -5)),
            "15,DriveStatus,6,1,0x0637,-5,,300,,,Operation enabled,0x0000,\"Operation enabled, csp "
            "target_reached\",0,0\n");
  m.on_axis_disposed(6, 1);
  EXPECT_EQ(m.axes().size(), 1u);
}

}  // namespace
}  // namespace stepnode::stepwatch
