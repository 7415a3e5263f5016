// SYNC consumer and producer (CiA 301 7.2.5, objects 0x1005, 0x1006, 0x1019).
#pragma once
#include <cstdint>
#include <functional>
#include <optional>

#include "node/deadline.hpp"

#include "od/can_frame.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class SyncService {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  // on_sync(counter or 0, sync, now): every SYNC, received or produced here; `sync_us` is
  // when it reached the interface (or was sent), `now_us` when it is handled.
  using OnSync = std::function<void(uint8_t counter, uint64_t sync_us, uint64_t now_us)>;
  // on_bad_length(dlc, now): a SYNC whose length does not match 0x1019 (EMCY 0x8240).
  using OnBadLength = std::function<void(uint8_t dlc, uint64_t now_us)>;
  SyncService(od::Dictionary& dictionary, Send send, OnSync on_sync, OnBadLength on_bad_length);

  // Returns true when the frame was a SYNC (consumed). `arrival_us`: its kernel receive
  // timestamp (0: unknown, now).
  bool on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us = 0);
  // Produces SYNC when 0x1005 bit 30 is set and 0x1006 is not 0.
  void on_tick(uint64_t now_us);
  void reset(uint64_t now_us);  // restart the producer's period and counter
  // A producer's next SYNC (the last + 0x1006 us; not yet started: at once, on_tick starts
  // the period); kNoDeadline for a consumer.
  uint64_t next_deadline_us(uint64_t now_us) const;

  uint32_t cob_id() const { return dictionary_.get<uint32_t>(0x1005, 0) & 0x7FF; }
  bool producer() const;

 private:
  od::Dictionary& dictionary_;
  Send send_;
  OnSync on_sync_;
  OnBadLength on_bad_length_;
  uint64_t next_us_ = 0;
  uint8_t counter_ = 0;
  bool running_ = false;
};

}  // namespace stepnode::node
