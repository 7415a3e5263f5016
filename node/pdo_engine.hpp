// The PDO engine (CiA 301 7.2.2): receive PDOs applied to the dictionary, transmit PDOs
// sent on SYNC (types 0..240) or on change (254/255) with inhibit time and event timer.
// Configuration is read from the dictionary (0x1400.. / 0x1600.. / 0x1800.. / 0x1A00..)
// whenever a parameter changed.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "node/deadline.hpp"
#include "node/emcy.hpp"
#include "od/can_frame.hpp"
#include "od/dictionary.hpp"
#include "od/pdo_mapping.hpp"

namespace stepnode::node {

class PdoEngine {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  PdoEngine(od::Dictionary& dictionary, unsigned pdo_count, Send send, EmcyProducer& emcy);

  // A communication or mapping parameter changed: re-read before the next use.
  void mark_dirty() { dirty_ = true; }
  // Handles a frame if it is one of our RPDOs (call only in operational). Returns true if
  // the frame was an RPDO of this node. `rx_us`: when it reached the bus interface (0:
  // unknown, now), against which the synchronous window 0x1007 is measured.
  bool on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t rx_us = 0);
  // A SYNC that reached the interface at `sync_us` (<= now_us), handled at `now_us`.
  void on_sync(uint8_t counter, uint64_t sync_us, uint64_t now_us);
  void on_tick(uint64_t now_us);
  // When on_tick next has timed work (CiA 301 7.5.2.35/36): an RPDO's deadline (its last
  // frame + event time + 1 us), an event-driven TPDO's event timer (last sent + event
  // time, not before its inhibit time) and a change held back by the inhibit time (last
  // sent + inhibit time). A change of a mapped value is found on the tick that follows
  // the frame or advance that made it, so it needs no deadline. kNoDeadline: none.
  uint64_t next_deadline_us(uint64_t now_us) const;
  // Entering operational: event-driven TPDOs go out once with the current values.
  void start(uint64_t now_us);
  // Leaving operational: forget pending data and timers.
  void stop();
  // NMT reset (the EMCY producer forgets its errors too): stop, and forget RPDO timeouts.
  void reset();

  struct Stats {
    uint64_t rpdo_received = 0, rpdo_length_errors = 0, rpdo_write_errors = 0;
    uint64_t tpdo_sent = 0;
    // Synchronous PDOs outside the window 0x1007: RPDOs discarded, TPDO cycles not sent.
    uint64_t rpdo_outside_window = 0, tpdo_outside_window = 0;
  };
  const Stats& stats() const { return stats_; }

 private:
  struct Rpdo {
    bool valid = false;
    uint32_t cob_id = 0;
    uint8_t type = 0;
    uint16_t event_ms = 0;
    od::PdoMapping mapping;
    size_t bytes = 0;
    // runtime
    bool sync_pending = false;
    std::vector<uint8_t> sync_data;
    bool monitoring = false, timed_out = false;
    uint64_t last_rx_us = 0;
    uint16_t length_error = 0;  // the EMCY code active for it (0x8210/0x8220), 0: none
  };
  struct Tpdo {
    bool valid = false;
    bool rtr_allowed = false;  // COB-ID bit 30 = 0: a remote frame asks for it
    uint32_t cob_id = 0;
    uint8_t type = 0;
    uint64_t inhibit_us = 0;
    uint64_t event_us = 0;
    uint8_t sync_start = 0;
    od::PdoMapping mapping;
    // runtime
    std::vector<uint8_t> last_data;
    std::vector<uint8_t> event_mask;  // bits whose change is an event (see Entry::pdo_sampled)
    bool sent_any = false, send_request = false, event_pending = false;
    bool waiting_sync_start = false;
    bool held = false;  // an event waits for the inhibit time to pass
    uint64_t last_sent_us = 0;
    unsigned sync_count = 0;
  };

  void reload(uint64_t now_us);
  // A remote frame on a TPDO's COB-ID; true if it asked for one.
  bool remote_request(const od::CanFrame& frame);
  // An RPDO is no longer late (received, destroyed): EMCY 0x8250 ends when none is late.
  void end_timeout(Rpdo& pdo, uint64_t now_us);
  // A length error (EMCY 0x8210 too short, 0x8220 too long) is active from the RPDO's
  // wrong frame until its next frame of the right length (or it is destroyed, or reset):
  // then the error reset, when no other RPDO has the same error.
  void length_error(Rpdo& pdo, uint16_t code, const od::CanFrame& frame, uint64_t now_us);
  void end_length_error(Rpdo& pdo, uint64_t now_us);
  void transmit(Tpdo& pdo, std::vector<uint8_t> data, uint64_t now_us);
  void apply(Rpdo& pdo, std::span<const uint8_t> data);
  // True while `at_us` lies within the synchronous window after the last SYNC (always when
  // 0x1007 is 0).
  bool in_window(uint64_t sync_us, uint64_t at_us) const;
  void sync_tpdo(Tpdo& t, uint8_t counter, bool window_open, uint64_t now_us);

  od::Dictionary& dictionary_;
  unsigned count_;
  Send send_;
  EmcyProducer& emcy_;
  std::vector<Rpdo> rpdos_;
  std::vector<Tpdo> tpdos_;
  bool dirty_ = true;
  bool running_ = false;
  // The last SYNC since entering operational (its arrival), for the synchronous window.
  bool sync_seen_ = false;
  uint64_t last_sync_us_ = 0;
  Stats stats_;
};

}  // namespace stepnode::node
