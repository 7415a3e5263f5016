#include "node/pdo_engine.hpp"

#include <algorithm>

#include "od/cob_id.hpp"
#include "od/communication_objects.hpp"

namespace stepnode::node {
namespace {

constexpr uint32_t kInvalid = 0x80000000u;

od::PdoMapping read_mapping(od::Dictionary& od, uint16_t index) {
  od::PdoMapping mapping;
  uint8_t n = od.get<uint8_t>(index, 0);
  for (uint8_t i = 1; i <= n && i <= od::kMaxMappedEntries; ++i)
    mapping.push_back(od::MappedEntry::from_word(od.get<uint32_t>(index, i)));
  return mapping;
}

}  // namespace

PdoEngine::PdoEngine(od::Dictionary& dictionary, unsigned pdo_count, Send send, EmcyProducer& emcy)
    : dictionary_(dictionary), count_(pdo_count), send_(std::move(send)), emcy_(emcy) {}

void PdoEngine::reload(uint64_t now_us) {
  dirty_ = false;
  rpdos_.resize(count_);
  tpdos_.resize(count_);
  for (unsigned n = 0; n < count_; ++n) {
    Rpdo& r = rpdos_[n];
    uint16_t rc = od::rpdo_parameter(n);
    uint32_t rid = dictionary_.get<uint32_t>(rc, 1);
    r.mapping = read_mapping(dictionary_, od::rpdo_mapping(n));
    r.bytes = od::mapping_bytes(r.mapping);
    // A PDO with nothing mapped carries no data: it stays silent (CiA 301 7.5.2.36).
    r.valid = !(rid & kInvalid) && !r.mapping.empty();
    r.cob_id = rid & 0x7FF;
    r.type = dictionary_.get<uint8_t>(rc, 2);
    r.event_ms = dictionary_.get<uint16_t>(rc, 5);
    if (!r.valid) {
      r.sync_pending = r.monitoring = false;
      end_timeout(r, now_us);
      end_length_error(r, now_us);
    }

    Tpdo& t = tpdos_[n];
    uint16_t tc = od::tpdo_parameter(n);
    uint32_t tid = dictionary_.get<uint32_t>(tc, 1);
    bool was_valid = t.valid;
    t.mapping = read_mapping(dictionary_, od::tpdo_mapping(n));
    t.valid = !(tid & kInvalid) && !t.mapping.empty();
    t.cob_id = tid & 0x7FF;
    t.rtr_allowed = (tid & od::kCobGenerate) == 0;  // bit 30: no RTR
    t.type = dictionary_.get<uint8_t>(tc, 2);
    t.inhibit_us = uint64_t{dictionary_.get<uint16_t>(tc, 3)} * 100;
    t.event_us = uint64_t{dictionary_.get<uint16_t>(tc, 5)} * 1000;
    t.sync_start = dictionary_.get<uint8_t>(tc, 6);
    // Event bits: the non-sampled entries, or all of them when every entry is sampled
    // (a TPDO of positions streams on change, limited by its inhibit time).
    t.event_mask.assign(od::mapping_bytes(t.mapping), 0);
    bool any_event = false;
    size_t offset = 0;
    for (const auto& m : t.mapping) {
      const od::Entry* e = m.dummy() ? nullptr : dictionary_.find(m.index, m.sub);
      if (e && !e->pdo_sampled) {
        od::write_bits(t.event_mask, offset, ~uint64_t{0}, m.bits);
        any_event = true;
      }
      offset += m.bits;
    }
    if (!any_event) std::fill(t.event_mask.begin(), t.event_mask.end(), 0xFF);
    if (t.valid && !was_valid) {
      // A PDO that (re)appears starts fresh and, if event-driven, sends its values once.
      t.last_data.clear();
      t.sent_any = false;
      t.send_request = running_;
      t.event_pending = running_;
      t.sync_count = 0;
      t.waiting_sync_start = t.sync_start != 0;
    }
  }
}

void PdoEngine::start(uint64_t now_us) {
  if (dirty_) reload(now_us);
  running_ = true;
  for (auto& t : tpdos_) {
    t.send_request = t.event_pending = true;
    t.sync_count = 0;
    t.waiting_sync_start = t.sync_start != 0;
  }
  // Deadline monitoring restarts with the next reception. A timeout seen before leaving
  // operational stays active until then (clearing the flag alone left EMCY 0x8250 and
  // 0x1001 bit 4 set for ever).
  for (auto& r : rpdos_) r.monitoring = r.sync_pending = false;
  on_tick(now_us);
}

void PdoEngine::stop() {
  running_ = false;
  sync_seen_ = false;
  for (auto& r : rpdos_) r.sync_pending = r.monitoring = false;
}

void PdoEngine::reset() {
  stop();
  for (auto& r : rpdos_) {  // the EMCY producer forgets them too
    r.timed_out = false;
    r.length_error = 0;
  }
}

void PdoEngine::apply(Rpdo& pdo, std::span<const uint8_t> data) {
  if (od::unpack_pdo(dictionary_, pdo.mapping, data) != od::SdoAbort::None)
    ++stats_.rpdo_write_errors;
}

void PdoEngine::end_timeout(Rpdo& pdo, uint64_t now_us) {
  if (!pdo.timed_out) return;
  pdo.timed_out = false;
  // One EMCY condition covers every late RPDO: it ends with the last of them (CiA 301
  // 7.2.7: the error reset tells that the condition is gone).
  for (const auto& r : rpdos_)
    if (r.timed_out) return;
  emcy_.clear(emcy_code::kRpdoTimeout, now_us);
}

void PdoEngine::length_error(Rpdo& pdo, uint16_t code, const od::CanFrame& frame, uint64_t now_us) {
  ++stats_.rpdo_length_errors;
  if (pdo.length_error == code) return;  // still active: reported once
  end_length_error(pdo, now_us);
  pdo.length_error = code;
  // Manufacturer bytes: the COB-ID (LE) and the length received.
  emcy_.raise(code, error_bits::kCommunication,
              {static_cast<uint8_t>(frame.id), static_cast<uint8_t>(frame.id >> 8), frame.dlc},
              now_us);
}

void PdoEngine::end_length_error(Rpdo& pdo, uint64_t now_us) {
  const uint16_t code = pdo.length_error;
  if (code == 0) return;
  pdo.length_error = 0;
  for (const auto& r : rpdos_)
    if (r.length_error == code) return;
  emcy_.clear(code, now_us);
}

bool PdoEngine::in_window(uint64_t sync_us, uint64_t at_us) const {
  const uint32_t window_us = dictionary_.get<uint32_t>(od::kSyncWindowLength, 0);
  return window_us == 0 || (at_us >= sync_us && at_us - sync_us <= window_us);
}

bool PdoEngine::on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t rx_us) {
  if (dirty_) reload(now_us);
  if (rx_us == 0 || rx_us > now_us) rx_us = now_us;
  if (frame.rtr) return remote_request(frame);
  bool consumed = false;
  for (auto& r : rpdos_) {
    if (!r.valid || r.cob_id != frame.id) continue;
    consumed = true;
    ++stats_.rpdo_received;
    // Too short: not processed, EMCY 0x8210. Too long: processed, EMCY 0x8220 (CiA 301
    // 7.2.2.2 leaves the extra bytes unused).
    if (frame.dlc < r.bytes) {
      length_error(r, emcy_code::kPdoLength, frame, now_us);
      continue;
    }
    if (frame.dlc > r.bytes) length_error(r, emcy_code::kPdoLengthExceeded, frame, now_us);
    else end_length_error(r, now_us);
    r.last_rx_us = now_us;
    r.monitoring = true;
    end_timeout(r, now_us);
    std::span<const uint8_t> data(frame.data.data(), r.bytes);
    if (r.type <= 240) {  // synchronous: applied at the next SYNC
      // CiA 301 7.2.2.2 (synchronous window): synchronous RPDO data that arrives after the
      // window has closed is discarded; before the first SYNC no window has opened.
      // Only with a window configured: without one (0x1007 = 0) every PDO counts.
      const bool window_used = dictionary_.get<uint32_t>(od::kSyncWindowLength, 0) != 0;
      if (window_used && (!sync_seen_ || !in_window(last_sync_us_, rx_us))) {
        ++stats_.rpdo_outside_window;
        continue;
      }
      r.sync_data.assign(data.begin(), data.end());
      r.sync_pending = true;
    } else {
      apply(r, data);
    }
  }
  return consumed;
}

