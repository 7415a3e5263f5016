#include "bridge/observer/bus_error_counter.hpp"

#if __has_include(<linux/can/error.h>)
#include <linux/can/error.h>
static_assert(stepnode::bridge::can_err::kCrtl == CAN_ERR_CRTL);
static_assert(stepnode::bridge::can_err::kBusOff == CAN_ERR_BUSOFF);
static_assert(stepnode::bridge::can_err::kCrtlRxOverflow == CAN_ERR_CRTL_RX_OVERFLOW);
static_assert(stepnode::bridge::can_err::kCrtlTxOverflow == CAN_ERR_CRTL_TX_OVERFLOW);
static_assert(stepnode::bridge::can_err::kCrtlRxPassive == CAN_ERR_CRTL_RX_PASSIVE);
static_assert(stepnode::bridge::can_err::kCrtlTxPassive == CAN_ERR_CRTL_TX_PASSIVE);
#endif

namespace stepnode::bridge {

void count_error_frame(BusCounters& c, uint32_t error_class, uint8_t controller_status) {
  ++c.error_frames;
  if (error_class & can_err::kBusOff) ++c.bus_off;
  if (error_class & can_err::kCrtl) {
    // One frame may report both directions passive: still one transition to count.
    if (controller_status & (can_err::kCrtlRxPassive | can_err::kCrtlTxPassive)) ++c.error_passive;
    if (controller_status & (can_err::kCrtlRxOverflow | can_err::kCrtlTxOverflow)) ++c.overruns;
  }
}

}  // namespace stepnode::bridge
