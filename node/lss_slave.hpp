// LSS slave (CiA 305 V3.0): the layer setting services a master uses to find a device by
// its identity (0x1018) and give it a node-ID and a bit timing. Pure frame logic: a request
// on 0x7E5 goes in, its answer on 0x7E4 comes out of the same call (never deferred, so a
// master's back-to-back requests each get theirs), and what the node must do about it
// (boot, store) is returned or asked of a hook. No sockets, no clocks, no files.
#pragma once
#include <cstdint>
#include <functional>
#include <optional>

#include "od/can_frame.hpp"

namespace stepnode::node {
namespace lss {

constexpr uint32_t kMasterToSlave = 0x7E5;  // LSS master -> slaves (CiA 305 5.1)
constexpr uint32_t kSlaveToMaster = 0x7E4;  // LSS slave -> master
// "Node-ID invalid": the device has none and waits for LSS (CiA 305, configure node-ID).
constexpr uint8_t kUnconfigured = 0xFF;

// Command specifiers (CiA 305 V3.0, clause 6).
namespace cs {
constexpr uint8_t kSwitchStateGlobal = 0x04;
constexpr uint8_t kConfigureNodeId = 0x11;
constexpr uint8_t kConfigureBitTiming = 0x13;
constexpr uint8_t kActivateBitTiming = 0x15;
constexpr uint8_t kStoreConfiguration = 0x17;
constexpr uint8_t kSwitchSelectiveVendor = 0x40;
constexpr uint8_t kSwitchSelectiveProduct = 0x41;
constexpr uint8_t kSwitchSelectiveRevision = 0x42;
constexpr uint8_t kSwitchSelectiveSerial = 0x43;
constexpr uint8_t kSwitchSelectiveResponse = 0x44;
constexpr uint8_t kIdentifyVendor = 0x46;
constexpr uint8_t kIdentifyProduct = 0x47;
constexpr uint8_t kIdentifyRevisionLow = 0x48;
constexpr uint8_t kIdentifyRevisionHigh = 0x49;
constexpr uint8_t kIdentifySerialLow = 0x4A;
constexpr uint8_t kIdentifySerialHigh = 0x4B;
constexpr uint8_t kIdentifyNonConfigured = 0x4C;
constexpr uint8_t kIdentifySlaveResponse = 0x4F;  // also the fast scan answer
constexpr uint8_t kIdentifyNonConfiguredResponse = 0x50;
constexpr uint8_t kFastScan = 0x51;
constexpr uint8_t kInquireVendor = 0x5A;
constexpr uint8_t kInquireProduct = 0x5B;
constexpr uint8_t kInquireRevision = 0x5C;
constexpr uint8_t kInquireSerial = 0x5D;
constexpr uint8_t kInquireNodeId = 0x5E;
}  // namespace cs

// Error codes of the configure and store protocols.
constexpr uint8_t kOk = 0;
constexpr uint8_t kNodeIdOutOfRange = 1;
constexpr uint8_t kBitTimingNotSupported = 1;
constexpr uint8_t kStoreNotSupported = 1;
constexpr uint8_t kStoreMediaError = 2;

// Fast scan: BitChecked 0x80 restarts the scan; LSSSub/LSSNext 0..3 name the identity part.
constexpr uint8_t kFastScanConfirm = 0x80;

enum class State : uint8_t { Waiting = 0, Configuration = 1 };

// The LSS address: the four entries of 0x1018, in LSSSub order.
struct Identity {
  uint32_t vendor_id = 0;
  uint32_t product_code = 0;
  uint32_t revision_number = 0;
  uint32_t serial_number = 0;
  uint32_t part(uint8_t lss_sub) const;  // 0 vendor .. 3 serial
  bool operator==(const Identity&) const = default;
};

// The bit rate of an index of the CiA 305 standard bit timing table (table selector 0):
// 0 1000, 1 800, 2 500, 3 250, 4 125, 6 50, 7 20, 8 10 kbit/s. Index 5 is reserved and 9
// (automatic bit rate detection) is not offered: nullopt.
std::optional<unsigned> bit_rate_kbit(uint8_t table_index);

}  // namespace lss

class LssSlave {
 public:
  // Store configuration: the pending node-ID and bit timing index to non-volatile memory;
  // false is a storage media access error. Unset: the service is not supported.
  using Store = std::function<bool(uint8_t node_id, std::optional<uint8_t> bit_timing)>;

  // `node_id`: the active one (lss::kUnconfigured when none); it is also the pending one
  // until configure node-ID changes that. `bit_timing`: the table index in use, if known.
  LssSlave(lss::Identity identity, uint8_t node_id, std::optional<uint8_t> bit_timing, Store store);

  struct Result {
    std::optional<od::CanFrame> response;  // on 0x7E4, to send now
    // Switch state global to waiting made an unconfigured device's pending node-ID valid:
    // the device now does an NMT reset communication by itself and boots with it.
    bool boot = false;
    // Activate bit timing: switch to the pending bit timing after this delay (ms).
    std::optional<uint16_t> activate_bit_timing_delay_ms;
  };
  // A frame on lss::kMasterToSlave (others, remote frames and DLC other than 8: nothing).
  Result on_frame(const od::CanFrame& frame);

  // NMT reset communication: the pending node-ID becomes the active one (CiA 305 V3.0,
  // "configure node-ID"). Returns it.
  uint8_t activate_pending_node_id();
  // NMT reset communication or reset node (and power-on): back to LSS waiting, any
  // selective, identify or fast scan sequence forgotten (CiA 305's automatic transition
  // into waiting after initialisation, as CANopenNode does at every communication reset).
  void enter_waiting();
  // Another device has the node-ID (node/node_id_conflict.hpp): none, active or pending,
  // so the next reset communication leaves the device waiting for a master.
  void give_up_node_id() { active_node_id_ = pending_node_id_ = lss::kUnconfigured; }

  lss::State state() const { return state_; }
  uint8_t active_node_id() const { return active_node_id_; }
  uint8_t pending_node_id() const { return pending_node_id_; }
  std::optional<uint8_t> active_bit_timing() const { return active_bit_timing_; }
  std::optional<uint8_t> pending_bit_timing() const { return pending_bit_timing_; }
  const lss::Identity& identity() const { return identity_; }

 private:
  bool configured() const {
    return active_node_id_ != lss::kUnconfigured || pending_node_id_ != lss::kUnconfigured;
  }
  void switch_selective(uint8_t command, uint32_t value, Result& out);
  void identify_remote_slave(uint8_t command, uint32_t value, Result& out);
  void fast_scan(const od::CanFrame& frame, Result& out);
  void configuration_service(const od::CanFrame& frame, Result& out);
  static od::CanFrame answer(uint8_t command, uint8_t b1 = 0, uint8_t b2 = 0);
  static od::CanFrame answer_u32(uint8_t command, uint32_t value);

  lss::Identity identity_;
  Store store_;
  lss::State state_ = lss::State::Waiting;
  uint8_t active_node_id_;
  uint8_t pending_node_id_;
  std::optional<uint8_t> active_bit_timing_;
  std::optional<uint8_t> pending_bit_timing_;
  // The command each multi-frame protocol expects next (0: none started).
  uint8_t selective_next_ = 0;
  uint8_t identify_next_ = 0;
  uint8_t fast_scan_position_ = 0;  // LSSPos: the identity part under test
};

}  // namespace stepnode::node
