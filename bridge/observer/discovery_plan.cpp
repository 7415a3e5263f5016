#include "bridge/observer/discovery_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>

#include "node/profiles/cia402/objects.hpp"
#include "node/profiles/horner/objects.hpp"

namespace stepnode::bridge {
namespace {

using od::SdoAbort;

constexpr uint16_t kDeviceType = 0x1000;
constexpr uint16_t kHeartbeatTime = 0x1017;
constexpr uint16_t kIdentity = 0x1018;
constexpr uint16_t kDeviceName = 0x1008;
constexpr uint16_t kTpdoComm = 0x1800;
constexpr uint16_t kTpdoMap = 0x1A00;
constexpr uint32_t kCobInvalid = 0x80000000u;
constexpr uint32_t kCobExtended = 0x20000000u;
// HP 44714A PSCALE (REAL64, user units per step), one per axis block.
constexpr uint16_t kPscaleOffset = 0x11;
constexpr size_t kMaxNameLength = 255;
// What the snapshot reads of each axis, in this order.
constexpr uint16_t kSnapshotOffsets[] = {0x01, 0x18, 0x19, 0x05, 0x06};
constexpr uint8_t kSnapshotItems = std::size(kSnapshotOffsets);
constexpr size_t kSnapshotSizes[kSnapshotItems] = {2, 1, 1, 4, 4};
// What the snapshot reads of each CiA 402 axis (axis 1 indices), in this order.
constexpr uint16_t kDriveSnapshotObjects[] = {
    cia402::obj::kStatusword,           cia402::obj::kModesOfOperationDisplay,
    cia402::obj::kPositionActual,       cia402::obj::kVelocityActual,
    cia402::obj::kFollowingErrorActual, cia402::obj::kErrorCode};
constexpr uint8_t kDriveSnapshotItems = std::size(kDriveSnapshotObjects);
constexpr size_t kDriveSnapshotSizes[kDriveSnapshotItems] = {2, 1, 4, 4, 4, 2};

// Little-endian unsigned of exactly `size` bytes; a value of another size is a device
// error that retrying will not fix, so the caller takes it as absent.
bool exact_u32(const od::Bytes& d, size_t size, uint32_t& out) {
  if (d.size() != size) return false;
  out = 0;
  for (size_t i = 0; i < size; ++i) out |= static_cast<uint32_t>(d[i]) << (8 * i);
  return true;
}

}  // namespace

ReadOutcome classify(const od::SdoResult& r) {
  if (r.ok()) return ReadOutcome::Value;
  if (!r.aborted_by_server) return ReadOutcome::Failed;
  // 0x0601xxxx access, 0x0602xxxx no object, 0x0609xxxx sub-index/value: the node means it.
  const uint32_t code = static_cast<uint32_t>(r.abort);
  const uint32_t group = code >> 16;
  if (group == 0x0601 || group == 0x0602 || group == 0x0609) return ReadOutcome::Absent;
  return ReadOutcome::Failed;
}

void DiscoveryPlan::restart_all() {
  ++epoch_;
  heartbeat_reread_ = false;
  phase_ = Phase::HeartbeatTime;
  snapshot_wanted_ = true;
  k_ = 0;
  entry_ = count_ = 0;
  new_tpdos_.clear();
  info_ = NodeInfo{};
}

void DiscoveryPlan::restart_tpdos() {
  if (phase_ < Phase::TpdoComm || !info_.has_axes()) return;
  ++epoch_;
  // The snapshot is read again only when the remap came before it was finished.
  if (phase_ == Phase::Done) {
    snapshot_wanted_ = false;
    info_.snapshot = {};  // the caller seeds from it at the end: nothing stale
    info_.drive_snapshot = {};
  }
  phase_ = Phase::TpdoComm;
  k_ = 0;
  entry_ = count_ = 0;
  new_tpdos_.clear();
}

void DiscoveryPlan::reread_heartbeat_time() {
  ++epoch_;
  // Until it is read, the old period says nothing of the new one.
  info_.heartbeat_period_ms = 0;
  info_.heartbeat_period_read = false;
  if (phase_ != Phase::HeartbeatTime) heartbeat_reread_ = true;  // else it is next anyway
}

SdoRead DiscoveryPlan::next() const {
  if (heartbeat_reread_) return {kHeartbeatTime, 0};
  switch (phase_) {
    case Phase::HeartbeatTime: return {kHeartbeatTime, 0};
    case Phase::DeviceType: return {kDeviceType, 0};
    case Phase::Identity: return {kIdentity, static_cast<uint8_t>(k_)};
    case Phase::Name: return {kDeviceName, 0};
    case Phase::AxisProbe: return {horner::obj::index(k_, horner::obj::kStatusBits), 0};
    case Phase::DriveProbe: return {cia402::obj::index(k_, cia402::obj::kSingleDeviceType), 0};
    case Phase::Pscale: return {horner::obj::index(k_, kPscaleOffset), 0};
    case Phase::TpdoComm: return {static_cast<uint16_t>(kTpdoComm + k_), 1};
    case Phase::TpdoCount: return {static_cast<uint16_t>(kTpdoMap + k_), 0};
    case Phase::TpdoEntry: return {static_cast<uint16_t>(kTpdoMap + k_), entry_};
    case Phase::Snapshot: return {horner::obj::index(k_, kSnapshotOffsets[entry_]), 0};
    case Phase::DriveSnapshot: return {cia402::obj::index(k_, kDriveSnapshotObjects[entry_]), 0};
    case Phase::Done: break;
  }
  return {};
}

ReadOutcome DiscoveryPlan::on_result(const od::SdoResult& result) {
  if (!wants_read()) return ReadOutcome::Failed;
  const ReadOutcome outcome = classify(result);
  if (outcome == ReadOutcome::Failed) return outcome;  // the same read is repeated
  const od::Bytes data = result.value_of_size(type_size());
  if (heartbeat_reread_) {
    heartbeat_reread_ = false;
    if (outcome == ReadOutcome::Value) heartbeat_time_value(data);
  } else if (outcome == ReadOutcome::Value) {
    value(data);
  } else {
    absent();
  }
  return outcome;
}

size_t DiscoveryPlan::type_size() const {
  if (heartbeat_reread_) return 2;
  switch (phase_) {
    case Phase::HeartbeatTime: return 2;  // UNSIGNED16
    case Phase::TpdoCount: return 1;      // UNSIGNED8
    case Phase::DeviceType:
    case Phase::Identity:
    case Phase::TpdoComm:
    case Phase::TpdoEntry: return 4;  // UNSIGNED32
    case Phase::Snapshot: return kSnapshotSizes[entry_];
    case Phase::DriveSnapshot: return kDriveSnapshotSizes[entry_];
    default: return 0;  // the name (a string), the probes (any answer), PSCALE (REAL64)
  }
}

// 0x1008, VISIBLE_STRING; some devices pad with NULs. A name is short: a node that sends
// kilobytes does not get them all republished in every NodeHealth. Cut at the first NUL;
// VISIBLE_STRING is ISO 646, so any other byte becomes '?' (NodeHealth's string must be
// valid UTF-8 for its readers, and printable).
std::string DiscoveryPlan::device_name(const od::Bytes& d) {
  size_t n = std::min<size_t>(d.size(), kMaxNameLength);
  n = static_cast<size_t>(std::find(d.begin(), d.begin() + static_cast<long>(n), 0) - d.begin());
  std::string name;
  for (size_t i = 0; i < n; ++i)
    name += d[i] >= 0x20 && d[i] <= 0x7E ? static_cast<char>(d[i]) : '?';
  return name;
}

// An HP channel's PSCALE (REAL64). A zero or non-finite scale would turn every position
// into nonsense: 1.0 then, as for one that cannot be read.
double DiscoveryPlan::pscale(const od::Bytes& d) {
  double scale = 1.0;
  if (d.size() == sizeof(double)) std::memcpy(&scale, d.data(), sizeof(double));
  return (std::isfinite(scale) && scale != 0.0) ? scale : 1.0;
}

void DiscoveryPlan::value(const od::Bytes& d) {
  uint32_t v = 0;
  switch (phase_) {
    case Phase::HeartbeatTime:
      heartbeat_time_value(d);
      phase_ = Phase::DeviceType;
      return;
    case Phase::DeviceType:
      if (exact_u32(d, 4, v)) {
        info_.device_type = v;
        info_.device_type_read = true;
      }
      phase_ = Phase::Identity;
      k_ = 1;
      return;
    case Phase::Identity:
      if (exact_u32(d, 4, v)) {
        info_.identity_read = true;
        uint32_t* field[] = {&info_.vendor_id, &info_.product_code, &info_.revision, &info_.serial};
        *field[k_ - 1] = v;
      }
      if (++k_ > 4) phase_ = Phase::Name;
      return;
    case Phase::Name: info_.device_name = device_name(d); return after_name();
    case Phase::AxisProbe:
      info_.axes = static_cast<uint8_t>(k_ + 1);
      if (++k_ >= kMaxAxes) after_axes();
      return;
    case Phase::DriveProbe:
      info_.drive_axes = static_cast<uint8_t>(k_ + 1);
      if (++k_ >= kMaxAxes) after_drives();
      return;
    case Phase::Pscale:
      info_.pscale[k_] = pscale(d);
      if (++k_ >= info_.axes) {
        phase_ = Phase::TpdoComm;
        k_ = 0;
      }
      return;
    case Phase::TpdoComm:
      // Bit 29: a 29-bit CAN-ID, which the bridge does not receive (and whose low 11 bits
      // would name another frame).
      if (!exact_u32(d, 4, v) || (v & (kCobInvalid | kCobExtended))) return next_tpdo();
      pending_ = TpdoInfo{k_, static_cast<uint16_t>(v & 0x7FF), {}};
      phase_ = Phase::TpdoCount;
      return;
    case Phase::TpdoCount:
      count_ = d.size() == 1 ? std::min<uint8_t>(d[0], od::kMaxMappedEntries) : 0;
      if (count_ == 0) {
        new_tpdos_.push_back(pending_);  // a valid TPDO with nothing mapped: known, empty
        return next_tpdo();
      }
      entry_ = 1;
      phase_ = Phase::TpdoEntry;
      return;
    case Phase::TpdoEntry:
      if (!exact_u32(d, 4, v)) return next_tpdo();  // unreadable mapping: not decoded
      pending_.mapping.push_back(od::MappedEntry::from_word(v));
      if (++entry_ > count_) {
        new_tpdos_.push_back(std::move(pending_));
        next_tpdo();
      }
      return;
    case Phase::Snapshot: snapshot_value(d); return next_snapshot();
    case Phase::DriveSnapshot: drive_snapshot_value(d); return next_drive_snapshot();
    case Phase::Done: return;
  }
}

void DiscoveryPlan::heartbeat_time_value(const od::Bytes& d) {
  uint32_t v = 0;
  if (!exact_u32(d, 2, v)) return;
  info_.heartbeat_period_ms = static_cast<uint16_t>(v);
  info_.heartbeat_period_read = true;
}

void DiscoveryPlan::absent() {
  switch (phase_) {
    case Phase::HeartbeatTime: phase_ = Phase::DeviceType; return;
    case Phase::DeviceType:
      phase_ = Phase::Identity;
      k_ = 1;
      return;
    case Phase::Identity:
      // No identity object at all: the other sub-indices are not there either.
      if (k_ == 1 || ++k_ > 4) phase_ = Phase::Name;
      return;
    case Phase::Name: return after_name();
    case Phase::AxisProbe: return after_axes();
    case Phase::DriveProbe: return after_drives();
    case Phase::Pscale:
      info_.pscale[k_] = 1.0;
      if (++k_ >= info_.axes) {
        phase_ = Phase::TpdoComm;
        k_ = 0;
      }
      return;
    case Phase::TpdoComm: return tpdos_done();  // no more TPDOs
    case Phase::TpdoCount:
    case Phase::TpdoEntry: return next_tpdo();     // this TPDO's mapping unreadable: skipped
    case Phase::Snapshot: return next_snapshot();  // e.g. no HP objects on this node
    case Phase::DriveSnapshot: return next_drive_snapshot();  // e.g. no 60F4h
    case Phase::Done: return;
  }
}

void DiscoveryPlan::after_name() {
  // Only a stepnode has axis blocks worth probing; a third-party device's 0x2001 means
  // something else entirely. A third-party CiA 402 drive has its standard objects.
  k_ = 0;
  if (info_.product_code == kStepnodeProductCode) phase_ = Phase::AxisProbe;
  else if (info_.device_type_is_cia402()) phase_ = Phase::DriveProbe;
  else phase_ = Phase::Done;
}

void DiscoveryPlan::after_axes() {
  // A stepnode (the only way here): its CiA 402 axes, if the profile is on. The probe is
  // made whatever 1000h said: 67FFh is what says it per axis.
  phase_ = Phase::DriveProbe;
  k_ = 0;
}

void DiscoveryPlan::after_drives() {
  // 67FFh is for devices with several axes; a single-axis drive may leave it out.
  if (info_.drive_axes == 0 && info_.device_type_is_cia402()) info_.drive_axes = 1;
  if (!info_.has_axes()) {  // "STEP" product code without 0x2001 or 67FFh: not ours after all
    phase_ = Phase::Done;
    return;
  }
  to_pscale_or_tpdos();
}

void DiscoveryPlan::to_pscale_or_tpdos() {
  k_ = 0;
  phase_ = info_.axes > 0 ? Phase::Pscale : Phase::TpdoComm;
}

void DiscoveryPlan::next_tpdo() {
  entry_ = count_ = 0;
  if (++k_ >= kMaxTpdos) return tpdos_done();
  phase_ = Phase::TpdoComm;
}

void DiscoveryPlan::tpdos_done() {
  // The new mapping replaces the old one at once, never entry by entry.
  info_.tpdos = std::move(new_tpdos_);
  new_tpdos_.clear();
  if (!snapshot_wanted_) {
    phase_ = Phase::Done;
    return;
  }
  info_.snapshot = {};
  info_.drive_snapshot = {};
  k_ = 0;
  entry_ = 0;
  if (info_.axes > 0) phase_ = Phase::Snapshot;
  else if (info_.drive_axes > 0) phase_ = Phase::DriveSnapshot;
  else phase_ = Phase::Done;
}

void DiscoveryPlan::snapshot_value(const od::Bytes& d) {
  AxisSnapshot& s = info_.snapshot[k_];
  uint32_t v = 0;
  const size_t size = kSnapshotSizes[entry_];  // the item's data type (type_size())
  switch (kSnapshotOffsets[entry_]) {
    case 0x01:
      if ((s.status_read = exact_u32(d, size, v))) s.status_bits = static_cast<uint16_t>(v);
      break;
    case 0x18:
      if ((s.done_read = exact_u32(d, size, v))) s.done_code = static_cast<int8_t>(v);
      break;
    case 0x19:
      if ((s.hp_error_read = exact_u32(d, size, v))) s.hp_error = static_cast<uint8_t>(v);
      break;
    case 0x05:
      if ((s.motor_read = exact_u32(d, size, v))) s.motor_position = static_cast<int32_t>(v);
      break;
    case 0x06:
      if ((s.encoder_read = exact_u32(d, size, v))) s.encoder_position = static_cast<int32_t>(v);
      break;
  }
}

void DiscoveryPlan::next_snapshot() {
  if (++entry_ < kSnapshotItems) return;
  entry_ = 0;
  if (++k_ < info_.axes) return;
  k_ = 0;
  phase_ = info_.drive_axes > 0 ? Phase::DriveSnapshot : Phase::Done;
}

void DiscoveryPlan::drive_snapshot_value(const od::Bytes& d) {
  DriveSnapshot& s = info_.drive_snapshot[k_];
  uint32_t v = 0;
  const size_t size = kDriveSnapshotSizes[entry_];  // the item's data type (type_size())
  switch (kDriveSnapshotObjects[entry_]) {
    case cia402::obj::kStatusword:
      if ((s.statusword_read = exact_u32(d, size, v))) s.statusword = static_cast<uint16_t>(v);
      break;
    case cia402::obj::kModesOfOperationDisplay:
      if ((s.mode_read = exact_u32(d, size, v))) s.mode_display = static_cast<int8_t>(v);
      break;
    case cia402::obj::kPositionActual:
      if ((s.position_read = exact_u32(d, size, v))) s.position_actual = static_cast<int32_t>(v);
      break;
    case cia402::obj::kVelocityActual:
      if ((s.velocity_read = exact_u32(d, size, v))) s.velocity_actual = static_cast<int32_t>(v);
      break;
    case cia402::obj::kFollowingErrorActual:
      if ((s.following_error_read = exact_u32(d, size, v)))
        s.following_error = static_cast<int32_t>(v);
      break;
    case cia402::obj::kErrorCode:
      if ((s.error_code_read = exact_u32(d, size, v))) s.error_code = static_cast<uint16_t>(v);
      break;
  }
}

void DiscoveryPlan::next_drive_snapshot() {
  if (++entry_ < kDriveSnapshotItems) return;
  entry_ = 0;
  if (++k_ >= info_.drive_axes) phase_ = Phase::Done;
}

}  // namespace stepnode::bridge
