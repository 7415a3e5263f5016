#include "bridge/observer/sdo_channel.hpp"

#include "od/sdo_protocol.hpp"

namespace stepnode::bridge {

using namespace od::sdo;

SdoChannel::SdoChannel(uint8_t node, uint64_t timeout_us, uint64_t quiet_us, bool echoed,
                       uint32_t request_id, uint32_t response_id)
    : node_(node),
      request_id_(request_id ? request_id : od::cob::kSdoRx + node),
      response_id_(response_id ? response_id : od::cob::kSdoTx + node),
      timeout_us_(timeout_us),
      quiet_us_(quiet_us),
      echoed_(echoed) {
  new_client();
}

void SdoChannel::new_client() {
  client_ = std::make_unique<od::SdoClient>(request_id_, response_id_);
  client_->set_timeout_us(timeout_us_);
}

bool SdoChannel::can_start(uint64_t now_us) const {
  if (in_flight_) return false;
  return !foreign_seen_ || now_us - last_foreign_us_ >= quiet_us_ + extra_quiet_us_;
}

void SdoChannel::start_upload(uint16_t index, uint8_t sub, uint64_t now_us,
                              std::vector<od::CanFrame>& out) {
  const size_t from = out.size();
  // Expedited or segmented, as the server chooses: every object discovery reads is small.
  client_->start_upload(index, sub, od::SdoClient::Mode::Auto, now_us, out);
  extra_quiet_us_ = 0;
  in_flight_ = !client_->done();
  remember_sent(out, from, now_us);
}

SdoChannel::FrameEvent SdoChannel::on_frame(const od::CanFrame& frame, uint64_t now_us,
                                            std::vector<od::CanFrame>& out) {
  if (frame.id == request_id_) return on_request(frame, now_us);
  if (frame.id == response_id_) return on_response(frame, now_us, out);
  // On a channel of our own, the default channel is the masters': only their downloads
  // matter here.
  FrameEvent ev;
  if (frame.id == od::cob::kSdoRx + node_) note_download_request(frame);
  if (frame.id == od::cob::kSdoTx + node_) ev.foreign_download = confirmed_download(frame);
  return ev;
}

SdoChannel::FrameEvent SdoChannel::on_request(const od::CanFrame& f, uint64_t now_us) {
  FrameEvent ev;
  if (is_own_echo(f, now_us)) return ev;
  foreign_seen_ = true;
  last_foreign_us_ = now_us;
  if (in_flight_) {
    // The server will answer the other master now; our transfer cannot go on. No abort
    // frame: it would end the other master's transfer too.
    cancel();
    ev.collision = true;
  }
  note_download_request(f);
  return ev;
}

void SdoChannel::note_download_request(const od::CanFrame& f) {
  if (f.dlc < 4) return;
  const uint8_t b0 = f.data[0];
  const bool initiate_download =
      command(b0) == ccs::kDownloadInitiate ||
      (command(b0) == ccs::kBlockDownload && (b0 & 0x01) == kBlockInitiate);
  if (initiate_download) {
    download_pending_ = true;
    download_index_ = od::get_u16(&f.data[1]);
  } else if (command(b0) == ccs::kAbort) {
    download_pending_ = false;
  }
}

SdoChannel::FrameEvent SdoChannel::on_response(const od::CanFrame& f, uint64_t now_us,
                                               std::vector<od::CanFrame>& out) {
  FrameEvent ev;
  if (in_flight_) {
    const size_t from = out.size();
    client_->on_frame(f, now_us, out);
    remember_sent(out, from, now_us);
    if (client_->done()) {
      in_flight_ = false;
      ev.completed = true;
    }
    return ev;
  }
  // Not for us: another master's answer.
  foreign_seen_ = true;
  last_foreign_us_ = now_us;
  ev.foreign_download = confirmed_download(f);
  return ev;
}

std::optional<uint16_t> SdoChannel::confirmed_download(const od::CanFrame& f) {
  if (!download_pending_ || f.dlc < 4 || od::get_u16(&f.data[1]) != download_index_)
    return std::nullopt;
  // Only the server's answer to that initiate ends the wait: its confirmation, or an
  // abort naming the object. Other answers may come first (the one to a read of ours
  // that the master's request cut short is still answered before it, 7.2.4.1).
  const uint8_t b0 = f.data[0];
  const bool confirms = command(b0) == scs::kDownloadInitiate ||
                        (command(b0) == scs::kBlockDownload && block_sub(b0) == kBlockInitiate);
  if (!confirms && command(b0) != scs::kAbort) return std::nullopt;
  download_pending_ = false;
  if (confirms) return download_index_;
  return std::nullopt;
}

bool SdoChannel::on_tick(uint64_t now_us, std::vector<od::CanFrame>& out) {
  if (!in_flight_) return false;
  const size_t from = out.size();
  client_->on_tick(now_us, out);
  remember_sent(out, from, now_us);
  if (!client_->done()) return false;
  in_flight_ = false;
  return true;
}

void SdoChannel::cancel() {
  if (!in_flight_) return;
  // SdoClient has no silent cancel (starting anew sends an abort); a fresh client is one
  // allocation on a rare path.
  new_client();
  in_flight_ = false;
}

void SdoChannel::remember_sent(const std::vector<od::CanFrame>& out, size_t from, uint64_t now_us) {
  if (!echoed_) return;
  for (size_t i = from; i < out.size(); ++i) {
    if (out[i].id != request_id_) continue;
    sent_[sent_next_] = Sent{out[i], now_us, true};
    sent_next_ = (sent_next_ + 1) % sent_.size();
  }
}

bool SdoChannel::is_own_echo(const od::CanFrame& f, uint64_t now_us) {
  if (!echoed_) return false;
  for (Sent& s : sent_) {
    if (!s.live) continue;
    // An echo comes back within microseconds; an old entry is no longer one.
    if (now_us - s.at_us > timeout_us_) {
      s.live = false;
      continue;
    }
    if (s.frame == f) {
      s.live = false;
      return true;
    }
  }
  return false;
}

}  // namespace stepnode::bridge
