// The bridge's use of one node's SDO server. A server has a single channel (CiA 301
// 7.2.4.1): a second client talking at the same time breaks both transfers. So this
// class
//  - runs one upload at a time through od::SdoClient,
//  - tells the node's own answers from another master's traffic, and says when the
//    channel has been quiet long enough to start (as stepctl watch does),
//  - gives a transfer up without a frame when another master starts talking mid-way,
//  - recognises another master's confirmed download (initiate request on 0x600+id, the
//    node's initiate response on 0x580+id) so the caller can re-read what was written,
//  - ignores the echo of its own requests when the socket loops them back (only when told
//    so: two bridges reading the same object send identical frames).
// Given a channel of its own (one of the node's 0x1201..0x1203, CiA 301 7.5.2.33), it
// reads there and the masters' traffic on the default channel neither delays nor breaks
// its reads; it still watches the default channel for the masters' confirmed downloads.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "od/can_frame.hpp"
#include "od/sdo_client.hpp"

namespace stepnode::bridge {

class SdoChannel {
 public:
  // `echoed`: our own requests come back from the socket (see ObserverConfig).
  // `request_id`/`response_id`: the server channel to read on; 0 = the default channel
  // (0x600+node / 0x580+node).
  SdoChannel(uint8_t node, uint64_t timeout_us, uint64_t quiet_us, bool echoed = false,
             uint32_t request_id = 0, uint32_t response_id = 0);

  struct FrameEvent {
    bool completed = false;  // our transfer ended (result() holds the answer)
    bool collision = false;  // another master started mid-transfer: ours was dropped
    std::optional<uint16_t> foreign_download;  // index another master wrote, confirmed
  };

  bool idle() const { return !in_flight_; }
  // Idle, and no other master's SDO frame for the quiet time (plus any extra wait).
  bool can_start(uint64_t now_us) const;
  // One-off extra quiet time before the next start (random, after a collision).
  void add_quiet(uint64_t extra_us) { extra_quiet_us_ = extra_us; }
  void start_upload(uint16_t index, uint8_t sub, uint64_t now_us, std::vector<od::CanFrame>& out);
  // A frame on this channel's or the default channel's COB-IDs.
  FrameEvent on_frame(const od::CanFrame& frame, uint64_t now_us, std::vector<od::CanFrame>& out);
  // Times out our transfer; true when it ended (with SdoAbort::Timeout).
  bool on_tick(uint64_t now_us, std::vector<od::CanFrame>& out);
  // Another master used the default channel at `at_us` (seen before this channel
  // existed). A channel of our own is not delayed by that.
  void note_foreign(uint64_t at_us) {
    if (request_id_ != od::cob::kSdoRx + node_) return;
    foreign_seen_ = true;
    last_foreign_us_ = at_us;
  }
  // Forgets the transfer in flight without a frame (the node rebooted, stopped, was lost).
  void cancel();
  const od::SdoResult& result() const { return client_->result(); }

 private:
  void remember_sent(const std::vector<od::CanFrame>& out, size_t from, uint64_t now_us);
  bool is_own_echo(const od::CanFrame& frame, uint64_t now_us);
  FrameEvent on_request(const od::CanFrame& frame, uint64_t now_us);
  FrameEvent on_response(const od::CanFrame& frame, uint64_t now_us,
                         std::vector<od::CanFrame>& out);
  void note_download_request(const od::CanFrame& frame);
  std::optional<uint16_t> confirmed_download(const od::CanFrame& frame);
  void new_client();

  uint8_t node_;
  uint32_t request_id_;   // client -> server: where our requests go
  uint32_t response_id_;  // server -> client
  uint64_t timeout_us_;
  uint64_t quiet_us_;
  bool echoed_;
  std::unique_ptr<od::SdoClient> client_;
  bool in_flight_ = false;
  bool foreign_seen_ = false;
  uint64_t last_foreign_us_ = 0;
  uint64_t extra_quiet_us_ = 0;
  // Another master's download initiate, waiting for the node's confirmation.
  bool download_pending_ = false;
  uint16_t download_index_ = 0;
  // Requests we sent that may still come back as an echo (each matches once).
  struct Sent {
    od::CanFrame frame;
    uint64_t at_us = 0;
    bool live = false;
  };
  std::array<Sent, 4> sent_{};
  size_t sent_next_ = 0;
};

}  // namespace stepnode::bridge
