// The list of SDO reads that discovers a node, as a cursor: next() names the read to do,
// on_result() takes its answer and moves on. No SDO client and no time in here, so the
// order and the decisions ("absent" vs "failed, try again") are tested on their own.
//
// Order: heartbeat time 0x1017 first (the heartbeat-loss timeout needs it before a second
// heartbeat was seen), device type 0x1000, identity 0x1018:1..4, name 0x1008; then, for a
// stepnode only, axis blocks 0x2n01 (n = 0.. until "no object"); for a stepnode or a
// device whose 1000h says CiA 402 (bits 0-15 = 0x192), the CiA 402 axes 67FFh + 0x800 * a
// (a = 0.. until "no object"; a 402 device without 67FFh has one axis). A CiA 402 only
// stepnode has no 0x2n01: it is found by its 67FFh. For a device with axes of either
// kind: PSCALE 0x2n11 per Horner axis, and every TPDO 0x1800+k:1 until "no object" with
// the mapping 0x1A00+k:0..n of the valid ones; last, a snapshot of each Horner axis
// (status 0x2n01, DONE? 0x2n18, HP error 0x2n19, motor and encoder position 0x2n05/0x2n06)
// and of each CiA 402 axis (6041h, 6061h, 6064h, 606Ch, 60F4h, 603Fh + 0x800 * a), read
// after the mapping so the TPDO decoder is already live (the caller installs it when
// mapping_read() turns true) and newer TPDO values win.
#pragma once
#include <cstdint>

#include "bridge/observer/node_info.hpp"
#include "od/sdo_client.hpp"

namespace stepnode::bridge {

struct SdoRead {
  uint16_t index = 0;
  uint8_t sub = 0;
  bool operator==(const SdoRead&) const = default;
};

enum class ReadOutcome {
  Value,   // the node answered with a value
  Absent,  // the node says the object cannot be read: taken as "not there"
  Failed,  // no usable answer (timeout, busy, protocol error): the same read again later
};

// How an SDO result is taken: the server's "no object / no sub-index / no access" answers
// mean absent; timeouts, client-detected errors and 0x0800xxxx (general, device state)
// are transient and retried.
ReadOutcome classify(const od::SdoResult& result);

class DiscoveryPlan {
 public:
  DiscoveryPlan() { restart_all(); }

  // From the first read: after a boot-up, or a node seen again after it was lost.
  void restart_all();
  // Only the TPDO parameters again (another master remapped one). Identity and axes are
  // kept. No effect before the TPDO phase (it is still to come) or on a device without
  // axes (its TPDOs are not decoded).
  void restart_tpdos();
  // Only the heartbeat time 0x1017 again (another master wrote it), before whatever is
  // still to read. Everything else is kept: the node is the same.
  void reread_heartbeat_time();
  // Counts the restarts above: a read started before one is answered for a cursor that
  // has moved (a channel of the bridge's own is not interrupted by the master's write),
  // so its answer must not be taken.
  uint32_t epoch() const { return epoch_; }

  // Discovery is complete (a 0x1017 read again may follow: wants_read()).
  bool finished() const { return phase_ == Phase::Done; }
  bool wants_read() const { return phase_ != Phase::Done || heartbeat_reread_; }
  // True once the TPDO parameters are read (the snapshot may still be in progress).
  bool mapping_read() const { return phase_ >= Phase::Snapshot; }
  SdoRead next() const;  // only while wants_read()
  ReadOutcome on_result(const od::SdoResult& result);

  const NodeInfo& info() const { return info_; }

 private:
  enum class Phase : uint8_t {
    HeartbeatTime,
    DeviceType,
    Identity,
    Name,
    AxisProbe,
    DriveProbe,
    Pscale,
    TpdoComm,
    TpdoCount,
    TpdoEntry,
    Snapshot,
    DriveSnapshot,
    Done,
  };
  // The size of the value next() reads, from its data type (0: variable, a string).
  size_t type_size() const;
  void value(const od::Bytes& data);
  void heartbeat_time_value(const od::Bytes& data);
  static std::string device_name(const od::Bytes& data);
  static double pscale(const od::Bytes& data);
  void absent();
  void after_name();
  void after_axes();
  void after_drives();
  void to_pscale_or_tpdos();
  void next_tpdo();
  void tpdos_done();
  void snapshot_value(const od::Bytes& d);
  void drive_snapshot_value(const od::Bytes& d);
  void next_snapshot();
  void next_drive_snapshot();

  Phase phase_ = Phase::HeartbeatTime;
  bool heartbeat_reread_ = false;
  uint32_t epoch_ = 0;
  uint16_t k_ = 0;  // identity sub, axis or TPDO number, by phase
  // (entry_ is also the item of the axis being read in the snapshot phases)
  uint8_t entry_ = 0;            // mapping entry being read (1-based)
  uint8_t count_ = 0;            // mapping entries of TPDO k_
  bool snapshot_wanted_ = true;  // not after a remap: the values are known then
  TpdoInfo pending_;             // the TPDO being read
  std::vector<TpdoInfo> new_tpdos_;
  NodeInfo info_;
};

}  // namespace stepnode::bridge
