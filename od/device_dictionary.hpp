// The stepnode device's object dictionary: the CiA 301 communication area (0x1000-0x1FFF)
// and the manufacturer objects. One table feeds the node, the EDS writer and the tools.
#pragma once
#include <cstdint>
#include <string>

#include "od/dictionary.hpp"

namespace stepnode::od {

struct DeviceInfo {
  uint8_t node_id = 1;
  unsigned axes = 3;  // 1..8; each axis owns kPdosPerAxis RPDOs and TPDOs
  // SPM30 3-axis models: one register set (axis 1) multiplexes 3 motors, chosen with
  // %Q1..%Q3. Then axes = 1 and the simulated machine has 3 motors.
  bool spm30_multiplexed = false;
  std::string device_name = "stepnode";
  std::string hardware_version = "simulated machine";
  std::string software_version = "0.1.0";
  uint32_t vendor_id = 0;  // no CiA-assigned vendor ID
  uint32_t product_code = 0x53544550;  // "STEP"
  uint32_t revision = 0x00010000;      // major 1, minor 0
  uint32_t serial_number = 0;
};

constexpr unsigned kMaxAxes = 8;
constexpr unsigned kPdosPerAxis = 4;
constexpr unsigned kHeartbeatConsumers = 4;
constexpr unsigned kErrorHistoryLength = 8;
constexpr size_t kUserDataMaxLength = 4096;
// 0x2F10: received frames the CAN socket dropped (receive queue overflow), U32 ro.
constexpr uint16_t kReceiveOverruns = 0x2F10;
// 0x2F11: the node-ID of the master whose heartbeat loss stops the axes (0: any), U8 rw.
constexpr uint16_t kMasterNodeId = 0x2F11;
// 0x1029 error behaviour (CiA 301 7.5.2.32), sub 1: the communication error class.
constexpr uint16_t kErrorBehaviour = 0x1029;
constexpr uint8_t kCommunicationErrorSub = 1;
constexpr uint8_t kErrorBehaviourPreOperational = 0, kErrorBehaviourNoChange = 1, kErrorBehaviourStopped = 2;

inline unsigned pdo_count(const DeviceInfo& info) { return kPdosPerAxis * info.axes; }
// Simulated motors (0x5000 blocks): one per axis, or 3 behind a multiplexed axis.
inline unsigned motor_count(const DeviceInfo& info) { return info.spm30_multiplexed ? 3 : info.axes; }

// Index ranges grouped for store/restore (0x1010/0x1011 sub-indices 1..4).
struct ParameterGroup {
  uint8_t sub;
  uint16_t first, last;
  const char* name;
};
constexpr ParameterGroup kParameterGroups[] = {
    {1, 0x1000, 0x9FFF, "all parameters"},
    {2, 0x1000, 0x1FFF, "communication parameters"},
    {3, 0x6000, 0x9FFF, "application parameters"},
    {4, 0x2000, 0x5FFF, "manufacturer parameters"},
};

constexpr uint32_t kSaveSignature = 0x65766173;  // "save", little-endian
constexpr uint32_t kLoadSignature = 0x64616F6C;  // "load"

// Fills `dictionary` with every object of the device, with the CiA 301 consistency rules
// (PDO COB-ID/mapping procedure, SYNC/EMCY COB-ID rules, heartbeat consumer duplicates)
// installed as validate hooks. Services add their own reactions on top.
void build_device_dictionary(Dictionary& dictionary, const DeviceInfo& info);

// True for identifiers CiA 301 7.3.5 reserves (never usable for a PDO, SYNC or EMCY).
bool is_restricted_can_id(uint32_t can_id);

}  // namespace stepnode::od
