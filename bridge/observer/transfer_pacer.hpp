// The bridge's share of the bus for its SDO reads (issue 13). Every node answers one
// transfer at a time, so a bridge that reads all nodes at once after a bus power-up (127
// boot-ups within milliseconds) would put 127 requests and 127 answers on the bus in a
// burst, on top of the heartbeats, and the nodes' receive queues overflow. Two bounds:
//  - at most `max_outstanding` transfers in flight on the whole bus: the bridge is
//    self-clocked by the answers, and never has more than that many requests queued;
//  - transfer starts at most `rate_per_s` on average (a generic cell rate algorithm: a
//    start is allowed while the theoretical arrival time is at most max_outstanding - 1
//    intervals ahead of now, so a burst is at most max_outstanding starts), so a long
//    discovery stays a fixed fraction of the bus.
// Pure, no clock: time is passed in.
#pragma once
#include <algorithm>
#include <cstdint>

namespace stepnode::bridge {

class TransferPacer {
 public:
  // rate_per_s 0: no rate bound (only the outstanding one). max_outstanding 0 is taken as 1.
  TransferPacer(uint32_t max_outstanding, uint32_t rate_per_s)
      : max_outstanding_(std::max<uint32_t>(max_outstanding, 1)),
        interval_us_(rate_per_s ? 1'000'000 / rate_per_s : 0),
        tolerance_us_(interval_us_ * (max_outstanding_ - 1)) {}

  bool may_start(uint64_t now_us) const {
    if (outstanding_ >= max_outstanding_) return false;
    return interval_us_ == 0 || tat_us_ <= now_us + tolerance_us_;
  }
  void started(uint64_t now_us) {
    ++outstanding_;
    ++starts_;
    tat_us_ = std::max(tat_us_, now_us) + interval_us_;
  }
  void ended() {
    if (outstanding_) --outstanding_;
  }

  uint32_t outstanding() const { return outstanding_; }
  uint64_t starts() const { return starts_; }

 private:
  uint32_t max_outstanding_;
  uint64_t interval_us_;
  uint64_t tolerance_us_;
  uint64_t tat_us_ = 0;  // theoretical arrival time of the next start
  uint32_t outstanding_ = 0;
  uint64_t starts_ = 0;
};

}  // namespace stepnode::bridge
