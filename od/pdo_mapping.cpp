#include "od/pdo_mapping.hpp"

namespace stepnode::od {

SdoAbort check_mapping_entry(const Dictionary& dictionary, uint32_t word, PdoDirection direction) {
  MappedEntry m = MappedEntry::from_word(word);
  if (m.dummy()) {
    // Dummy mapping skips bits of a received PDO; meaningless in a transmitted one.
    // BOOLEAN (0x0001) would be a 1-bit dummy; the EDS declares it unsupported.
    if (direction == PdoDirection::Transmit || m.index == 0x0001) return SdoAbort::NotMappable;
    size_t size = fixed_size(static_cast<DataType>(m.index));
    if (size == 0 || m.sub != 0) return SdoAbort::NotMappable;
    return m.bits == size * 8 ? SdoAbort::None : SdoAbort::ParameterIncompatible;
  }
  const Entry* e = dictionary.find(m.index, m.sub);
  if (!e) return dictionary.object(m.index) ? SdoAbort::NoSubindex : SdoAbort::NoObject;
  bool direction_ok =
      direction == PdoDirection::Receive ? writable(e->access) : readable(e->access);
  if (!e->pdo_mappable || !direction_ok || is_variable_length(e->type))
    return SdoAbort::NotMappable;
  if (m.bits != e->bit_length()) return SdoAbort::ParameterIncompatible;
  return SdoAbort::None;
}

SdoAbort check_mapping(const Dictionary& dictionary, std::span<const uint32_t> words,
                       PdoDirection direction) {
  size_t bits = 0;
  for (uint32_t w : words) {
    if (SdoAbort a = check_mapping_entry(dictionary, w, direction); a != SdoAbort::None) return a;
    bits += w & 0xFF;
  }
  return bits > kMaxPdoBits ? SdoAbort::PdoTooLong : SdoAbort::None;
}

SdoAbort check_mapping_record(const Dictionary& dictionary, uint16_t index) {
  const bool receive = is_rpdo_mapping(index);
  if (!receive && !is_tpdo_mapping(index)) return SdoAbort::NoObject;
  const Entry* count = dictionary.find(index, 0);
  if (!count) return SdoAbort::NoObject;
  const uint8_t n = static_cast<uint8_t>(as_unsigned(count->type, count->value));
  if (n > kMaxMappedEntries) return SdoAbort::PdoTooLong;  // more entries than the record has
  std::vector<uint32_t> words;
  for (uint8_t sub = 1; sub <= n; ++sub) {
    const Entry* e = dictionary.find(index, sub);
    if (!e) return SdoAbort::NoSubindex;
    words.push_back(static_cast<uint32_t>(as_unsigned(e->type, e->value)));
  }
  return check_mapping(dictionary, words, receive ? PdoDirection::Receive : PdoDirection::Transmit);
}

size_t mapping_bits(const PdoMapping& mapping) {
  size_t bits = 0;
  for (const auto& m : mapping) bits += m.bits;
  return bits;
}

void write_bits(std::span<uint8_t> dst, size_t bit_offset, uint64_t value, size_t bits) {
  for (size_t i = 0; i < bits; ++i) {
    size_t pos = bit_offset + i;
    uint8_t mask = static_cast<uint8_t>(1u << (pos % 8));
    if ((value >> i) & 1) dst[pos / 8] |= mask;
    else dst[pos / 8] &= static_cast<uint8_t>(~mask);
  }
}

uint64_t read_bits(std::span<const uint8_t> src, size_t bit_offset, size_t bits) {
  uint64_t v = 0;
  for (size_t i = 0; i < bits; ++i) {
    size_t pos = bit_offset + i;
    if ((src[pos / 8] >> (pos % 8)) & 1) v |= uint64_t{1} << i;
  }
  return v;
}

std::vector<uint8_t> pack_pdo(Dictionary& dictionary, const PdoMapping& mapping) {
  std::vector<uint8_t> out(mapping_bytes(mapping), 0);
  size_t offset = 0;
  for (const auto& m : mapping) {
    if (Entry* e = m.dummy() ? nullptr : dictionary.find(m.index, m.sub)) {
      if (e->on_read) e->on_read(e->value);
      write_bits(out, offset, as_unsigned(e->type, e->value), m.bits);
    }
    offset += m.bits;
  }
  return out;
}

SdoAbort unpack_pdo(Dictionary& dictionary, const PdoMapping& mapping,
                    std::span<const uint8_t> data) {
  // A PDO shorter than its mapping is not processed (CiA 301 7.2.2.2; the node sends EMCY
  // 0x8210). Refusing here also keeps read_bits inside the buffer.
  if (data.size() * 8 < mapping_bits(mapping)) return SdoAbort::LengthTooLow;
  size_t offset = 0;
  SdoAbort first = SdoAbort::None;
  std::vector<std::pair<Entry*, Bytes>> written;  // with the value each had before
  for (const auto& m : mapping) {
    if (!m.dummy()) {
      Bytes value = encode<uint64_t>(read_bits(data, offset, m.bits));
      value.resize((m.bits + 7) / 8);
      Entry* e = dictionary.find(m.index, m.sub);
      Bytes previous = e ? e->value : Bytes{};
      SdoAbort a = dictionary.write(m.index, m.sub, value, WriteOrigin::Pdo);
      if (a == SdoAbort::None) written.emplace_back(e, std::move(previous));
      else if (e && e->on_pdo_refused) e->on_pdo_refused(value, a);
      if (first == SdoAbort::None) first = a;
    }
    offset += m.bits;
  }
  // Reactions after the whole PDO is in (a command sees the destination sent with it). A
  // PDO has no answer: a refused command reports itself (its owner's error and EMCY).
  for (auto& [e, previous] : written) (void)run_reactions(*e, previous);
  return first;
}

void set_default_mapping(Dictionary& dictionary, uint16_t map_index,
                         std::initializer_list<uint32_t> words) {
  uint8_t n = 0;
  for (uint32_t w : words) {
    Entry& e = dictionary.at(map_index, ++n);
    e.default_value = e.value = encode<uint32_t>(w);
  }
  Entry& count = dictionary.at(map_index, 0);
  count.default_value = count.value = {n};
}

}  // namespace stepnode::od
