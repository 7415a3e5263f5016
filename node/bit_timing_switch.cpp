#include "node/bit_timing_switch.hpp"

#include <spdlog/spdlog.h>

#include "node/deadline.hpp"

namespace stepnode::node {

void BitTimingSwitch::activate(unsigned kbit, uint16_t delay_ms, uint64_t now_us) {
  if (active_) return;
  active_ = true;
  switched_ = false;
  kbit_ = kbit;
  switch_at_us_ = now_us + uint64_t{delay_ms} * 1000;
  quiet_until_us_ = switch_at_us_ + uint64_t{delay_ms} * 1000;
  dropped_ = 0;
  spdlog::info("LSS: activate bit timing {} kbit/s: switching in {} ms, silent for {} ms", kbit,
               delay_ms, 2 * delay_ms);
}

uint64_t BitTimingSwitch::next_deadline_us() const {
  if (!active_) return kNoDeadline;
  return switched_ ? quiet_until_us_ : switch_at_us_;
}

void BitTimingSwitch::on_tick(uint64_t now_us) {
  if (!active_) return;
  if (!switched_ && now_us >= switch_at_us_) {
    switched_ = true;
    const std::string error = apply_(kbit_ * 1000);
    if (error.empty()) spdlog::info("LSS: bit rate set to {} kbit/s", kbit_);
    else spdlog::error("LSS: the bit timing {} kbit/s was not applied: {}", kbit_, error);
  }
  if (switched_ && now_us >= quiet_until_us_) {
    active_ = false;
    if (dropped_)
      spdlog::info("LSS: {} frames made during the bit timing switch were not sent", dropped_);
  }
}

}  // namespace stepnode::node
