// Decodes TPDOs by the mapping each node really has into per-axis state, and publishes
// AxisStatus when the status changes, AxisPosition for every TPDO that carries a
// position, velocity or phase, and DriveStatus for every TPDO that carries one of a CiA
// 402 axis's objects (6041h statusword, 6061h modes display, 6064h position actual,
// 606Ch velocity actual, 60F4h following error, 603Fh error code, at index + 0x800 * a).
//
// The hot path of the bridge (~80,000 frames/s): a table of 2048 slots indexed by COB-ID
// finds the TPDO; its mapping was compiled at discovery into fields (bit offset, width,
// axis, meaning), so a frame is unpacked with shifts from one 64-bit load. No allocation
// and no string per frame.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "bridge/observer/bus_observer.hpp"
#include "bridge/observer/node_info.hpp"
#include "bridge/samples.hpp"

namespace stepnode::bridge {

// What a mapped axis object means to the bridge (offset in the axis block,
// node/profiles/horner/objects.hpp and the HP objects 0x2n18/0x2n19; the CiA 402 objects
// of node/profiles/cia402/objects.hpp).
enum class AxisField : uint8_t {
  None,             // mapped, but not republished (command bits, dummy, other objects)
  StatusBits,       // 0x01 U16
  MotorPosition,    // 0x05 I32
  EncoderPosition,  // 0x06 I32
  Velocity,         // 0x07 I32
  MotionPhase,      // 0x08 U8
  DoneCode,         // 0x18 I8, HP DONE?
  HpError,          // 0x19 U8, HP error number
  // CiA 402, axis a's object at index + 0x800 * a:
  DriveStatusword,      // 6041h U16
  DriveModeDisplay,     // 6061h I8
  DrivePosition,        // 6064h I32
  DriveVelocity,        // 606Ch I32
  DriveFollowingError,  // 60F4h I32
  DriveErrorCode,       // 603Fh U16
};
constexpr bool is_drive_field(AxisField f) { return f >= AxisField::DriveStatusword; }

// Axis (0-based) and meaning of a mapped object; field None for anything else.
struct MappedAxisField {
  uint8_t axis = 0;
  AxisField field = AxisField::None;
};
MappedAxisField axis_field_of(const od::MappedEntry& entry);

class TpdoDecoder {
 public:
  explicit TpdoDecoder(SampleSink& sink);

  // The node's TPDOs, axes (Horner and CiA 402) and PSCALE as discovery read them; replaces
  // what was known. Axis state (last status) is kept: a remap is no reason to republish the
  // status.
  void install(uint8_t node, const NodeInfo& info);
  // The node's TPDOs are no longer decoded (boot-up, lost); its axis state is forgotten so
  // the first status after re-discovery is published again.
  void forget(uint8_t node);
  // One TPDO no longer decoded until the next install (a master is remapping it).
  void suspend(uint8_t node, uint16_t tpdo_number);

  // Values read over SDO (discovery's snapshot). Published where no TPDO has said anything
  // since install(): a TPDO is never overridden by an older SDO read.
  void seed(uint8_t node, const NodeInfo& info, uint64_t can_time_ns);

  // A value read over SDO after discovery (the observer's refresh of 603Fh): applied and
  // published as a TPDO carrying it would be. Objects that are no drive field of an
  // installed CiA 402 axis are ignored.
  void apply_read(uint8_t node, uint16_t index, uint8_t sub, const od::Bytes& data,
                  uint64_t can_time_ns);
  // CiA 402 axes (bit per 0-based axis) whose 603Fh error code is worth reading over SDO:
  // the statusword's fault bit changed (a fault came or was reset) and no TPDO carries the
  // axis's 603Fh. The call clears them.
  uint8_t take_stale_error_codes(uint8_t node) {
    if (node == 0 || node >= kNodeIds) return 0;
    const uint8_t stale = nodes_[node].error_code_stale;
    nodes_[node].error_code_stale = 0;
    return stale;
  }

  void on_sync(uint8_t counter) { sync_counter_ = counter; }

  enum class Result : uint8_t { NotATpdo, Decoded, TooShort };
  // The node whose TPDO this was is returned in `node` (Decoded or TooShort).
  Result on_frame(const ObservedFrame& frame, uint8_t& node) {
    const uint32_t id = frame.frame.id;
    if (id >= slots_.size()) return Result::NotATpdo;
    const Slot s = slots_[id];
    if (s.node == 0) return Result::NotATpdo;
    node = s.node;
    return decode(s, frame);
  }

 private:
  struct Field {
    uint8_t bit_offset = 0;
    uint8_t bits = 0;
    uint8_t axis = 0;
    AxisField field = AxisField::None;
  };
  struct CompiledTpdo {
    uint16_t number = 0;
    uint16_t cob_id = 0;
    uint8_t bytes = 0;  // the mapping's length: a shorter frame is not applied
    uint8_t field_count = 0;
    bool suspended = false;
    std::array<Field, od::kMaxMappedEntries> fields{};
  };
  struct AxisState {
    bool status_known = false;
    bool position_known = false;  // a position was published since the last forget()
    uint16_t status_bits = 0;
    int8_t done_code = kDoneUnknown;
    uint8_t hp_error = 0;
    int32_t motor_position = 0, encoder_position = 0, velocity = 0;
    uint8_t motion_phase = 0;
    double pscale = 1.0;
  };
  // Bits of DriveAxisState::from_tpdo: which values a TPDO carried since forget().
  enum DriveBit : uint8_t {
    kDriveStatusword = 1,
    kDriveMode = 2,
    kDrivePosition = 4,
    kDriveVelocity = 8,
    kDriveFollowingError = 16,
    kDriveErrorCode = 32,
  };
  struct DriveAxisState {
    uint8_t from_tpdo = 0;  // DriveBit: newer than any SDO snapshot
    bool statusword_known = false;
    uint16_t statusword = 0;
    int8_t mode_display = 0;
    int32_t position_actual = 0, velocity_actual = 0, following_error = 0;
    uint16_t error_code = 0;
  };
  struct NodeTpdos {
    std::vector<CompiledTpdo> tpdos;
    std::array<AxisState, kMaxAxes> axes{};
    std::array<DriveAxisState, kMaxAxes> drives{};
    uint8_t axis_count = 0;
    uint8_t drive_count = 0;
    uint8_t error_code_mapped = 0;  // bit per drive axis: a TPDO carries its 603Fh
    uint8_t error_code_stale = 0;   // see take_stale_error_codes()
  };
  struct Slot {
    uint8_t node = 0;   // 0: no TPDO on this COB-ID
    uint16_t tpdo = 0;  // index into NodeTpdos::tpdos
  };

  Result decode(Slot slot, const ObservedFrame& of);
  void publish_status(uint8_t node, unsigned axis, uint64_t can_time_ns);
  void publish_position(uint8_t node, unsigned axis, uint64_t can_time_ns);
  void publish_drive(uint8_t node, unsigned axis, uint64_t can_time_ns);
  // Sets a drive value (raw: the field's bits, not sign-extended yet); returns the DriveBit.
  static uint8_t set_drive(NodeTpdos& n, unsigned axis, AxisField field, uint64_t raw,
                           unsigned bits);
  void clear_slots(uint8_t node);

  SampleSink& sink_;
  std::array<Slot, 2048> slots_{};
  std::array<NodeTpdos, kNodeIds> nodes_{};
  uint8_t sync_counter_ = 0;
};

}  // namespace stepnode::bridge
