// TIME consumer and producer (CiA 301 7.2.6, object 0x1012): the network time, kept on
// the node's monotonic clock from the last TIME stamp received, and readable in 0x2F12.
// TIME_OF_DAY on the bus: 6 bytes, little-endian: milliseconds after midnight (28 bits,
// the 4 bits above them 0) and days since 1984-01-01 (16 bits).
#pragma once
#include <cstdint>
#include <functional>
#include <optional>

#include "node/deadline.hpp"
#include "od/can_frame.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

// TIME_OF_DAY (CiA 301 7.1.6.5) and its conversions.
struct TimeOfDay {
  uint32_t ms = 0;    // after midnight, 0..86,399,999
  uint16_t days = 0;  // since 1984-01-01
  static constexpr uint64_t kMsPerDay = 86'400'000;
  // 1970-01-01 to 1984-01-01: 14 years, 3 of them leap years.
  static constexpr uint64_t kUnixMsAt1984 = (14 * 365 + 3) * kMsPerDay;
  uint64_t ms_since_1984() const { return uint64_t{days} * kMsPerDay + ms; }
  static TimeOfDay from_ms_since_1984(uint64_t ms);
  static std::optional<TimeOfDay> decode(const od::CanFrame& frame);  // 6 bytes, else none
  od::CanFrame encode(uint32_t cob_id) const;
};

class TimeService {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  // The wall clock (us since 1970-01-01 UTC) a producer sends; empty: it sends the network
  // time it keeps (nothing before it has one).
  using WallClock = std::function<uint64_t()>;
  // 0x2F12:4, where the network time comes from.
  enum class Source : uint8_t { None = 0, Consumed = 1, Produced = 2 };

  TimeService(od::Dictionary& dictionary, Send send, WallClock wall_clock);

  // Returns true when the frame was the TIME object this node consumes (0x1012 bit 31).
  // `arrival_us`: its kernel receive timestamp (0: unknown, now).
  bool on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us = 0);
  // Produces TIME every 0x2F12:5 ms when 0x1012 bit 30 is set.
  void on_tick(uint64_t now_us);
  // A producer's next TIME stamp (0x1012 bit 30 and a period set); kNoDeadline otherwise.
  uint64_t next_deadline_us(uint64_t now_us) const;
  // Reset communication: the producer's period restarts, the network time is forgotten.
  void reset(uint64_t now_us);

  // The network time now, in ms since 1984-01-01; none before a TIME stamp.
  std::optional<uint64_t> network_ms(uint64_t now_us) const;
  uint32_t cob_id() const { return dictionary_.get<uint32_t>(0x1012, 0) & 0x7FF; }
  bool consumer() const { return dictionary_.get<uint32_t>(0x1012, 0) & 0x80000000u; }
  bool producer() const { return dictionary_.get<uint32_t>(0x1012, 0) & 0x40000000u; }

 private:
  void install_reads();

  od::Dictionary& dictionary_;
  Send send_;
  WallClock wall_clock_;
  Source source_ = Source::None;
  uint64_t stamp_ms_ = 0;  // the network time at stamp_at_us_
  uint64_t stamp_at_us_ = 0;
  uint64_t now_us_ = 0;  // the latest time seen, for reads of 0x2F12
  uint64_t next_us_ = 0;
  bool producing_ = false;
};

}  // namespace stepnode::node
