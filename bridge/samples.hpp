// What the bridge publishes, as plain C++ values: the bus side (bridge/observer) fills
// them, the DDS side (bridge/dds) turns them into the IDL types of bridge/idl/stepnode.idl.
// Keeping them DDS-free lets the observer be tested without a participant.
#pragma once
#include <array>
#include <cstdint>
#include <string>

namespace stepnode::bridge {

// NMT state of a node as the bridge sees it (heartbeat byte, CiA 301 7.2.8.3.2) plus the
// bridge's own verdicts: never heard of yet, and heartbeat lost.
enum class NodeState : uint8_t {
  Unknown = 0,
  BootUp = 1,          // 0x00
  Stopped = 2,         // 0x04
  Operational = 3,     // 0x05
  PreOperational = 4,  // 0x7F
  Lost = 5,            // no heartbeat for 3 periods (or the configured timeout)
};

// DONE? code of the HP 44714A (-3..+2) when the node maps it; kDoneUnknown otherwise.
constexpr int8_t kDoneUnknown = -128;

// One axis instance is keyed by (node, axis); axis is 1-based as on the node's panel.
struct AxisStatusSample {
  uint8_t node = 0;
  uint8_t axis = 0;
  uint16_t status_bits = 0;  // %I1..%I16 as bits 0..15 (node/motion/axis_registers.hpp)
  int8_t done_code = kDoneUnknown;
  uint8_t hp_error = 0;      // HP error number 89..94, 0 = none (when mapped)
  uint64_t can_time_ns = 0;  // kernel receive timestamp (CLOCK_REALTIME) of the TPDO
};

struct AxisPositionSample {
  uint8_t node = 0;
  uint8_t axis = 0;
  int32_t motor_position = 0;    // steps
  int32_t encoder_position = 0;  // encoder counts
  double motor_user_units = 0;   // motor position x PSCALE (HP), = steps when PSCALE is 1
  double encoder_user_units = 0;
  int32_t velocity = 0;          // steps/s, signed
  uint8_t motion_phase = 0;      // 0 idle, 1 accelerating, 2 running, 3 decelerating, 4 base
  uint8_t sync_counter = 0;      // counter of the last SYNC seen before the TPDO (0: none)
  uint64_t can_time_ns = 0;      // kernel receive timestamp of the TPDO
  uint64_t publish_time_ns = 0;  // CLOCK_REALTIME when the bridge published
};

// The CiA 402 power drive system state (IEC 61800-7-201 / CiA 402-2 "device control"), as
// the statusword's state coding gives it; Unknown: no statusword seen yet, or a bit pattern
// the standard's table does not define.
enum class DriveState : uint8_t {
  Unknown = 0,
  NotReadyToSwitchOn,
  SwitchOnDisabled,
  ReadyToSwitchOn,
  SwitchedOn,
  OperationEnabled,
  QuickStopActive,
  FaultReactionActive,
  Fault,
};

// 6041h state coding (bits 6, 5, 3..0; "x" is any value):
//   x0xx 0000 Not ready to switch on    x1xx 0000 Switch on disabled
//   x01x 0001 Ready to switch on        x01x 0011 Switched on
//   x01x 0111 Operation enabled         x00x 0111 Quick stop active
//   x0xx 1111 Fault reaction active     x0xx 1000 Fault
constexpr DriveState drive_state_of(uint16_t statusword) {
  switch (statusword & 0x4F) {
    case 0x00: return DriveState::NotReadyToSwitchOn;
    case 0x40: return DriveState::SwitchOnDisabled;
    case 0x0F: return DriveState::FaultReactionActive;
    case 0x08: return DriveState::Fault;
    default: break;
  }
  switch (statusword & 0x6F) {
    case 0x21: return DriveState::ReadyToSwitchOn;
    case 0x23: return DriveState::SwitchedOn;
    case 0x27: return DriveState::OperationEnabled;
    case 0x07: return DriveState::QuickStopActive;
    default: return DriveState::Unknown;
  }
}

// One CiA 402 axis (node, axis 1-based: its objects at index + 0x800 * (axis - 1)); the
// values are the last the TPDOs (or discovery's SDO reads) carried.
struct DriveStatusSample {
  uint8_t node = 0;
  uint8_t axis = 0;
  bool statusword_known = false;  // false: state() is Unknown
  uint16_t statusword = 0;        // 6041h
  int8_t mode_display = 0;        // 6061h (0: no mode)
  int32_t position_actual = 0;    // 6064h, position units
  int32_t velocity_actual = 0;    // 606Ch, velocity units
  int32_t following_error = 0;    // 60F4h, position units
  uint16_t error_code = 0;        // 603Fh
  uint64_t can_time_ns = 0;       // kernel receive timestamp of the TPDO (or of the SDO answer)
  uint64_t publish_time_ns = 0;   // CLOCK_REALTIME when the bridge published
  DriveState state() const {
    return statusword_known ? drive_state_of(statusword) : DriveState::Unknown;
  }
};

struct BusCounters {
  uint64_t frames = 0;        // every frame received
  uint64_t bad_frames = 0;    // malformed: wrong length (TPDO shorter than its mapping, EMCY,
                              // SYNC, heartbeat), no such NMT state
  uint64_t undecoded = 0;     // well-formed frames the bridge has no use for: RPDOs, TPDOs of
                              // nodes not (yet) discovered or being remapped, TIME, RTR
  uint64_t error_frames = 0;  // CAN error frames from the controller
  uint64_t error_passive = 0;
  uint64_t bus_off = 0;
  // Frames lost before the bridge could decode them: the controller's receive or transmit
  // overflows (error frames) and the frames the kernel dropped from the bridge's own
  // socket queue when it was full (SO_RXQ_OVFL).
  uint64_t overruns = 0;
};

struct EmergencySample {
  uint8_t node = 0;
  uint16_t code = 0;
  uint8_t error_register = 0;
  std::array<uint8_t, 5> manufacturer{};
  std::string text;  // class and code in words, the module's error bits by name
  uint64_t can_time_ns = 0;
};

struct NodeHealthSample {
  uint8_t node = 0;
  NodeState state = NodeState::Unknown;
  bool is_stepnode = false;  // identity says stepnode (0x1018 product code 0x53544550)
  std::string device_name;   // 0x1008 (empty until read or when unreadable)
  uint32_t vendor_id = 0, product_code = 0, revision = 0, serial = 0;  // 0x1018
  uint8_t axes = 0;               // the device's axes: Horner blocks (0x2n01) or CiA 402 axes
                                  // (67FFh + 0x800 * a), whichever are more
  uint32_t heartbeat_age_ms = 0;  // since the last heartbeat
  uint16_t last_emcy_code = 0;
  uint8_t error_register = 0;  // from the last EMCY
  uint32_t frames = 0;         // frames from this node
  uint32_t bad_frames = 0;
  uint32_t sdo_failures = 0;  // discovery transfers that failed (each is retried)
  bool discovered = false;    // identity and mapping read
  BusCounters bus;            // the whole bus, as the bridge's socket sees it
};

// The observer's output. Implemented by the DDS publisher and by test recorders.
class SampleSink {
 public:
  virtual ~SampleSink() = default;
  virtual void axis_status(const AxisStatusSample& sample) = 0;
  virtual void axis_position(const AxisPositionSample& sample) = 0;
  virtual void node_health(const NodeHealthSample& sample) = 0;
  virtual void emergency(const EmergencySample& sample) = 0;
  virtual void drive_status(const DriveStatusSample& sample) = 0;
  // The node is lost (or gone): its axis instances (AxisStatus, AxisPosition and
  // DriveStatus) are disposed.
  virtual void dispose_axes(uint8_t node, uint8_t axes) = 0;
};

}  // namespace stepnode::bridge
