#include "bridge/observer/tpdo_decoder.hpp"

#include "node/profiles/cia402/objects.hpp"
#include "node/profiles/horner/objects.hpp"

namespace stepnode::bridge {
namespace {

constexpr uint16_t kAxisBlocksFirst = 0x2000;
constexpr uint16_t kAxisBlocksLast = 0x2000 + 0x100 * kMaxAxes - 1;
constexpr uint16_t kDoneCodeOffset = 0x18;
constexpr uint16_t kHpErrorOffset = 0x19;
constexpr uint16_t kDriveFirst = 0x6000;
constexpr uint16_t kDriveLast = kDriveFirst + cia402::kAxisOffset * kMaxAxes - 1;  // 0x9FFF
constexpr uint16_t kStatuswordFault = 1u << 3;                                     // 6041h bit 3

MappedAxisField drive_field_of(const od::MappedEntry& e) {
  const auto axis = static_cast<uint8_t>((e.index - kDriveFirst) / cia402::kAxisOffset);
  const auto base =
      static_cast<uint16_t>(kDriveFirst + (e.index - kDriveFirst) % cia402::kAxisOffset);
  using namespace cia402::obj;
  switch (base) {
    case kStatusword: return {axis, AxisField::DriveStatusword};
    case kModesOfOperationDisplay: return {axis, AxisField::DriveModeDisplay};
    case kPositionActual: return {axis, AxisField::DrivePosition};
    case kVelocityActual: return {axis, AxisField::DriveVelocity};
    case kFollowingErrorActual: return {axis, AxisField::DriveFollowingError};
    case kErrorCode: return {axis, AxisField::DriveErrorCode};
    default: return {};
  }
}

int64_t sign_extend(uint64_t v, unsigned bits) {
  if (bits == 0 || bits >= 64) return static_cast<int64_t>(v);
  const uint64_t sign = uint64_t{1} << (bits - 1);
  return static_cast<int64_t>((v ^ sign) - sign);
}

}  // namespace

MappedAxisField axis_field_of(const od::MappedEntry& e) {
  if (e.sub != 0) return {};
  if (e.index >= kDriveFirst && e.index <= kDriveLast) return drive_field_of(e);
  if (e.index < kAxisBlocksFirst || e.index > kAxisBlocksLast) return {};
  const auto axis = static_cast<uint8_t>((e.index - kAxisBlocksFirst) >> 8);
  using namespace horner::obj;
  switch (e.index & 0xFF) {
    case kStatusBits: return {axis, AxisField::StatusBits};
    case kMotorPosition: return {axis, AxisField::MotorPosition};
    case kEncoderPosition: return {axis, AxisField::EncoderPosition};
    case kVelocity: return {axis, AxisField::Velocity};
    case kMotionPhase: return {axis, AxisField::MotionPhase};
    case kDoneCodeOffset: return {axis, AxisField::DoneCode};
    case kHpErrorOffset: return {axis, AxisField::HpError};
    default: return {};
  }
}

TpdoDecoder::TpdoDecoder(SampleSink& sink) : sink_(sink) {}

void TpdoDecoder::clear_slots(uint8_t node) {
  for (const CompiledTpdo& t : nodes_[node].tpdos)
    if (slots_[t.cob_id].node == node) slots_[t.cob_id] = Slot{};
}

void TpdoDecoder::install(uint8_t node, const NodeInfo& info) {
  if (node == 0 || node >= kNodeIds) return;
  clear_slots(node);
  NodeTpdos& n = nodes_[node];
  n.tpdos.clear();
  n.axis_count = info.axes;
  n.drive_count = info.drive_axes;
  n.error_code_mapped = 0;
  for (unsigned a = 0; a < kMaxAxes; ++a) n.axes[a].pscale = info.pscale[a];
  for (const TpdoInfo& t : info.tpdos) {
    // CiA 301 limits a mapping to 64 bits; a longer one cannot come from a real device and
    // would not fit the 64-bit unpacking below.
    if (od::mapping_bits(t.mapping) > od::kMaxPdoBits || t.cob_id >= slots_.size()) continue;
    CompiledTpdo c;
    c.number = t.number;
    c.cob_id = t.cob_id;
    c.bytes = static_cast<uint8_t>(od::mapping_bytes(t.mapping));
    unsigned offset = 0;
    for (const od::MappedEntry& e : t.mapping) {
      const MappedAxisField m = axis_field_of(e);
      const unsigned axes = is_drive_field(m.field) ? info.drive_axes : info.axes;
      if (m.field != AxisField::None && m.axis < axes && e.bits > 0 &&
          c.field_count < c.fields.size()) {
        c.fields[c.field_count++] = Field{static_cast<uint8_t>(offset), e.bits, m.axis, m.field};
        if (m.field == AxisField::DriveErrorCode)
          n.error_code_mapped |= static_cast<uint8_t>(1u << m.axis);
      }
      offset += e.bits;
    }
    n.tpdos.push_back(c);
  }
  for (size_t i = 0; i < n.tpdos.size(); ++i) {
    // Two nodes on one COB-ID is a bus configuration error; the later-discovered wins.
    Slot& s = slots_[n.tpdos[i].cob_id];
    if (s.node != 0 && s.node != node) {
      NodeTpdos& other = nodes_[s.node];
      for (CompiledTpdo& t : other.tpdos)
        if (t.cob_id == n.tpdos[i].cob_id) t.suspended = true;
    }
    s = Slot{node, static_cast<uint16_t>(i)};
  }
}

void TpdoDecoder::forget(uint8_t node) {
  if (node == 0 || node >= kNodeIds) return;
  clear_slots(node);
  NodeTpdos& n = nodes_[node];
  n.tpdos.clear();
  for (AxisState& a : n.axes) {
    const double pscale = a.pscale;
    a = AxisState{};
    a.pscale = pscale;
  }
  n.drives = {};
  n.error_code_stale = 0;
}

void TpdoDecoder::suspend(uint8_t node, uint16_t tpdo_number) {
  if (node == 0 || node >= kNodeIds) return;
  for (CompiledTpdo& t : nodes_[node].tpdos)
    if (t.number == tpdo_number) t.suspended = true;
}

TpdoDecoder::Result TpdoDecoder::decode(Slot slot, const ObservedFrame& of) {
  NodeTpdos& n = nodes_[slot.node];
  const CompiledTpdo& t = n.tpdos[slot.tpdo];
  if (t.suspended) return Result::NotATpdo;
  const od::CanFrame& f = of.frame;
  if (f.dlc < t.bytes) return Result::TooShort;  // CiA 301: not processed, nothing applied

  uint64_t raw = 0;
  for (unsigned i = 0; i < 8; ++i) raw |= uint64_t{f.data[i]} << (8 * i);

  uint8_t status_changed = 0, position_touched = 0, drive_touched = 0;  // bit per axis
  for (unsigned i = 0; i < t.field_count; ++i) {
    const Field& fl = t.fields[i];
    uint64_t v = raw >> fl.bit_offset;
    if (fl.bits < 64) v &= (uint64_t{1} << fl.bits) - 1;
    AxisState& a = n.axes[fl.axis];
    const uint8_t bit = static_cast<uint8_t>(1u << fl.axis);
    switch (fl.field) {
      case AxisField::StatusBits: {
        const auto s = static_cast<uint16_t>(v);
        if (!a.status_known || s != a.status_bits) status_changed |= bit;
        a.status_bits = s;
        a.status_known = true;
        break;
      }
      case AxisField::DoneCode: {
        const auto d = static_cast<int8_t>(sign_extend(v, fl.bits));
        if (d != a.done_code) status_changed |= bit;
        a.done_code = d;
        break;
      }
      case AxisField::HpError: {
        const auto e = static_cast<uint8_t>(v);
        if (e != a.hp_error) status_changed |= bit;
        a.hp_error = e;
        break;
      }
      case AxisField::MotorPosition:
        a.motor_position = static_cast<int32_t>(sign_extend(v, fl.bits));
        position_touched |= bit;
        break;
      case AxisField::EncoderPosition:
        a.encoder_position = static_cast<int32_t>(sign_extend(v, fl.bits));
        position_touched |= bit;
        break;
      case AxisField::Velocity:
        a.velocity = static_cast<int32_t>(sign_extend(v, fl.bits));
        position_touched |= bit;
        break;
      case AxisField::MotionPhase:
        a.motion_phase = static_cast<uint8_t>(v);
        position_touched |= bit;
        break;
      case AxisField::DriveStatusword:
      case AxisField::DriveModeDisplay:
      case AxisField::DrivePosition:
      case AxisField::DriveVelocity:
      case AxisField::DriveFollowingError:
      case AxisField::DriveErrorCode:
        n.drives[fl.axis].from_tpdo |= set_drive(n, fl.axis, fl.field, v, fl.bits);
        drive_touched |= bit;
        break;
      case AxisField::None: break;
    }
  }

  for (unsigned ax = 0; status_changed && ax < kMaxAxes; ++ax)
    if (status_changed & (1u << ax)) publish_status(slot.node, ax, of.can_time_ns);
  for (unsigned ax = 0; position_touched && ax < kMaxAxes; ++ax)
    if (position_touched & (1u << ax)) publish_position(slot.node, ax, of.can_time_ns);
  for (unsigned ax = 0; drive_touched && ax < kMaxAxes; ++ax)
    if (drive_touched & (1u << ax)) publish_drive(slot.node, ax, of.can_time_ns);
  return Result::Decoded;
}

uint8_t TpdoDecoder::set_drive(NodeTpdos& n, unsigned axis, AxisField field, uint64_t raw,
                               unsigned bits) {
  DriveAxisState& d = n.drives[axis];
  const auto i32 = [&] { return static_cast<int32_t>(sign_extend(raw, bits)); };
  switch (field) {
    case AxisField::DriveStatusword: {
      const auto s = static_cast<uint16_t>(raw);
      // A fault came or was reset: 603Fh changed with it (unless a TPDO brings it anyway).
      const uint16_t fault_edge = (d.statusword_known ? d.statusword ^ s : s) & kStatuswordFault;
      if (fault_edge && !(n.error_code_mapped & (1u << axis)))
        n.error_code_stale |= static_cast<uint8_t>(1u << axis);
      d.statusword = s;
      d.statusword_known = true;
      return kDriveStatusword;
    }
    case AxisField::DriveModeDisplay:
      d.mode_display = static_cast<int8_t>(sign_extend(raw, bits));
      return kDriveMode;
    case AxisField::DrivePosition: d.position_actual = i32(); return kDrivePosition;
    case AxisField::DriveVelocity: d.velocity_actual = i32(); return kDriveVelocity;
    case AxisField::DriveFollowingError: d.following_error = i32(); return kDriveFollowingError;
    case AxisField::DriveErrorCode:
      d.error_code = static_cast<uint16_t>(raw);
      return kDriveErrorCode;
    default: return 0;
  }
}

void TpdoDecoder::apply_read(uint8_t node, uint16_t index, uint8_t sub, const od::Bytes& data,
                             uint64_t can_time_ns) {
  if (node == 0 || node >= kNodeIds || data.empty() || data.size() > 4) return;
  NodeTpdos& n = nodes_[node];
  const auto bits = static_cast<uint8_t>(8 * data.size());
  const MappedAxisField m = axis_field_of(od::MappedEntry{index, sub, bits});
  if (!is_drive_field(m.field) || m.axis >= n.drive_count) return;
  uint64_t v = 0;
  for (size_t i = 0; i < data.size(); ++i) v |= uint64_t{data[i]} << (8 * i);
  set_drive(n, m.axis, m.field, v, bits);
  // (the stale mark a statusword read could set is not wanted: this is already a read)
  if (m.field == AxisField::DriveStatusword)
    n.error_code_stale &= static_cast<uint8_t>(~(1u << m.axis));
  publish_drive(node, m.axis, can_time_ns);
}

}  // namespace stepnode::bridge

