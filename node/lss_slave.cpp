#include "node/lss_slave.hpp"

namespace stepnode::node {
namespace lss {

uint32_t Identity::part(uint8_t lss_sub) const {
  switch (lss_sub) {
    case 0: return vendor_id;
    case 1: return product_code;
    case 2: return revision_number;
    default: return serial_number;
  }
}

std::optional<unsigned> bit_rate_kbit(uint8_t table_index) {
  switch (table_index) {
    case 0: return 1000;
    case 1: return 800;
    case 2: return 500;
    case 3: return 250;
    case 4: return 125;
    case 6: return 50;
    case 7: return 20;
    case 8: return 10;
    default: return std::nullopt;  // 5 reserved, 9 automatic detection, 10..255 reserved
  }
}

}  // namespace lss

LssSlave::LssSlave(lss::Identity identity, uint8_t node_id, std::optional<uint8_t> bit_timing,
                   Store store)
    : identity_(identity),
      store_(std::move(store)),
      active_node_id_(node_id),
      pending_node_id_(node_id),
      active_bit_timing_(bit_timing),
      pending_bit_timing_(bit_timing) {}

od::CanFrame LssSlave::answer(uint8_t command, uint8_t b1, uint8_t b2) {
  // Every LSS frame has 8 bytes; the ones a protocol does not use are reserved (0).
  return od::CanFrame(lss::kSlaveToMaster, {command, b1, b2, 0, 0, 0, 0, 0});
}

od::CanFrame LssSlave::answer_u32(uint8_t command, uint32_t value) {
  od::CanFrame f = answer(command);
  od::put_u32(&f.data[1], value);
  return f;
}

void LssSlave::enter_waiting() {
  state_ = lss::State::Waiting;
  selective_next_ = identify_next_ = fast_scan_position_ = 0;
}

uint8_t LssSlave::activate_pending_node_id() {
  active_node_id_ = pending_node_id_;
  return active_node_id_;
}

LssSlave::Result LssSlave::on_frame(const od::CanFrame& frame) {
  Result out;
  if (frame.id != lss::kMasterToSlave || frame.rtr || frame.dlc != 8) return out;
  const uint8_t command = frame.data[0];
  const uint32_t value = od::get_u32(&frame.data[1]);
  using namespace lss::cs;

  if (command == kSwitchStateGlobal) {
    if (frame.data[1] == static_cast<uint8_t>(lss::State::Waiting)) {
      // Leaving configuration with a node-ID where there was none: the device was waiting
      // in NMT initialisation for exactly this, and now boots (CiA 305, switch state global).
      out.boot = state_ == lss::State::Configuration && active_node_id_ == lss::kUnconfigured &&
                 pending_node_id_ != lss::kUnconfigured;
      state_ = lss::State::Waiting;
      selective_next_ = 0;
    } else if (frame.data[1] == static_cast<uint8_t>(lss::State::Configuration)) {
      state_ = lss::State::Configuration;
    }
    return out;
  }
  // Identification runs in both states: a master looks for devices whatever they do.
  if (command >= kIdentifyVendor && command <= kIdentifySerialHigh) {
    identify_remote_slave(command, value, out);
    return out;
  }
  if (command == kIdentifyNonConfigured) {
    if (!configured()) out.response = answer(kIdentifyNonConfiguredResponse);
    return out;
  }
  if (state_ == lss::State::Waiting) {
    if (command >= kSwitchSelectiveVendor && command <= kSwitchSelectiveSerial)
      switch_selective(command, value, out);
    else if (command == kFastScan) fast_scan(frame, out);
    return out;  // the configuration services are for a device in configuration only
  }
  configuration_service(frame, out);
  return out;
}

void LssSlave::switch_selective(uint8_t command, uint32_t value, Result& out) {
  using namespace lss::cs;
  // The four parts come in order, vendor first; any other order or a part that is not
  // ours ends the sequence, and a new vendor-ID always starts one.
  const uint8_t part = static_cast<uint8_t>(command - kSwitchSelectiveVendor);
  const bool in_order = command == kSwitchSelectiveVendor || command == selective_next_;
  if (!in_order || identity_.part(part) != value) {
    selective_next_ = 0;
    return;
  }
  if (command != kSwitchSelectiveSerial) {
    selective_next_ = static_cast<uint8_t>(command + 1);
    return;
  }
  selective_next_ = 0;
  state_ = lss::State::Configuration;
  out.response = answer(kSwitchSelectiveResponse);
}

void LssSlave::identify_remote_slave(uint8_t command, uint32_t value, Result& out) {
  using namespace lss::cs;
  // Vendor-ID and product code must be equal; revision and serial number within the
  // inclusive ranges [low, high] the master sends, in this order.
  const bool in_order = command == kIdentifyVendor || command == identify_next_;
  bool match = in_order;
  if (match) {
    switch (command) {
      case kIdentifyVendor: match = value == identity_.vendor_id; break;
      case kIdentifyProduct: match = value == identity_.product_code; break;
      case kIdentifyRevisionLow: match = value <= identity_.revision_number; break;
      case kIdentifyRevisionHigh: match = value >= identity_.revision_number; break;
      case kIdentifySerialLow: match = value <= identity_.serial_number; break;
      default: match = value >= identity_.serial_number; break;
    }
  }
  if (!match) {
    identify_next_ = 0;
    return;
  }
  if (command != kIdentifySerialHigh) {
    identify_next_ = static_cast<uint8_t>(command + 1);
    return;
  }
  identify_next_ = 0;
  out.response = answer(kIdentifySlaveResponse);
}

void LssSlave::fast_scan(const od::CanFrame& frame, Result& out) {
  // Only a device without a node-ID takes part: the scan finds the ones still to configure.
  if (configured()) return;
  const uint32_t id_number = od::get_u32(&frame.data[1]);
  const uint8_t bit_checked = frame.data[5], lss_sub = frame.data[6], lss_next = frame.data[7];
  if ((bit_checked > 31 && bit_checked != lss::kFastScanConfirm) || lss_sub > 3 || lss_next > 3)
    return;
  if (bit_checked == lss::kFastScanConfirm) {
    // Every device still unconfigured answers, and the scan starts again at the vendor-ID.
    fast_scan_position_ = 0;
    out.response = answer(lss::cs::kIdentifySlaveResponse);
    return;
  }
  if (lss_sub != fast_scan_position_) return;  // dropped out earlier in this scan
  // Bits bit_checked..31 of the part are compared; the lower ones are still unknown.
  const uint32_t mask = 0xFFFFFFFFu << bit_checked;
  if ((id_number & mask) != (identity_.part(lss_sub) & mask)) return;
  out.response = answer(lss::cs::kIdentifySlaveResponse);
  fast_scan_position_ = lss_next;
  // The whole of the last part confirmed (the master wraps LSSNext back): this is the one.
  if (bit_checked == 0 && lss_next < lss_sub) state_ = lss::State::Configuration;
}

void LssSlave::configuration_service(const od::CanFrame& frame, Result& out) {
  using namespace lss::cs;
  const uint8_t command = frame.data[0];
  switch (command) {
    case kConfigureNodeId: {
      // 1..127, or 0xFF to make the device unconfigured at its next reset communication.
      const uint8_t id = frame.data[1];
      const bool valid = (id >= 1 && id <= 127) || id == lss::kUnconfigured;
      if (valid) pending_node_id_ = id;
      out.response = answer(command, valid ? lss::kOk : lss::kNodeIdOutOfRange);
      break;
    }
    case kConfigureBitTiming: {
      const uint8_t selector = frame.data[1], index = frame.data[2];
      // Table selector 0 is the CiA standard table; the others are not offered.
      const bool valid = selector == 0 && lss::bit_rate_kbit(index).has_value();
      if (valid) pending_bit_timing_ = index;
      out.response = answer(command, valid ? lss::kOk : lss::kBitTimingNotSupported);
      break;
    }
    case kActivateBitTiming:
      // No answer: every device in configuration switches after the delay, together.
      active_bit_timing_ = pending_bit_timing_;
      out.activate_bit_timing_delay_ms = od::get_u16(&frame.data[1]);
      break;
    case kStoreConfiguration: {
      uint8_t error = lss::kStoreNotSupported;
      if (store_)
        error = store_(pending_node_id_, pending_bit_timing_) ? lss::kOk : lss::kStoreMediaError;
      out.response = answer(command, error);
      break;
    }
    case kInquireVendor: out.response = answer_u32(command, identity_.vendor_id); break;
    case kInquireProduct: out.response = answer_u32(command, identity_.product_code); break;
    case kInquireRevision: out.response = answer_u32(command, identity_.revision_number); break;
    case kInquireSerial: out.response = answer_u32(command, identity_.serial_number); break;
    case kInquireNodeId: out.response = answer(command, active_node_id_); break;
    default: break;  // a switch state selective or fast scan frame: for devices waiting
  }
}

}  // namespace stepnode::node
