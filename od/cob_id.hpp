// The COB-ID entry layout of CiA 301 7.5.2 (EMCY, PDO, SDO parameter objects) and the rule
// every configurable one follows when it is written.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "od/sdo_abort.hpp"

namespace stepnode::od {

constexpr uint32_t kCobInvalid = 0x80000000;  // bit 31: object does not exist / not valid
constexpr uint32_t kCobGenerate =
    0x40000000;  // bit 30: SYNC producer (0x1005), no RTR (TPDO), dynamic (SDO)
constexpr uint32_t kCobExtended = 0x20000000;    // bit 29: 29-bit ID (not supported)
constexpr uint32_t kCobIdHighBits = 0x1FFFF800;  // bits 11..28: 0 for an 11-bit CAN-ID

// No 29-bit IDs (bit 29, and bits 11..28 are 0 with an 11-bit CAN-ID), no restricted IDs,
// and the CAN-ID of an object that is valid may not change: set bit 31 first (CiA 301
// 7.3.5, 7.5.2.17, 7.5.2.33, 7.5.2.35, 7.5.2.37). `valid_mask_when_clear` is the bit that,
// clear, makes the object valid (kCobInvalid), or 0 for an object that is always valid.
SdoAbort check_cob_id(uint32_t current, uint32_t next, uint32_t valid_mask_when_clear);

// An 11-bit CAN-ID (1..0x7FF) as a user writes it ("0x685", "1669"), or nullopt.
std::optional<uint32_t> parse_can_id(const std::string& text);

}  // namespace stepnode::od