namespace stepnode::bridge {

void TpdoDecoder::publish_status(uint8_t node, unsigned axis, uint64_t can_time_ns) {
  const AxisState& a = nodes_[node].axes[axis];
  AxisStatusSample s;
  s.node = node;
  s.axis = static_cast<uint8_t>(axis + 1);
  s.status_bits = a.status_bits;
  s.done_code = a.done_code;
  s.hp_error = a.hp_error;
  s.can_time_ns = can_time_ns;
  sink_.axis_status(s);
}

void TpdoDecoder::publish_position(uint8_t node, unsigned axis, uint64_t can_time_ns) {
  AxisState& a = nodes_[node].axes[axis];
  a.position_known = true;
  AxisPositionSample p;
  p.node = node;
  p.axis = static_cast<uint8_t>(axis + 1);
  p.motor_position = a.motor_position;
  p.encoder_position = a.encoder_position;
  // PSCALE is user units per step. The encoder gets the same scale: the bridge reads no
  // separate encoder scale, so with PSCALE 1 both stay in their own counts.
  p.motor_user_units = a.motor_position * a.pscale;
  p.encoder_user_units = a.encoder_position * a.pscale;
  p.velocity = a.velocity;
  p.motion_phase = a.motion_phase;
  p.sync_counter = sync_counter_;
  p.can_time_ns = can_time_ns;
  sink_.axis_position(p);
}

void TpdoDecoder::publish_drive(uint8_t node, unsigned axis, uint64_t can_time_ns) {
  const DriveAxisState& d = nodes_[node].drives[axis];
  DriveStatusSample s;
  s.node = node;
  s.axis = static_cast<uint8_t>(axis + 1);
  s.statusword_known = d.statusword_known;
  s.statusword = d.statusword;
  s.mode_display = d.mode_display;
  s.position_actual = d.position_actual;
  s.velocity_actual = d.velocity_actual;
  s.following_error = d.following_error;
  s.error_code = d.error_code;
  s.can_time_ns = can_time_ns;
  sink_.drive_status(s);
}

void TpdoDecoder::seed(uint8_t node, const NodeInfo& info, uint64_t can_time_ns) {
  if (node == 0 || node >= kNodeIds) return;
  NodeTpdos& n = nodes_[node];
  for (unsigned ax = 0; ax < info.axes && ax < kMaxAxes; ++ax) {
    const AxisSnapshot& snap = info.snapshot[ax];
    AxisState& a = n.axes[ax];
    if (!a.status_known && snap.status_read) {
      a.status_known = true;
      a.status_bits = snap.status_bits;
      if (snap.done_read) a.done_code = snap.done_code;
      if (snap.hp_error_read) a.hp_error = snap.hp_error;
      publish_status(node, ax, can_time_ns);
    }
    if (!a.position_known && snap.motor_read && snap.encoder_read) {
      a.motor_position = snap.motor_position;
      a.encoder_position = snap.encoder_position;
      publish_position(node, ax, can_time_ns);
    }
  }
  // CiA 402 axes: each value a TPDO has not brought since install() (a TPDO is newer).
  for (unsigned ax = 0; ax < info.drive_axes && ax < kMaxAxes; ++ax) {
    const DriveSnapshot& snap = info.drive_snapshot[ax];
    DriveAxisState& d = n.drives[ax];
    bool seeded = false;
    auto take = [&](bool read, DriveBit bit, auto& field, auto value) {
      if (!read || (d.from_tpdo & bit)) return;
      field = value;
      seeded = true;
    };
    if (snap.statusword_read && !(d.from_tpdo & kDriveStatusword)) d.statusword_known = true;
    take(snap.statusword_read, kDriveStatusword, d.statusword, snap.statusword);
    take(snap.mode_read, kDriveMode, d.mode_display, snap.mode_display);
    take(snap.position_read, kDrivePosition, d.position_actual, snap.position_actual);
    take(snap.velocity_read, kDriveVelocity, d.velocity_actual, snap.velocity_actual);
    take(snap.following_error_read, kDriveFollowingError, d.following_error, snap.following_error);
    take(snap.error_code_read, kDriveErrorCode, d.error_code, snap.error_code);
    if (seeded) publish_drive(node, ax, can_time_ns);
  }
}

}  // namespace stepnode::bridge
