// SDO abort codes (CiA 301 7.2.4.3.17). A value of None means success.
#pragma once
#include <cstdint>
#include <string_view>

namespace stepnode::od {

enum class SdoAbort : uint32_t {
  None = 0,
  ToggleBit = 0x05030000,
  Timeout = 0x05040000,
  BadCommand = 0x05040001,
  InvalidBlockSize = 0x05040002,
  InvalidSequence = 0x05040003,
  CrcError = 0x05040004,
  OutOfMemory = 0x05040005,
  UnsupportedAccess = 0x06010000,
  WriteOnly = 0x06010001,
  ReadOnly = 0x06010002,
  NoObject = 0x06020000,
  NotMappable = 0x06040041,
  PdoTooLong = 0x06040042,
  ParameterIncompatible = 0x06040043,
  DeviceIncompatible = 0x06040047,
  Hardware = 0x06060000,
  LengthMismatch = 0x06070010,
  LengthTooHigh = 0x06070012,
  LengthTooLow = 0x06070013,
  NoSubindex = 0x06090011,
  InvalidValue = 0x06090030,
  ValueTooHigh = 0x06090031,
  ValueTooLow = 0x06090032,
  MaxBelowMin = 0x06090036,
  General = 0x08000000,
  DataTransfer = 0x08000020,
  LocalControl = 0x08000021,
  DeviceState = 0x08000022,
  NoDictionary = 0x08000023,
  NoData = 0x08000024,
};

// The CiA 301 text of the code, for logs and tools ("Object does not exist ...").
std::string_view abort_text(SdoAbort code);
std::string_view abort_text(uint32_t code);

}  // namespace stepnode::od
