// The master's side of the bus for stepctl: raw frames with timeouts, and SDO transfers run
// to completion with od/'s SDO client state machine.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "canio/socketcan.hpp"
#include "od/sdo_client.hpp"

namespace stepnode::tools {

class MasterBus {
 public:
  explicit MasterBus(const std::string& iface);

  void send(const od::CanFrame& frame);
  // Waits up to timeout_ms for the next data frame (error frames are skipped).
  std::optional<canio::ReceivedFrame> receive(int timeout_ms);

  od::SdoResult upload(uint8_t node, uint16_t index, uint8_t sub,
                       od::SdoClient::Mode mode = od::SdoClient::Mode::Auto);
  od::SdoResult download(uint8_t node, uint16_t index, uint8_t sub, od::Bytes data,
                         od::SdoClient::Mode mode = od::SdoClient::Mode::Auto);

  void set_sdo_timeout_ms(int ms) { sdo_timeout_ms_ = ms; }
  const std::string& iface() const { return can_.iface(); }

 private:
  template <class Start>
  od::SdoResult run(uint8_t node, Start start);

  canio::SocketCan can_;
  int sdo_timeout_ms_ = 1000;
};

uint64_t monotonic_us();

}  // namespace stepnode::tools
