#include "node/sdo_server_channels.hpp"

#include <spdlog/spdlog.h>

namespace stepnode::node {

SdoServerChannels::SdoServerChannels(od::Dictionary& dictionary, uint64_t timeout_us, Send send)
    : dictionary_(dictionary), send_(std::move(send)) {
  for (unsigned c = 0; c < od::kSdoServerChannels; ++c) {
    channels_[c].ids = od::sdo_channel_ids(dictionary_, c);
    channels_[c].server = std::make_unique<od::SdoServer>(dictionary_, channels_[c].ids.tx);
    channels_[c].server->set_timeout_us(timeout_us);
  }
  // The write arrives over a channel, possibly the one it changes, from inside that
  // channel's server: the change applies once the server has answered (on the old COB-ID),
  // not in the middle of its transfer.
  for (unsigned c = 1; c < od::kSdoServerChannels; ++c) {
    const auto index = static_cast<uint16_t>(od::kSdoServerParameter + c);
    for (uint8_t sub : {od::sdo_param::kCobIdClientToServer, od::sdo_param::kCobIdServerToClient})
      od::listen(dictionary_.at(index, sub), [this] { changed_ = true; });
  }
}

bool SdoServerChannels::on_frame(const od::CanFrame& frame, uint64_t now_us) {
  if (frame.rtr) return false;
  for (Channel& ch : channels_) {
    if (!ch.ids.valid || frame.id != ch.ids.rx) continue;
    out_.clear();
    ch.server->on_request(frame, now_us, out_);
    send_all();
    if (changed_) reconfigure();
    return true;
  }
  return false;
}

void SdoServerChannels::on_tick(uint64_t now_us) {
  if (changed_) reconfigure();  // written by the node itself (config defaults, restore)
  out_.clear();
  for (Channel& ch : channels_)
    if (ch.ids.valid) ch.server->on_tick(now_us, out_);
  send_all();
}

uint64_t SdoServerChannels::next_deadline_us(uint64_t now_us) const {
  if (changed_) return now_us;
  uint64_t next = kNoDeadline;
  for (const Channel& ch : channels_)
    if (ch.ids.valid)
      if (const std::optional<uint64_t> at = ch.server->next_deadline_us())
        next = earliest(next, *at);
  return next;
}

void SdoServerChannels::reset() {
  for (Channel& ch : channels_) ch.server->reset();
}

void SdoServerChannels::reconfigure() {
  changed_ = false;
  for (unsigned c = 0; c < od::kSdoServerChannels; ++c) {
    Channel& ch = channels_[c];
    const od::SdoChannelIds ids = od::sdo_channel_ids(dictionary_, c);
    if (ids.rx == ch.ids.rx && ids.tx == ch.ids.tx && ids.valid == ch.ids.valid) continue;
    if (ids.valid)
      spdlog::info("SDO server channel 0x{:04X}: receives on 0x{:03X}, answers on 0x{:03X}",
                   od::kSdoServerParameter + c, ids.rx, ids.tx);
    ch.server->reset();  // a transfer cannot go on on other identifiers
    ch.server->set_tx_cob_id(ids.tx);
    ch.ids = ids;
  }
}

void SdoServerChannels::send_all() {
  for (const auto& f : out_) send_(f);
}

}  // namespace stepnode::node
