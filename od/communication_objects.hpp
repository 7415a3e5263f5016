// The CiA 301 communication objects (0x1000-0x1FFF) of a device: identity, error history,
// SYNC, EMCY, heartbeat, error behaviour, store/restore, SDO server and PDO parameters,
// with their consistency rules. Generic: the profiles add their own objects on top
// (node/profiles/*), so one table feeds the node, the EDS writer and the tools.
#pragma once
#include <cstdint>
#include <string>

#include "od/dictionary.hpp"

namespace stepnode::od {

struct DeviceInfo {
  uint8_t node_id = 1;
  std::string device_name = "stepnode";
  std::string hardware_version = "simulated machine";
  std::string software_version = "0.1.0";
  uint32_t vendor_id = 0;              // no CiA-assigned vendor ID
  uint32_t product_code = 0x53544550;  // "STEP"
  uint32_t revision = 0x00010000;      // major 1, minor 0
  uint32_t serial_number = 0;
  std::string description{};  // one line for the EDS comments (the profiles and axes)
};

constexpr unsigned kHeartbeatConsumers = 4;
constexpr uint16_t kSyncWindowLength = 0x1007;  // us; 0: no window
// 0x1F80 NMT startup (CiA 302-2): bit 2 = 1 do not start by itself (the only bit supported).
constexpr uint16_t kNmtStartup = 0x1F80;
constexpr uint32_t kNmtStartupNoAutoStart = 0x04;
constexpr unsigned kErrorHistoryLength = 8;
// 0x1029 error behaviour (CiA 301 7.5.2.32), sub 1: the communication error class.
constexpr uint16_t kErrorBehaviour = 0x1029;
constexpr uint8_t kCommunicationErrorSub = 1;
constexpr uint8_t kErrorBehaviourPreOperational = 0, kErrorBehaviourNoChange = 1,
                  kErrorBehaviourStopped = 2;
// RPDOs and TPDOs a device may have (CiA 301: 0x1400-0x15FF / 0x1800-0x19FF).
constexpr unsigned kMaxPdos = 512;

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

// Fills `od` with the communication objects of a device with `pdos` RPDOs and as
// many TPDOs (their mappings empty: the profiles give the defaults), with the CiA 301
// consistency rules (PDO COB-ID/mapping procedure, SYNC/EMCY COB-ID rules, heartbeat
// consumer duplicates) installed as validate hooks. Services add their reactions on top.
void build_communication_objects(Dictionary& od, const DeviceInfo& info, unsigned pdos);

// A new node-ID for the defaults that follow it (those whose EDS default is
// "$NODEID+0x...": the EMCY, SDO and first four PDO COB-IDs). Only the default values
// change: the node puts defaults and stored values back at its next reset communication,
// which is when CiA 301 7.3.2.2.1 says a new node-ID takes effect.
void apply_node_id(Dictionary& od, uint8_t node_id);

// True for identifiers CiA 301 7.3.5 reserves (never usable for a PDO, SYNC or EMCY).
bool is_restricted_can_id(uint32_t can_id);

}  // namespace stepnode::od
