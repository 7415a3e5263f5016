// The node's SDO server channels (CiA 301 7.2.4.1, 7.5.2.33): one od::SdoServer per SDO
// server parameter object 0x1200..0x1203. CiA 301 allows one client per channel, so each
// channel has its own transfer state: two clients on two channels never see each other's
// answers. A frame goes to the channel whose client->server COB-ID it carries, and that
// channel answers on its own server->client COB-ID.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "node/deadline.hpp"
#include "od/can_frame.hpp"
#include "od/dictionary.hpp"
#include "od/sdo_server.hpp"
#include "od/sdo_server_parameter.hpp"

namespace stepnode::node {

class SdoServerChannels {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  // Installs the reactions to writes of 0x1201..0x1203's COB-IDs.
  SdoServerChannels(od::Dictionary& dictionary, uint64_t timeout_us, Send send);

  // True when the frame was an SDO request to one of the valid channels (and was handled).
  bool on_frame(const od::CanFrame& frame, uint64_t now_us);
  // Server-side timeouts of every channel.
  void on_tick(uint64_t now_us);
  // A transfer in progress times out in on_tick (SDO protocol timed out, 0x05040000): the
  // earliest channel's timeout instant (its client's last frame + the SDO timeout), or a
  // block download's stalled sub-block acknowledgement (half the timeout) before it.
  // kNoDeadline with every channel idle.
  uint64_t next_deadline_us(uint64_t now_us) const;
  // Drops every transfer in progress, without a frame (NMT states without SDO, resets).
  void reset();
  // Takes the COB-IDs from the dictionary again (after a restore of stored values); a
  // channel whose COB-IDs changed or became invalid loses its transfer.
  void reconfigure();

 private:
  struct Channel {
    std::unique_ptr<od::SdoServer> server;
    od::SdoChannelIds ids;
  };
  void send_all();

  od::Dictionary& dictionary_;
  Send send_;
  std::array<Channel, od::kSdoServerChannels> channels_;
  std::vector<od::CanFrame> out_;
  bool changed_ = false;  // a COB-ID was written; reconfigure() after the answer
};

}  // namespace stepnode::node
