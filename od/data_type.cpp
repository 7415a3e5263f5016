#include "od/data_type.hpp"

#include <array>
#include <utility>

namespace stepnode::od {
namespace {

struct TypeInfo {
  DataType type;
  std::string_view name;
  size_t size;
};

constexpr std::array<TypeInfo, 14> kTypes{{
    {DataType::Boolean, "BOOLEAN", 1},
    {DataType::Integer8, "INTEGER8", 1},
    {DataType::Integer16, "INTEGER16", 2},
    {DataType::Integer32, "INTEGER32", 4},
    {DataType::Unsigned8, "UNSIGNED8", 1},
    {DataType::Unsigned16, "UNSIGNED16", 2},
    {DataType::Unsigned32, "UNSIGNED32", 4},
    {DataType::Real32, "REAL32", 4},
    {DataType::VisibleString, "VISIBLE_STRING", 0},
    {DataType::OctetString, "OCTET_STRING", 0},
    {DataType::Domain, "DOMAIN", 0},
    {DataType::Real64, "REAL64", 8},
    {DataType::Integer64, "INTEGER64", 8},
    {DataType::Unsigned64, "UNSIGNED64", 8},
}};

const TypeInfo* info(DataType type) {
  for (const auto& t : kTypes)
    if (t.type == type) return &t;
  return nullptr;
}

}  // namespace

size_t fixed_size(DataType type) {
  const TypeInfo* t = info(type);
  return t ? t->size : 0;
}

bool is_variable_length(DataType type) { return fixed_size(type) == 0; }

bool is_signed_integer(DataType type) {
  return type == DataType::Integer8 || type == DataType::Integer16 || type == DataType::Integer32 ||
         type == DataType::Integer64;
}

bool is_unsigned_integer(DataType type) {
  return type == DataType::Boolean || type == DataType::Unsigned8 || type == DataType::Unsigned16 ||
         type == DataType::Unsigned32 || type == DataType::Unsigned64;
}

bool is_real(DataType type) { return type == DataType::Real32 || type == DataType::Real64; }

std::string_view type_name(DataType type) {
  const TypeInfo* t = info(type);
  return t ? t->name : "UNKNOWN";
}

std::optional<DataType> type_from_name(std::string_view name) {
  for (const auto& t : kTypes)
    if (t.name == name) return t.type;
  return std::nullopt;
}

std::string_view access_eds_name(Access access) {
  switch (access) {
    case Access::ReadOnly: return "ro";
    case Access::WriteOnly: return "wo";
    case Access::ReadWrite: return "rw";
    case Access::Const: return "const";
  }
  return "ro";
}

bool readable(Access access) { return access != Access::WriteOnly; }
bool writable(Access access) { return access == Access::WriteOnly || access == Access::ReadWrite; }

}  // namespace stepnode::od
