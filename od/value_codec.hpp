// Little-endian encoding of typed values into object-dictionary byte strings.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>
#include <type_traits>
#include <vector>

#include "od/data_type.hpp"

namespace stepnode::od {

using Bytes = std::vector<uint8_t>;

template <class T>
Bytes encode(T value) {
  static_assert(std::is_arithmetic_v<T>);
  Bytes out(sizeof(T));
  if constexpr (std::is_floating_point_v<T>) {
    std::memcpy(out.data(), &value, sizeof(T));  // IEEE 754, little-endian host
  } else {
    using U = std::make_unsigned_t<T>;
    U u = static_cast<U>(value);
    for (size_t i = 0; i < sizeof(T); ++i) out[i] = static_cast<uint8_t>(u >> (8 * i));
  }
  return out;
}

inline Bytes encode_string(std::string_view s) { return Bytes(s.begin(), s.end()); }

// Decodes up to sizeof(T) bytes (missing bytes read as zero, sign not extended).
template <class T>
T decode(std::span<const uint8_t> bytes) {
  static_assert(std::is_arithmetic_v<T>);
  if constexpr (std::is_floating_point_v<T>) {
    T value{};
    std::memcpy(&value, bytes.data(), std::min(bytes.size(), sizeof(T)));
    return value;
  } else {
    using U = std::make_unsigned_t<T>;
    U u = 0;
    for (size_t i = 0; i < sizeof(T) && i < bytes.size(); ++i)
      u |= static_cast<U>(bytes[i]) << (8 * i);
    return static_cast<T>(u);
  }
}

// Type-aware views of a stored value, for comparisons, printing and limits.
int64_t as_signed(DataType type, std::span<const uint8_t> bytes);     // sign-extended
uint64_t as_unsigned(DataType type, std::span<const uint8_t> bytes);  // zero-extended
double as_real(DataType type, std::span<const uint8_t> bytes);
// <0, 0, >0 like strcmp, by the numeric meaning of the type. Only for fixed-size types.
int compare_values(DataType type, std::span<const uint8_t> a, std::span<const uint8_t> b);

// Human text of a value ("1000", "-5", "0x00000191", "\"stepnode\"", "12 bytes").
std::string format_value(DataType type, std::span<const uint8_t> bytes, bool hex = false);
// Parses text into a value of the type: decimal, 0x-hex, float, or a string. For a signed
// type, unsigned hex of the type's width is its two's-complement pattern. Throws
// std::invalid_argument naming the text and the type when it does not fit.
Bytes parse_value(DataType type, std::string_view text);

}  // namespace stepnode::od