bool PdoEngine::remote_request(const od::CanFrame& frame) {
  // CiA 301 7.2.2: a remote frame on a TPDO whose COB-ID allows it (bit 30 = 0) asks for
  // the PDO. An event-driven one goes out on the tick that follows the frame (its inhibit
  // time kept), a synchronous one with its next SYNC. (A master could clear bit 30, was
  // confirmed and then heard nothing: found in review; python-canopen clears it by default.)
  bool asked = false;
  for (auto& t : tpdos_) {
    if (!t.valid || !t.rtr_allowed || t.cob_id != frame.id) continue;
    t.send_request = t.event_pending = true;
    asked = true;
  }
  return asked;
}

void PdoEngine::transmit(Tpdo& pdo, std::vector<uint8_t> data, uint64_t now_us) {
  od::CanFrame f(pdo.cob_id, std::span<const uint8_t>(data));
  send_(f);
  ++stats_.tpdo_sent;
  pdo.last_data = std::move(data);
  pdo.last_sent_us = now_us;
  pdo.sent_any = true;
  pdo.send_request = false;
  pdo.event_pending = false;
  pdo.held = false;
}

void PdoEngine::on_sync(uint8_t counter, uint64_t sync_us, uint64_t now_us) {
  if (dirty_) reload(now_us);
  if (!running_) return;
  if (sync_us == 0 || sync_us > now_us) sync_us = now_us;
  for (auto& r : rpdos_) {
    if (r.valid && r.sync_pending) {
      r.sync_pending = false;
      apply(r, r.sync_data);
    }
  }
  sync_seen_ = true;
  last_sync_us_ = sync_us;
  // The TPDOs of this SYNC go out now; if the SYNC is handled after its window closed
  // (the process came to it late), they are not sent in this cycle (CiA 301 7.2.2.2).
  const bool window_open = in_window(sync_us, now_us);
  for (auto& t : tpdos_)
    if (t.valid && t.type <= 240) sync_tpdo(t, counter, window_open, now_us);
}

