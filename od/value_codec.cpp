#include "od/value_codec.hpp"

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>

namespace stepnode::od {

int64_t as_signed(DataType type, std::span<const uint8_t> bytes) {
  switch (type) {
    case DataType::Integer8: return decode<int8_t>(bytes);
    case DataType::Integer16: return decode<int16_t>(bytes);
    case DataType::Integer32: return decode<int32_t>(bytes);
    case DataType::Integer64: return decode<int64_t>(bytes);
    default: return static_cast<int64_t>(as_unsigned(type, bytes));
  }
}

uint64_t as_unsigned(DataType type, std::span<const uint8_t> bytes) {
  size_t n = fixed_size(type);
  if (n == 0 || n > bytes.size()) n = std::min<size_t>(bytes.size(), 8);
  uint64_t v = 0;
  for (size_t i = 0; i < n; ++i) v |= static_cast<uint64_t>(bytes[i]) << (8 * i);
  return v;
}

double as_real(DataType type, std::span<const uint8_t> bytes) {
  if (type == DataType::Real32) return decode<float>(bytes);
  if (type == DataType::Real64) return decode<double>(bytes);
  if (is_signed_integer(type)) return static_cast<double>(as_signed(type, bytes));
  return static_cast<double>(as_unsigned(type, bytes));
}

int compare_values(DataType type, std::span<const uint8_t> a, std::span<const uint8_t> b) {
  if (is_real(type)) {
    double x = as_real(type, a), y = as_real(type, b);
    return x < y ? -1 : (x > y ? 1 : 0);
  }
  if (is_signed_integer(type)) {
    int64_t x = as_signed(type, a), y = as_signed(type, b);
    return x < y ? -1 : (x > y ? 1 : 0);
  }
  uint64_t x = as_unsigned(type, a), y = as_unsigned(type, b);
  return x < y ? -1 : (x > y ? 1 : 0);
}

std::string format_value(DataType type, std::span<const uint8_t> bytes, bool hex) {
  if (type == DataType::VisibleString) return "\"" + std::string(bytes.begin(), bytes.end()) + "\"";
  if (type == DataType::OctetString || type == DataType::Domain) {
    std::string out = std::to_string(bytes.size()) + " bytes";
    if (!bytes.empty()) out += ":";
    static const char* digits = "0123456789abcdef";
    for (size_t i = 0; i < bytes.size() && i < 16; ++i) {
      out += ' ';
      out += digits[bytes[i] >> 4];
      out += digits[bytes[i] & 15];
    }
    if (bytes.size() > 16) out += " ...";
    return out;
  }
  if (is_real(type)) {
    // Shortest text that reads back to the same value in the type's own precision: a
    // REAL32 0.1 prints "0.1", not the double "0.10000000149011612".
    char buf[64];
    auto [p, ec] = type == DataType::Real32
                       ? std::to_chars(buf, buf + sizeof buf, decode<float>(bytes))
                       : std::to_chars(buf, buf + sizeof buf, as_real(type, bytes));
    return std::string(buf, p);
  }
  if (hex) {
    char buf[32];
    int width = static_cast<int>(fixed_size(type) * 2);
    std::snprintf(buf, sizeof buf, "0x%0*llx", width,
                  static_cast<unsigned long long>(as_unsigned(type, bytes)));
    return buf;
  }
  if (is_signed_integer(type)) return std::to_string(as_signed(type, bytes));
  return std::to_string(as_unsigned(type, bytes));
}

namespace {

[[noreturn]] void bad(std::string_view text, DataType type, std::string_view why) {
  throw std::invalid_argument("value '" + std::string(text) + "' is not a valid " +
                              std::string(type_name(type)) + ": " + std::string(why));
}

}  // namespace

Bytes parse_value(DataType type, std::string_view text) {
  if (type == DataType::VisibleString || type == DataType::OctetString ||
      type == DataType::Domain) {
    return encode_string(text);
  }
  if (text.empty()) bad(text, type, "empty");
  std::string s(text);
  if (is_real(type)) {
    char* end = nullptr;
    errno = 0;
    double v = std::strtod(s.c_str(), &end);
    if (std::isspace(static_cast<unsigned char>(s[0])) || *end != '\0' || errno != 0)
      bad(text, type, "not a number");
    if (type == DataType::Real32) {
      // A finite double beyond the float range has no REAL32 value (and converting it is
      // undefined behaviour).
      if (std::isfinite(v) && std::fabs(v) > std::numeric_limits<float>::max())
        bad(text, type, "out of range");
      return encode<float>(static_cast<float>(v));
    }
    return encode<double>(v);
  }
  bool negative = s[0] == '-';
  std::string digits = negative || s[0] == '+' ? s.substr(1) : s;
  int base = 10;
  if (digits.size() > 2 && digits[0] == '0' && (digits[1] == 'x' || digits[1] == 'X')) {
    base = 16;
    digits = digits.substr(2);
  }
  uint64_t magnitude = 0;
  auto [p, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), magnitude, base);
  if (ec != std::errc{} || p != digits.data() + digits.size() || digits.empty())
    bad(text, type, "not an integer");
  size_t size = fixed_size(type);
  if (is_signed_integer(type)) {
    int bits = static_cast<int>(size * 8);
    // Hex without a sign is the two's-complement bit pattern of the type ("0xFFFE" is an
    // INTEGER16 -2), as format_value(hex) prints it and EDS files write signed limits.
    if (base == 16 && !negative && (size == 8 || magnitude >> bits == 0)) {
      Bytes all = encode<uint64_t>(magnitude);
      return Bytes(all.begin(), all.begin() + static_cast<long>(size));
    }
    uint64_t max_pos = (uint64_t{1} << (bits - 1)) - 1;
    if ((!negative && magnitude > max_pos) || (negative && magnitude > max_pos + 1))
      bad(text, type, "out of range");
    int64_t v = negative ? static_cast<int64_t>(0 - magnitude) : static_cast<int64_t>(magnitude);
    Bytes all = encode<int64_t>(v);
    return Bytes(all.begin(), all.begin() + static_cast<long>(size));
  }
  if (negative && magnitude != 0) bad(text, type, "negative value for an unsigned type");
  if (type == DataType::Boolean && magnitude > 1) bad(text, type, "must be 0 or 1");
  if (size < 8 && magnitude >> (size * 8)) bad(text, type, "out of range");
  Bytes all = encode<uint64_t>(magnitude);
  return Bytes(all.begin(), all.begin() + static_cast<long>(size));
}

}  // namespace stepnode::od
