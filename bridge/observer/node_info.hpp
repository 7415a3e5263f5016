// What the bridge learns about one node over SDO (identity, name, axes, PSCALE, every
// valid TPDO's COB-ID and mapping). Filled by DiscoveryPlan, used by the TPDO decoder
// and copied into NodeHealth.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "od/pdo_mapping.hpp"

namespace stepnode::bridge {

// 0x1018:2 of a stepnode ("STEP", od/device_dictionary.hpp DeviceInfo::product_code).
constexpr uint32_t kStepnodeProductCode = 0x53544550;
constexpr unsigned kMaxAxes = 8;          // axis blocks 0x2000..0x27FF
constexpr unsigned kMaxTpdos = 512;       // 0x1800..0x19FF
constexpr unsigned kNodeIds = 128;        // 1..127 (0 unused)

struct TpdoInfo {
  uint16_t number = 0;   // 0-based: communication parameter 0x1800 + number
  uint16_t cob_id = 0;   // 11-bit identifier (bit 31 clear: valid)
  od::PdoMapping mapping;
};

// An axis's values read over SDO at the end of discovery. Event-driven TPDOs of an idle
// axis never come, so without this a bridge started after the nodes would know nothing.
struct AxisSnapshot {
  bool status_read = false, done_read = false, hp_error_read = false;
  bool motor_read = false, encoder_read = false;
  uint16_t status_bits = 0;
  int8_t done_code = 0;
  uint8_t hp_error = 0;
  int32_t motor_position = 0, encoder_position = 0;
};

struct NodeInfo {
  bool identity_read = false;  // 0x1018 answered (absent on some third-party devices)
  uint32_t vendor_id = 0, product_code = 0, revision = 0, serial = 0;
  std::string device_name;            // 0x1008, empty when absent
  uint16_t heartbeat_period_ms = 0;   // 0x1017, 0 = producer off or unknown
  bool heartbeat_period_read = false;
  uint8_t axes = 0;                   // 0x2n01 present for n < axes
  std::array<double, kMaxAxes> pscale{1, 1, 1, 1, 1, 1, 1, 1};  // 0x2n11, 1.0 when absent
  std::vector<TpdoInfo> tpdos;        // valid TPDOs only
  std::array<AxisSnapshot, kMaxAxes> snapshot{};

  // A stepnode: the product code says so AND the first axis block exists.
  bool is_stepnode() const { return product_code == kStepnodeProductCode && axes > 0; }
};

}  // namespace stepnode::bridge
