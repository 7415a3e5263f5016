// A SampleSink that keeps every sample, for assertions.
#pragma once
#include <utility>
#include <vector>

#include "bridge/samples.hpp"

namespace stepnode::bridge::test {

struct RecordingSink : SampleSink {
  std::vector<AxisStatusSample> statuses;
  std::vector<AxisPositionSample> positions;
  std::vector<NodeHealthSample> healths;
  std::vector<EmergencySample> emergencies;
  std::vector<DriveStatusSample> drives;
  std::vector<std::pair<uint8_t, uint8_t>> disposed;  // (node, axes)

  void axis_status(const AxisStatusSample& s) override { statuses.push_back(s); }
  void axis_position(const AxisPositionSample& s) override { positions.push_back(s); }
  void node_health(const NodeHealthSample& s) override { healths.push_back(s); }
  void emergency(const EmergencySample& s) override { emergencies.push_back(s); }
  void drive_status(const DriveStatusSample& s) override { drives.push_back(s); }
  void dispose_axes(uint8_t node, uint8_t axes) override { disposed.emplace_back(node, axes); }

  void clear() {
    statuses.clear();
    positions.clear();
    healths.clear();
    emergencies.clear();
    drives.clear();
    disposed.clear();
  }
  const NodeHealthSample* last_health(uint8_t node) const {
    for (auto it = healths.rbegin(); it != healths.rend(); ++it)
      if (it->node == node) return &*it;
    return nullptr;
  }
};

}  // namespace stepnode::bridge::test
