#include "node/emcy.hpp"

#include <algorithm>

#include "od/communication_objects.hpp"

namespace stepnode::node {

EmcyProducer::EmcyProducer(od::Dictionary& dictionary, Send send)
    : dictionary_(dictionary), send_(std::move(send)) {}

uint8_t EmcyProducer::error_register() const { return dictionary_.get<uint8_t>(0x1001, 0); }

void EmcyProducer::update_register() {
  uint8_t reg = 0;
  for (const auto& [key, condition] : active_) reg |= condition.register_bits;
  if (!active_.empty()) reg |= error_bits::kGeneric;  // bit 0 is set for any error
  dictionary_.put<uint8_t>(0x1001, 0, reg);
}

void EmcyProducer::push_history(uint16_t code, std::array<uint8_t, 5> manufacturer) {
  // Newest at sub 1 (CiA 301 7.5.2.3); the field holds the code and 16 bits of extra info.
  for (unsigned i = od::kErrorHistoryLength; i > 1; --i)
    dictionary_.set(0x1003, static_cast<uint8_t>(i),
                    dictionary_.value(0x1003, static_cast<uint8_t>(i - 1)));
  uint32_t info = static_cast<uint32_t>(manufacturer[0] | (manufacturer[1] << 8));
  dictionary_.put<uint32_t>(0x1003, 1, code | (info << 16));
  uint8_t count = dictionary_.get<uint8_t>(0x1003, 0);
  if (count < od::kErrorHistoryLength) dictionary_.put<uint8_t>(0x1003, 0, count + 1);
}

void EmcyProducer::enqueue(uint16_t code, std::array<uint8_t, 5> manufacturer, uint64_t now_us) {
  uint32_t cob_id = dictionary_.get<uint32_t>(0x1014, 0);
  if (cob_id & 0x80000000u) return;  // EMCY does not exist
  od::CanFrame f(cob_id & 0x7FF, {static_cast<uint8_t>(code), static_cast<uint8_t>(code >> 8),
                                  error_register(), manufacturer[0], manufacturer[1],
                                  manufacturer[2], manufacturer[3], manufacturer[4]});
  pending_.push_back(f);
  if (pending_.size() > 32) pending_.pop_front();  // a storm of errors keeps the newest
  on_tick(now_us);
}

namespace {
// report()'s event is active only while its own message is built.
constexpr uint16_t kReportSource = 0xFFFF;
}  // namespace

bool EmcyProducer::active(uint16_t code) const {
  const auto it = active_.lower_bound({code, 0});
  return it != active_.end() && it->first.first == code;
}

void EmcyProducer::raise(uint16_t code, uint8_t register_bits, std::array<uint8_t, 5> manufacturer,
                         uint64_t now_us, uint16_t source) {
  if (!active_.try_emplace({code, source}, Condition{register_bits, manufacturer}).second) return;
  update_register();
  push_history(code, manufacturer);
  enqueue(code, manufacturer, now_us);
}

void EmcyProducer::report(uint16_t code, uint8_t register_bits, std::array<uint8_t, 5> manufacturer,
                          uint64_t now_us) {
  // The register shows the event in the message itself, then falls back.
  active_[{code, kReportSource}] = Condition{register_bits, manufacturer};
  update_register();
  push_history(code, manufacturer);
  enqueue(code, manufacturer, now_us);
  active_.erase({code, kReportSource});
  update_register();
}

void EmcyProducer::clear(uint16_t code, uint64_t now_us, uint16_t source) {
  if (!active_.erase({code, source})) return;
  update_register();
  if (active_.empty()) enqueue(emcy_code::kNoError, {}, now_us);
}

void EmcyProducer::on_tick(uint64_t now_us) {
  if (!enabled_) return;
  // Inhibit time in multiples of 100 us (CiA 301 7.5.2.16).
  uint64_t inhibit_us = uint64_t{dictionary_.get<uint16_t>(0x1015, 0)} * 100;
  while (!pending_.empty()) {
    if (sent_any_ && now_us < last_sent_us_ + inhibit_us) return;
    // 0x1014 as it is now (CiA 301 7.5.2.17): a master may have made the EMCY invalid, or
    // moved it to another CAN-ID, while this message waited for the inhibit time.
    const uint32_t cob_id = dictionary_.get<uint32_t>(0x1014, 0);
    if (cob_id & 0x80000000u) {  // EMCY does not exist: nothing waiting is produced
      pending_.clear();
      return;
    }
    pending_.front().id = cob_id & 0x7FF;
    send_(pending_.front());
    pending_.pop_front();
    last_sent_us_ = now_us;
    sent_any_ = true;
  }
}

uint64_t EmcyProducer::next_deadline_us(uint64_t now_us) const {
  if (!enabled_ || pending_.empty()) return kNoDeadline;
  if (!sent_any_) return now_us;
  const uint64_t inhibit_us = uint64_t{dictionary_.get<uint16_t>(0x1015, 0)} * 100;
  return std::max(now_us, last_sent_us_ + inhibit_us);
}

void EmcyProducer::reset() {
  active_.clear();
  pending_.clear();
  sent_any_ = false;
  update_register();
}

void EmcyProducer::reset_communication(uint64_t now_us) {
  std::erase_if(
      active_, [](const auto& entry) { return entry.first.second == emcy_source::kCommunication; });
  pending_.clear();
  sent_any_ = false;
  update_register();
  for (const auto& [key, condition] : active_) {
    push_history(key.first, condition.manufacturer);
    enqueue(key.first, condition.manufacturer, now_us);  // sent once EMCY is enabled
  }
}

}  // namespace stepnode::node
