// Decodes TPDOs by the mapping each node really has into per-axis state, and publishes
// AxisStatus when the status changes and AxisPosition for every TPDO that carries a
// position, velocity or phase.
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
// od/axis_objects.hpp and the HP objects 0x2n18/0x2n19).
enum class AxisField : uint8_t {
  None,             // mapped, but not republished (command bits, dummy, other objects)
  StatusBits,       // 0x01 U16
  MotorPosition,    // 0x05 I32
  EncoderPosition,  // 0x06 I32
  Velocity,         // 0x07 I32
  MotionPhase,      // 0x08 U8
  DoneCode,         // 0x18 I8, HP DONE?
  HpError,          // 0x19 U8, HP error number
};

// Axis (0-based) and meaning of a mapped object; field None for anything else.
struct MappedAxisField {
  uint8_t axis = 0;
  AxisField field = AxisField::None;
};
MappedAxisField axis_field_of(const od::MappedEntry& entry);

class TpdoDecoder {
 public:
  explicit TpdoDecoder(SampleSink& sink);

  // The node's TPDOs, axes and PSCALE as discovery read them; replaces what was known.
  // Axis state (last status) is kept: a remap is no reason to republish the status.
  void install(uint8_t node, const NodeInfo& info);
  // The node's TPDOs are no longer decoded (boot-up, lost); its axis state is forgotten so
  // the first status after re-discovery is published again.
  void forget(uint8_t node);
  // One TPDO no longer decoded until the next install (a master is remapping it).
  void suspend(uint8_t node, uint16_t tpdo_number);

  // Values read over SDO (discovery's snapshot). Published where no TPDO has said anything
  // since install(): a TPDO is never overridden by an older SDO read.
  void seed(uint8_t node, const NodeInfo& info, uint64_t can_time_ns);

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
  struct NodeTpdos {
    std::vector<CompiledTpdo> tpdos;
    std::array<AxisState, kMaxAxes> axes{};
    uint8_t axis_count = 0;
  };
  struct Slot {
    uint8_t node = 0;     // 0: no TPDO on this COB-ID
    uint16_t tpdo = 0;    // index into NodeTpdos::tpdos
  };

  Result decode(Slot slot, const ObservedFrame& frame);
  void publish_status(uint8_t node, unsigned axis, uint64_t can_time_ns);
  void publish_position(uint8_t node, unsigned axis, uint64_t can_time_ns);
  void clear_slots(uint8_t node);

  SampleSink& sink_;
  std::array<Slot, 2048> slots_{};
  std::array<NodeTpdos, kNodeIds> nodes_{};
  uint8_t sync_counter_ = 0;
};

}  // namespace stepnode::bridge
