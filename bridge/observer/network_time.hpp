// The network time of a CANopen bus as the bridge sees it (issue 12: TIME in the bridge's
// timestamps). A TIME producer sends TIME_OF_DAY on COB-ID 0x100 (CiA 301 7.2.6; the
// default of 0x1012): 6 bytes, little-endian, bits 0-27 the milliseconds after midnight,
// bits 28-31 reserved, bits 32-47 the days since 1984-01-01. The stamp is the time at which
// the frame is on the bus, so the kernel's receive timestamp of that same frame is the host
// clock's reading for that instant; their difference is the offset between the two clocks.
// Any later kernel timestamp maps to network time by that offset, until the next TIME frame
// gives a new one (the clocks drift apart slowly; producers repeat TIME periodically).
// Before any TIME frame, times stay on the host clock, as without this option.
#pragma once
#include <cstdint>
#include <optional>

#include "od/can_frame.hpp"

namespace stepnode::bridge {

// 1970-01-01 to 1984-01-01: 14 years, three of them leap years (1972, 1976, 1980).
constexpr uint64_t kUnixDaysAt1984 = 14 * 365 + 3;
constexpr uint64_t kMsPerDay = 86'400'000;

// A TIME_OF_DAY frame as ns since 1970-01-01 (the scale of CLOCK_REALTIME); none when it
// is not 6 bytes or its milliseconds are not within a day. Reserved bits are ignored.
std::optional<uint64_t> time_of_day_unix_ns(const od::CanFrame& frame);

class NetworkTime {
 public:
  // A TIME frame and its kernel receive timestamp (CLOCK_REALTIME ns). False: not a valid
  // TIME_OF_DAY, nothing changed.
  bool on_time(const od::CanFrame& frame, uint64_t can_time_ns);
  bool known() const { return known_; }
  // A kernel receive timestamp on the network's clock (unchanged before the first TIME).
  uint64_t to_network(uint64_t can_time_ns) const {
    return known_ ? static_cast<uint64_t>(static_cast<int64_t>(can_time_ns) + offset_ns_)
                  : can_time_ns;
  }
  int64_t offset_ns() const { return offset_ns_; }  // network minus host

 private:
  bool known_ = false;
  int64_t offset_ns_ = 0;
};

}  // namespace stepnode::bridge
