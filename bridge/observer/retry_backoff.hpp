// Exponential backoff for failed discovery reads: the first retry after `initial_ms`,
// each further failure doubles the wait up to `max_ms`; a success starts over.
#pragma once
#include <algorithm>
#include <cstdint>

namespace stepnode::bridge {

class RetryBackoff {
 public:
  RetryBackoff(uint32_t initial_ms, uint32_t max_ms)
      : initial_us_(uint64_t{initial_ms} * 1000),
        max_us_(std::max(uint64_t{max_ms} * 1000, initial_us_)) {}

  void failed(uint64_t now_us) {
    delay_us_ = delay_us_ == 0 ? initial_us_ : std::min(delay_us_ * 2, max_us_);
    retry_at_us_ = now_us + delay_us_;
  }
  void reset() {
    delay_us_ = 0;
    retry_at_us_ = 0;
  }
  bool ready(uint64_t now_us) const { return now_us >= retry_at_us_; }
  uint64_t delay_us() const { return delay_us_; }  // the wait after the last failure

 private:
  uint64_t initial_us_, max_us_;
  uint64_t delay_us_ = 0;
  uint64_t retry_at_us_ = 0;
};

}  // namespace stepnode::bridge
