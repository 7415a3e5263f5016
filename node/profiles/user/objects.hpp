// The user objects: general-purpose storage for the master, registers it can map into
// PDOs (0x2F00) and a data block (0x2F01), both kept by "store parameters" like any other
// setting. Pure table; nothing reacts to them.
#pragma once
#include <cstddef>
#include <cstdint>

#include "od/dictionary.hpp"

namespace stepnode::user {

constexpr uint16_t kRegisters = 0x2F00;  // ARRAY of 8 U32 rw, PDO-mappable
constexpr uint16_t kData = 0x2F01;       // DOMAIN rw
constexpr size_t kDataMaxLength = 4096;

void add_objects(od::Dictionary& od);

}  // namespace stepnode::user
