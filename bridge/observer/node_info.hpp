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
constexpr unsigned kMaxAxes = 8;     // axis blocks 0x2000..0x27FF, CiA 402 axes 0x6000..0x9FFF
constexpr unsigned kMaxTpdos = 512;  // 0x1800..0x19FF
constexpr unsigned kNodeIds = 128;   // 1..127 (0 unused)

struct TpdoInfo {
  uint16_t number = 0;  // 0-based: communication parameter 0x1800 + number
  uint16_t cob_id = 0;  // 11-bit identifier (bit 31 clear: valid)
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

// A CiA 402 axis's values read over SDO at the end of discovery (6041h, 6061h, 6064h,
// 606Ch, 60F4h, 603Fh), for the same reason.
struct DriveSnapshot {
  bool statusword_read = false, mode_read = false, position_read = false, velocity_read = false;
  bool following_error_read = false, error_code_read = false;
  uint16_t statusword = 0;
  int8_t mode_display = 0;
  int32_t position_actual = 0, velocity_actual = 0, following_error = 0;
  uint16_t error_code = 0;
  bool any() const {
    return statusword_read || mode_read || position_read || velocity_read || following_error_read ||
           error_code_read;
  }
};

// 1000h bits 0-15: the device profile number; 402 (0x192) is a drive (CiA 402). A device
// with several axes has 67FFh + 0x800 * a per axis (CiA 402-2, multiple axes).
constexpr uint16_t kProfileCia402 = 0x192;

struct NodeInfo {
  bool identity_read = false;  // 0x1018 answered (absent on some third-party devices)
  uint32_t vendor_id = 0, product_code = 0, revision = 0, serial = 0;
  std::string device_name;   // 0x1008, empty when absent
  uint32_t device_type = 0;  // 0x1000
  bool device_type_read = false;
  uint16_t heartbeat_period_ms = 0;  // 0x1017, 0 = producer off or unknown
  bool heartbeat_period_read = false;
  uint8_t axes = 0;                                             // 0x2n01 present for n < axes
  std::array<double, kMaxAxes> pscale{1, 1, 1, 1, 1, 1, 1, 1};  // 0x2n11, 1.0 when absent
  std::vector<TpdoInfo> tpdos;                                  // valid TPDOs only
  std::array<AxisSnapshot, kMaxAxes> snapshot{};
  // CiA 402 axes: 67FFh + 0x800 * a readable for a < drive_axes; a device whose 1000h says
  // 402 but that has no 67FFh is one axis.
  uint8_t drive_axes = 0;
  std::array<DriveSnapshot, kMaxAxes> drive_snapshot{};

  // 1000h says CiA 402 (bits 0-15 = 0x192).
  bool device_type_is_cia402() const {
    return device_type_read && (device_type & 0xFFFF) == kProfileCia402;
  }
  // A stepnode: the product code says so AND the first axis block (Horner 0x2001 or CiA 402
  // axis 1) exists.
  bool is_stepnode() const {
    return product_code == kStepnodeProductCode && (axes > 0 || drive_axes > 0);
  }
  // The bridge decodes this device's TPDOs: a stepnode, or any CiA 402 drive.
  bool has_axes() const { return axes > 0 || drive_axes > 0; }
  uint8_t device_axes() const { return axes > drive_axes ? axes : drive_axes; }
};

}  // namespace stepnode::bridge
