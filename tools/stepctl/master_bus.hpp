// The master's side of the bus for stepctl: raw frames with timeouts, and SDO transfers run
// to completion with od/'s SDO client state machine, on the node's default SDO channel
// (0x600+id / 0x580+id) or on the channel the user names (--sdo-cob-ids).
#pragma once
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "canio/socketcan.hpp"
#include "od/sdo_client.hpp"

namespace stepnode::tools {

// Another client talked on the SDO channel during our transfer and the transfer failed:
// what it got cannot be trusted, so no value is shown (stepctl exits 1 with this line).
struct SdoChannelBusy : std::runtime_error {
  explicit SdoChannelBusy(uint8_t node)
      : std::runtime_error("another master is using node " + std::to_string(node) +
                           "'s SDO channel") {}
};

// The COB-IDs of one SDO server channel (CiA 301 7.5.2.33 sub 1 and 2).
struct SdoCobIds {
  uint32_t client_to_server = 0;
  uint32_t server_to_client = 0;
};
// "0x685,0x6C5" (client->server, server->client); throws std::invalid_argument.
SdoCobIds parse_sdo_cob_ids(const std::string& text);

class MasterBus {
 public:
  explicit MasterBus(const std::string& iface);

  void send(const od::CanFrame& frame);
  // Waits up to timeout_ms for the next data frame (error frames are skipped).
  std::optional<canio::ReceivedFrame> receive(int timeout_ms);

  // Reads are repeated (kReadAttempts in all) when another master disturbed them; a
  // write is never repeated: whether the node took it is unknown. Both throw
  // SdoChannelBusy when the channel stayed busy.
  od::SdoResult upload(uint8_t node, uint16_t index, uint8_t sub,
                       od::SdoClient::Mode mode = od::SdoClient::Mode::Auto);
  od::SdoResult download(uint8_t node, uint16_t index, uint8_t sub, od::Bytes data,
                         od::SdoClient::Mode mode = od::SdoClient::Mode::Auto);

  void set_sdo_timeout_ms(int ms) { sdo_timeout_ms_ = ms; }
  // Every transfer goes to this channel instead of the node's default one.
  void set_sdo_cob_ids(SdoCobIds ids) { cob_ids_ = ids; }
  const std::string& iface() const { return can_.iface(); }

  static constexpr int kReadAttempts = 3;

 private:
  template <class Start>
  od::SdoResult run(uint8_t node, Start start, bool& disturbed);

  canio::SocketCan can_;
  int sdo_timeout_ms_ = 1000;
  std::optional<SdoCobIds> cob_ids_;
};

uint64_t monotonic_us();

}  // namespace stepnode::tools
