// stepwatch's view of the bridge's topics: the latest status and position of every axis
// (and its CiA 402 drive status), the health of every node, the last EMCY of each node;
// rendered as a table, JSON lines or CSV rows. Pure (no DDS entities), so it is tested without a
// participant.
#pragma once
#include <stepnodePubSubTypes.h>

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace stepnode::stepwatch {

struct AxisRow {
  uint8_t node = 0;
  uint8_t axis = 0;
  std::optional<::stepnode::AxisStatus> status;
  std::optional<::stepnode::AxisPosition> position;
  std::optional<::stepnode::DriveStatus> drive;  // a CiA 402 axis
};

class WatchModel {
 public:
  void on_status(const ::stepnode::AxisStatus& s);
  void on_position(const ::stepnode::AxisPosition& p);
  void on_health(const ::stepnode::NodeHealth& h);
  void on_emergency(const ::stepnode::Emergency& e);
  void on_drive(const ::stepnode::DriveStatus& d);
  // The bridge disposed the axis (node lost): the row goes.
  void on_axis_disposed(uint8_t node, uint8_t axis);

  const std::map<uint16_t, AxisRow>& axes() const { return axes_; }
  const std::map<uint8_t, ::stepnode::NodeHealth>& nodes() const { return nodes_; }
  bool empty() const { return axes_.empty() && nodes_.empty(); }
  uint64_t samples() const { return samples_; }

  // One JSON object per node ({"type":"node",...}) then per axis ({"type":"axis",...},
  // with "drive" for a CiA 402 axis), ordered by node and axis.
  std::vector<nlohmann::json> snapshot() const;
  // The live table: one line per axis under its node's line.
  std::string table() const;

 private:
  std::map<uint16_t, AxisRow> axes_;  // node << 8 | axis
  std::map<uint8_t, ::stepnode::NodeHealth> nodes_;
  std::map<uint8_t, ::stepnode::Emergency> last_emcy_;
  uint64_t samples_ = 0;
};

nlohmann::json to_json(const ::stepnode::AxisStatus& s);
nlohmann::json to_json(const ::stepnode::AxisPosition& p);
nlohmann::json to_json(const ::stepnode::NodeHealth& h);
nlohmann::json to_json(const ::stepnode::Emergency& e);
nlohmann::json to_json(const ::stepnode::DriveStatus& d);
// "Operation enabled, pp, target_reached remote" (state, mode, set bits by name).
std::string drive_words(const ::stepnode::DriveStatus& d);
// "moving accelerating position_valid" (set bits by name, %I order); "-" when none.
std::string status_words(const ::stepnode::AxisStatus& s);

// CSV log: one row per received sample, the same columns for every topic (empty when a
// topic has no such field).
std::string csv_header();
std::string csv_row(uint64_t recv_time_ns, const ::stepnode::AxisStatus& s);
std::string csv_row(uint64_t recv_time_ns, const ::stepnode::AxisPosition& p);
std::string csv_row(uint64_t recv_time_ns, const ::stepnode::NodeHealth& h);
std::string csv_row(uint64_t recv_time_ns, const ::stepnode::Emergency& e);
std::string csv_row(uint64_t recv_time_ns, const ::stepnode::DriveStatus& d);
std::string csv_disposed_row(uint64_t recv_time_ns, const char* topic, uint8_t node, uint8_t axis);

}  // namespace stepnode::stepwatch
