// PDO mapping (CiA 301 7.4.7 / 7.5.2.36): validating a mapping against the dictionary and
// packing/unpacking PDO data bit-exactly, little-endian.
#pragma once
#include <cstdint>
#include <initializer_list>
#include <span>
#include <vector>

#include "od/dictionary.hpp"

namespace stepnode::od {

enum class PdoDirection { Receive, Transmit };

struct MappedEntry {
  uint16_t index = 0;
  uint8_t sub = 0;
  uint8_t bits = 0;
  bool dummy() const { return index >= 0x0001 && index <= 0x0007; }
  static MappedEntry from_word(uint32_t word) {
    return {static_cast<uint16_t>(word >> 16), static_cast<uint8_t>(word >> 8),
            static_cast<uint8_t>(word)};
  }
};

using PdoMapping = std::vector<MappedEntry>;

constexpr unsigned kMaxPdoBits = 64;
constexpr unsigned kMaxMappedEntries = 8;

// Checks one mapping word: object exists and is mappable in that direction, the length
// matches the entry. RPDOs may map dummy entries (index 0x0001..0x0007 = a data type).
SdoAbort check_mapping_entry(const Dictionary& dictionary, uint32_t word, PdoDirection direction);
// Checks a whole mapping (each entry, and the total length <= 64 bits: 0x06040042).
SdoAbort check_mapping(const Dictionary& dictionary, std::span<const uint32_t> words,
                       PdoDirection direction);

// Checks the mapping record at `index` as it stands in the dictionary: RPDO mappings
// 0x1600..0x17FF, TPDO mappings 0x1A00..0x1BFF (sub 0 the number of entries, at most 8).
// Stored or configured records are loaded without the mapping procedure; this is its rule.
SdoAbort check_mapping_record(const Dictionary& dictionary, uint16_t index);
inline bool is_rpdo_mapping(uint16_t index) { return index >= 0x1600 && index <= 0x17FF; }
// The records of PDO n (from 0): RPDO communication 0x1400+n and mapping 0x1600+n, TPDO
// communication 0x1800+n and mapping 0x1A00+n.
constexpr uint16_t rpdo_parameter(unsigned n) { return static_cast<uint16_t>(0x1400 + n); }
constexpr uint16_t rpdo_mapping(unsigned n) { return static_cast<uint16_t>(0x1600 + n); }
constexpr uint16_t tpdo_parameter(unsigned n) { return static_cast<uint16_t>(0x1800 + n); }
constexpr uint16_t tpdo_mapping(unsigned n) { return static_cast<uint16_t>(0x1A00 + n); }
inline bool is_tpdo_mapping(uint16_t index) { return index >= 0x1A00 && index <= 0x1BFF; }

// A mapping entry (CiA 301 7.5.2.36): index << 16 | sub << 8 | length in bits.
constexpr uint32_t mapping_word(uint16_t index, uint8_t sub, uint8_t bits) {
  return (static_cast<uint32_t>(index) << 16) | (static_cast<uint32_t>(sub) << 8) | bits;
}
// Makes `words` the default (and present) mapping of the record `map_index`
// (rpdo_mapping(n) or tpdo_mapping(n)), with sub 0 their count: a profile's default PDOs,
// the one place they are built.
void set_default_mapping(Dictionary& dictionary, uint16_t map_index,
                         std::initializer_list<uint32_t> words);

size_t mapping_bits(const PdoMapping& mapping);
inline size_t mapping_bytes(const PdoMapping& mapping) { return (mapping_bits(mapping) + 7) / 8; }

// Packs the mapped values into a PDO payload (bit by bit, LSB first). An entry the
// dictionary does not have packs as zeros (check_mapping_record keeps such mappings out
// of use; this keeps a stale one from ever throwing in the send path).
std::vector<uint8_t> pack_pdo(Dictionary& dictionary, const PdoMapping& mapping);
// Writes the values of a received PDO into the dictionary (WriteOrigin::Pdo). Data shorter
// than the mapping writes nothing and gives LengthTooLow; extra bytes are ignored. Returns
// the first abort from a write (e.g. out of range), or None.
SdoAbort unpack_pdo(Dictionary& dictionary, const PdoMapping& mapping,
                    std::span<const uint8_t> data);

// Bit-level helpers, exposed for tests.
void write_bits(std::span<uint8_t> dst, size_t bit_offset, uint64_t value, size_t bits);
uint64_t read_bits(std::span<const uint8_t> src, size_t bit_offset, size_t bits);

}  // namespace stepnode::od
