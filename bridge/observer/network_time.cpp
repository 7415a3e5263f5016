#include "bridge/observer/network_time.hpp"

namespace stepnode::bridge {

std::optional<uint64_t> time_of_day_unix_ns(const od::CanFrame& f) {
  if (f.rtr || f.dlc != 6) return std::nullopt;
  const uint32_t word = static_cast<uint32_t>(f.data[0]) | static_cast<uint32_t>(f.data[1]) << 8 |
                        static_cast<uint32_t>(f.data[2]) << 16 |
                        static_cast<uint32_t>(f.data[3]) << 24;
  const uint32_t ms = word & 0x0FFFFFFFu;
  if (ms >= kMsPerDay) return std::nullopt;
  const uint64_t days = static_cast<uint64_t>(f.data[4]) | static_cast<uint64_t>(f.data[5]) << 8;
  return ((kUnixDaysAt1984 + days) * kMsPerDay + ms) * 1'000'000;
}

bool NetworkTime::on_time(const od::CanFrame& frame, uint64_t can_time_ns) {
  const auto network_ns = time_of_day_unix_ns(frame);
  if (!network_ns) return false;
  offset_ns_ = static_cast<int64_t>(*network_ns) - static_cast<int64_t>(can_time_ns);
  known_ = true;
  return true;
}

}  // namespace stepnode::bridge
