// CiA 301 data types (7.1) and object-dictionary access rights.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace stepnode::od {

// Values are the CiA 301 data type indices (they also appear in the EDS as DataType=).
enum class DataType : uint16_t {
  Boolean = 0x0001,
  Integer8 = 0x0002,
  Integer16 = 0x0003,
  Integer32 = 0x0004,
  Unsigned8 = 0x0005,
  Unsigned16 = 0x0006,
  Unsigned32 = 0x0007,
  Real32 = 0x0008,
  VisibleString = 0x0009,
  OctetString = 0x000A,
  Domain = 0x000F,
  Real64 = 0x0011,
  Integer64 = 0x0015,
  Unsigned64 = 0x001B,
};

enum class Access : uint8_t { ReadOnly, WriteOnly, ReadWrite, Const };

// Size in bytes of a fixed-size type; 0 for strings and domains (variable length).
size_t fixed_size(DataType type);
bool is_variable_length(DataType type);
bool is_signed_integer(DataType type);
bool is_unsigned_integer(DataType type);  // Boolean counts as unsigned
bool is_real(DataType type);

std::string_view type_name(DataType type);  // "UNSIGNED16", ...
std::optional<DataType> type_from_name(std::string_view name);
std::string_view access_eds_name(Access access);  // "ro", "wo", "rw", "const"
bool readable(Access access);
bool writable(Access access);

}  // namespace stepnode::od
