#include "node/sync.hpp"

namespace stepnode::node {

SyncService::SyncService(od::Dictionary& dictionary, Send send, OnSync on_sync,
                         OnBadLength on_bad_length)
    : dictionary_(dictionary),
      send_(std::move(send)),
      on_sync_(std::move(on_sync)),
      on_bad_length_(std::move(on_bad_length)) {}

bool SyncService::producer() const {
  return (dictionary_.get<uint32_t>(0x1005, 0) & 0x40000000u) &&
         dictionary_.get<uint32_t>(0x1006, 0) != 0;
}

bool SyncService::on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us) {
  if (frame.rtr || frame.id != cob_id()) return false;
  uint8_t overflow = dictionary_.get<uint8_t>(0x1019, 0);
  // With a counter configured the SYNC carries 1 byte, without it none (CiA 301 7.2.5.3).
  uint8_t expected = overflow ? 1 : 0;
  if (frame.dlc != expected) {
    if (on_bad_length_) on_bad_length_(frame.dlc, now_us);
    return true;
  }
  on_sync_(overflow ? frame.data[0] : 0, arrival_us && arrival_us <= now_us ? arrival_us : now_us,
           now_us);
  return true;
}

void SyncService::reset(uint64_t now_us) {
  counter_ = 0;
  running_ = false;
  next_us_ = now_us;
}

uint64_t SyncService::next_deadline_us(uint64_t now_us) const {
  if (!producer()) return running_ ? now_us : kNoDeadline;  // on_tick stops the producer
  return running_ ? next_us_ : now_us;
}

void SyncService::on_tick(uint64_t now_us) {
  if (!producer()) {
    running_ = false;
    return;
  }
  uint64_t period_us = dictionary_.get<uint32_t>(0x1006, 0);
  if (!running_) {
    running_ = true;
    next_us_ = now_us + period_us;
    counter_ = 0;
    return;
  }
  if (now_us < next_us_) return;
  // Keep the cycle's phase; if ticks were missed, skip forward instead of bursting.
  next_us_ += period_us;
  if (next_us_ <= now_us) next_us_ = now_us + period_us;
  uint8_t overflow = dictionary_.get<uint8_t>(0x1019, 0);
  od::CanFrame f;
  f.id = cob_id();
  if (overflow) {
    counter_ = counter_ >= overflow ? 1 : static_cast<uint8_t>(counter_ + 1);
    f.dlc = 1;
    f.data[0] = counter_;
  }
  send_(f);
  // A CAN controller does not receive its own frames: the producer's SYNC acts here too.
  on_sync_(overflow ? counter_ : 0, now_us, now_us);
}

}  // namespace stepnode::node