void PdoEngine::sync_tpdo(Tpdo& t, uint8_t counter, bool window_open, uint64_t now_us) {
  if (t.waiting_sync_start && counter != 0) {
    // With a SYNC counter, the first transmission waits for the start value (7.5.2.35).
    if (counter != t.sync_start) return;
    t.waiting_sync_start = false;
    t.sync_count = t.type;  // transmit on this SYNC
  } else {
    // A SYNC without a counter (0x1019 = 0): the start value is ignored (CiA 301, TPDO
    // communication parameter sub-index 06h); waiting for it kept the TPDO silent.
    t.waiting_sync_start = false;
    ++t.sync_count;
  }
  std::vector<uint8_t> data = od::pack_pdo(dictionary_, t.mapping);
  if (t.type == 0) {
    // Acyclic synchronous: sent on the SYNC after a change. A change whose window passed
    // is still a change at the next SYNC.
    if (t.event_pending || data != t.last_data) {
      if (window_open) {
        transmit(t, std::move(data), now_us);
      } else {
        t.event_pending = true;
        ++stats_.tpdo_outside_window;
      }
    }
    t.sync_count = 0;
  } else if (t.sync_count >= t.type) {
    // Cyclic: this cycle's transmission is lost; the count starts again for the next one.
    t.sync_count = 0;
    if (window_open) transmit(t, std::move(data), now_us);
    else ++stats_.tpdo_outside_window;
  }
}

void PdoEngine::on_tick(uint64_t now_us) {
  if (dirty_) reload(now_us);
  if (!running_) return;
  for (auto& r : rpdos_) {
    // Deadline monitoring of received PDOs (event timer, CiA 301 7.5.2.35).
    if (r.valid && r.monitoring && !r.timed_out && r.event_ms &&
        now_us - r.last_rx_us > uint64_t{r.event_ms} * 1000) {
      r.timed_out = true;
      emcy_.raise(emcy_code::kRpdoTimeout, error_bits::kCommunication, {}, now_us);
    }
  }
  for (auto& t : tpdos_) {
    if (!t.valid || t.type <= 240) continue;
    std::vector<uint8_t> data = od::pack_pdo(dictionary_, t.mapping);
    bool changed = !t.sent_any || t.last_data.size() != data.size();
    for (size_t i = 0; !changed && i < data.size(); ++i)
      changed = ((data[i] ^ t.last_data[i]) & t.event_mask[i]) != 0;
    bool timer = t.event_us && now_us - t.last_sent_us >= t.event_us;
    if (!(changed || timer || t.send_request)) {
      // A change undone within the inhibit time leaves nothing to send after it: no longer
      // held (kept, its deadline stayed at now after the inhibit time, a busy loop).
      t.held = false;
      continue;
    }
    if (t.sent_any && now_us - t.last_sent_us < t.inhibit_us) {
      t.held = true;  // retried once the inhibit time has passed (next_deadline_us)
      continue;
    }
    transmit(t, std::move(data), now_us);
  }
}

uint64_t PdoEngine::next_deadline_us(uint64_t now_us) const {
  if (dirty_) return now_us;  // the configuration is read again on the next tick
  if (!running_) return kNoDeadline;
  uint64_t next = kNoDeadline;
  for (const auto& r : rpdos_)
    if (r.valid && r.monitoring && !r.timed_out && r.event_ms)
      next = earliest(next, r.last_rx_us + uint64_t{r.event_ms} * 1000 + 1);
  for (const auto& t : tpdos_) {
    if (!t.valid || t.type <= 240) continue;
    if (!t.sent_any) return now_us;
    const uint64_t inhibit_end = t.last_sent_us + t.inhibit_us;
    if (t.held || t.send_request) next = earliest(next, std::max(now_us, inhibit_end));
    if (t.event_us) next = earliest(next, std::max(t.last_sent_us + t.event_us, inhibit_end));
  }
  return next;
}

}  // namespace stepnode::node
