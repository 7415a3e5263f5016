#include "node/profiles/horner/refused_words.hpp"

#include "node/profiles/horner/objects.hpp"

namespace stepnode::node {
namespace {

uint32_t key(uint16_t index, uint8_t sub) { return static_cast<uint32_t>(index) << 8 | sub; }

// The raw bits as the entry's own type (I32 sign-extended from 32 bits; U16/U32 as is).
template <class T>
T as(uint64_t raw) {
  return static_cast<T>(raw);
}

}  // namespace

RefusedWords::RefusedWords(od::Dictionary& dictionary, unsigned a) : axis_(a) {
  using namespace horner::obj;
  watch(dictionary.at(index(a, kDestination), 0));
  for (uint8_t sub = horner::profile_sub::kVelocityDivisor;
       sub <= horner::profile_sub::kDeceleration; ++sub)
    watch(dictionary.at(index(a, kProfile), sub));
  for (uint8_t sub = horner::indexed_sub::kDestination; sub <= horner::indexed_sub::kWindowClose;
       ++sub)
    watch(dictionary.at(index(a, kIndexedMove), sub));
}

void RefusedWords::watch(od::Entry& entry) {
  uint32_t k = key(entry.index, entry.sub);
  entry.on_pdo_refused = [this, k](std::span<const uint8_t> value, od::SdoAbort) {
    uint64_t raw = 0;
    for (size_t i = 0; i < value.size() && i < 8; ++i) raw |= uint64_t{value[i]} << (8 * i);
    refused_[k] = raw;
  };
  // A valid value replaces the refused one; the word's other reactions still run.
  od::listen(entry, [this, k] { refused_.erase(k); });
}

void RefusedWords::overlay(motion::CommandWords& w) const {
  using namespace horner::obj;
  for (const auto& [k, raw] : refused_) {
    uint16_t offset = static_cast<uint16_t>((k >> 8) - index(axis_, 0));
    auto sub = static_cast<uint8_t>(k & 0xFF);
    if (offset == kDestination) {
      w.destination = as<int32_t>(raw);
    } else if (offset == kProfile) {
      switch (sub) {
        case horner::profile_sub::kVelocityDivisor: w.velocity_divisor = as<uint16_t>(raw); break;
        case horner::profile_sub::kBaseVelocity: w.base_velocity = as<uint16_t>(raw); break;
        case horner::profile_sub::kRunningVelocity: w.running_velocity = as<uint16_t>(raw); break;
        case horner::profile_sub::kAcceleration: w.acceleration_ms = as<uint16_t>(raw); break;
        case horner::profile_sub::kDeceleration: w.deceleration_ms = as<uint16_t>(raw); break;
      }
    } else if (offset == kIndexedMove) {
      switch (sub) {
        case horner::indexed_sub::kDestination: w.index_destination = as<uint32_t>(raw); break;
        case horner::indexed_sub::kDeceleration: w.index_deceleration_ms = as<uint16_t>(raw); break;
        case horner::indexed_sub::kWindowOpen: w.index_window_open = as<uint32_t>(raw); break;
        case horner::indexed_sub::kWindowClose: w.index_window_close = as<uint32_t>(raw); break;
      }
    }
  }
}

}  // namespace stepnode::node
