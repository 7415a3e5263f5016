// CAN error frames (SocketCAN, linux/can/error.h) into the bus counters: error passive,
// bus off, controller overruns. Pure: the constants are restated here so the observer
// needs no Linux header, and checked against it where it exists.
#pragma once
#include <cstdint>

#include "bridge/samples.hpp"

namespace stepnode::bridge {

namespace can_err {
constexpr uint32_t kCrtl = 0x00000004;     // CAN_ERR_CRTL: controller problems in data[1]
constexpr uint32_t kBusOff = 0x00000040;   // CAN_ERR_BUSOFF
constexpr uint8_t kCrtlRxOverflow = 0x01;  // CAN_ERR_CRTL_RX_OVERFLOW
constexpr uint8_t kCrtlTxOverflow = 0x02;  // CAN_ERR_CRTL_TX_OVERFLOW
constexpr uint8_t kCrtlRxPassive = 0x10;   // CAN_ERR_CRTL_RX_PASSIVE
constexpr uint8_t kCrtlTxPassive = 0x20;   // CAN_ERR_CRTL_TX_PASSIVE
}  // namespace can_err

void count_error_frame(BusCounters& counters, uint32_t error_class, uint8_t controller_status);

}  // namespace stepnode::bridge
