#include "node/time_service.hpp"

#include <spdlog/spdlog.h>

#include "node/diagnostic_objects.hpp"
#include "od/value_codec.hpp"

namespace stepnode::node {

TimeOfDay TimeOfDay::from_ms_since_1984(uint64_t ms) {
  return {static_cast<uint32_t>(ms % kMsPerDay), static_cast<uint16_t>(ms / kMsPerDay)};
}

std::optional<TimeOfDay> TimeOfDay::decode(const od::CanFrame& frame) {
  if (frame.dlc != 6) return std::nullopt;
  const uint32_t raw = od::get_u32(frame.data.data());
  // The 4 bits above the 28 of milliseconds are reserved: ignored, as a consumer must.
  TimeOfDay t{raw & 0x0FFFFFFFu, od::get_u16(&frame.data[4])};
  if (t.ms >= kMsPerDay) return std::nullopt;
  return t;
}

od::CanFrame TimeOfDay::encode(uint32_t cob_id) const {
  return od::CanFrame(cob_id,
                      {static_cast<uint8_t>(ms), static_cast<uint8_t>(ms >> 8),
                       static_cast<uint8_t>(ms >> 16), static_cast<uint8_t>((ms >> 24) & 0x0F),
                       static_cast<uint8_t>(days), static_cast<uint8_t>(days >> 8)});
}

TimeService::TimeService(od::Dictionary& dictionary, Send send, WallClock wall_clock)
    : dictionary_(dictionary), send_(std::move(send)), wall_clock_(std::move(wall_clock)) {
  install_reads();
}

void TimeService::install_reads() {
  // 0x2F12:1..4 are computed when read: the time runs on between TIME stamps.
  auto now_of_day = [this] {
    return TimeOfDay::from_ms_since_1984(network_ms(now_us_).value_or(0));
  };
  dictionary_.at(kNetworkTime, 1).on_read = [now_of_day](od::Bytes& v) {
    v = od::encode<uint32_t>(now_of_day().ms);
  };
  dictionary_.at(kNetworkTime, 2).on_read = [now_of_day](od::Bytes& v) {
    v = od::encode<uint16_t>(now_of_day().days);
  };
  dictionary_.at(kNetworkTime, 3).on_read = [this](od::Bytes& v) {
    auto ms = network_ms(now_us_);
    v = od::encode<uint64_t>(ms ? *ms + TimeOfDay::kUnixMsAt1984 : 0);
  };
  dictionary_.at(kNetworkTime, 4).on_read = [this](od::Bytes& v) {
    v = {static_cast<uint8_t>(source_)};
  };
}

std::optional<uint64_t> TimeService::network_ms(uint64_t now_us) const {
  if (producer() && wall_clock_) {
    const uint64_t unix_us = wall_clock_();
    if (unix_us / 1000 >= TimeOfDay::kUnixMsAt1984)
      return unix_us / 1000 - TimeOfDay::kUnixMsAt1984;
  }
  if (source_ == Source::None) return std::nullopt;
  return stamp_ms_ + (now_us - stamp_at_us_) / 1000;
}

bool TimeService::on_frame(const od::CanFrame& frame, uint64_t now_us, uint64_t arrival_us) {
  now_us_ = now_us;
  if (!consumer() || frame.rtr || frame.id != cob_id()) return false;
  auto t = TimeOfDay::decode(frame);
  if (!t) {
    spdlog::debug("TIME on 0x{:03X} with {} bytes or a time of day out of range: ignored", frame.id,
                  frame.dlc);
    return true;
  }
  // The stamp was the time when the frame was on the bus: from then on the node's clock runs it.
  stamp_ms_ = t->ms_since_1984();
  stamp_at_us_ = arrival_us && arrival_us <= now_us ? arrival_us : now_us;
  if (source_ != Source::Consumed)
    spdlog::info("TIME: network time received (day {} since 1984, {} ms)", t->days, t->ms);
  source_ = Source::Consumed;
  return true;
}

void TimeService::reset(uint64_t now_us) {
  now_us_ = now_us;
  source_ = Source::None;
  producing_ = false;
}

uint64_t TimeService::next_deadline_us(uint64_t now_us) const {
  const uint16_t period_ms = dictionary_.get<uint16_t>(kNetworkTime, kTimeProducerPeriodSub);
  if (!producer() || period_ms == 0) return producing_ ? now_us : kNoDeadline;
  return producing_ ? next_us_ : now_us;
}

void TimeService::on_tick(uint64_t now_us) {
  now_us_ = now_us;
  const uint16_t period_ms = dictionary_.get<uint16_t>(kNetworkTime, kTimeProducerPeriodSub);
  if (!producer() || period_ms == 0) {
    producing_ = false;
    return;
  }
  if (!producing_) {
    producing_ = true;
    next_us_ = now_us;  // the first stamp at once, then every period
  }
  if (now_us < next_us_) return;
  next_us_ += uint64_t{period_ms} * 1000;
  if (next_us_ <= now_us) next_us_ = now_us + uint64_t{period_ms} * 1000;
  auto ms = network_ms(now_us);
  if (!ms) return;  // no wall clock and no TIME received: nothing true to send
  if (wall_clock_) source_ = Source::Produced;
  send_(TimeOfDay::from_ms_since_1984(*ms).encode(cob_id()));
}

}  // namespace stepnode::node
