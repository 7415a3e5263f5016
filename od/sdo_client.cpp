// SDO client (CiA 301 7.2.4). One transfer at a time; its phase says which server
// answer the client waits for next:
//   DownloadInitiate      initiate download response (7.2.4.3.3)
//   DownloadSegment       download segment response (7.2.4.3.4)
//   UploadInitiate        initiate upload response (7.2.4.3.6)
//   UploadSegment         upload segment response (7.2.4.3.7)
//   BlockDownloadInitiate initiate block download response (7.2.4.3.9)
//   BlockDownloadSub      the server's acknowledgement of a sub-block (7.2.4.3.10)
//   BlockDownloadEnd      end block download response (7.2.4.3.11)
//   BlockUploadInitiate   initiate block upload response (7.2.4.3.12), or a normal upload
//                         initiate response when the server switches protocol (pst)
//   BlockUploadSub        sub-block segments (7.2.4.3.14); every frame is a segment here
//   BlockUploadEnd        end block upload (7.2.4.3.15)
//
// Choices: a block upload offers pst = 4, so a value that fits an expedited frame comes
// back in 2 frames instead of 5. Starting a transfer while one is in progress aborts the
// old one with 0x08000000 first, so that a server in the middle of a block download (where
// it cannot recognise an initiate) lets it go. Frames with DLC < 8 are answered with abort
// 0x05040001 (7.2.4.3.1), except frames starting with 0x80, which are aborts and end the
// transfer unanswered.
//
// CiA 301 gives one client to an SDO channel, but a second master on the same channel
// happens (a bridge, a second tool): its answers then arrive on our COB-ID too. So every
// response is checked against the transfer before it is used: the command specifier the
// phase expects, the request's multiplexer in initiate responses (and in aborts), the
// toggle of the segment in flight. A response that fails a check is another transfer's
// (or stale): it is ignored and counted (SdoResult::foreign_replies), never turned into
// an abort, which would end the other client's transfer as well. If no right answer
// comes, the transfer times out, and the count tells the caller why. The block upload
// sub-block is the exception: its segments carry only a sequence number.
#include "od/sdo_client.hpp"

#include <algorithm>

#include "od/crc16.hpp"
#include "od/sdo_block.hpp"
#include "od/sdo_protocol.hpp"

namespace stepnode::od {

using namespace sdo;

namespace {

constexpr uint8_t kProtocolSwitchThreshold = 4;

enum class Phase : uint8_t {
  Idle,
  DownloadInitiate,
  DownloadSegment,
  UploadInitiate,
  UploadSegment,
  BlockDownloadInitiate,
  BlockDownloadSub,
  BlockDownloadEnd,
  BlockUploadInitiate,
  BlockUploadSub,
  BlockUploadEnd,
};

struct Transfer {
  Phase phase = Phase::Idle;
  uint16_t index = 0;
  uint8_t sub = 0;
  uint64_t last_rx_us = 0;
  bool expedited = false;       // download initiate carried the data
  bool toggle = false;          // segmented: toggle bit of the segment in flight
  bool sent_last = false;       // segmented download: the segment in flight has c set
  bool size_indicated = false;  // upload: the server gave the size ...
  size_t size = 0;              // ... this one
  bool crc = false;             // block upload: the server computes the CRC (sc)
  Bytes data;                   // download: to send; upload: received so far
  size_t offset = 0;            // segmented download: bytes sent
  BlockSender sender;
  BlockReceiver receiver;
};

}  // namespace

struct SdoClient::State {
  explicit State(SdoClient& c) : client(c) {}

  SdoClient& client;
  Transfer t;
  SdoResult result;
  unsigned foreign = 0;  // responses of this transfer's time that were not its answers

  void begin(uint16_t index, uint8_t sub, uint64_t now_us, std::vector<CanFrame>& out);
  void finish(Bytes data = {});
  void fail(SdoAbort code, std::vector<CanFrame>& out);
  void send(uint8_t byte0, uint32_t value, std::vector<CanFrame>& out) const;
  bool same_object(const CanFrame& f) const {
    return frame_index(f) == t.index && frame_sub(f) == t.sub;
  }
  bool expected(const CanFrame& f) const;

  void response(const CanFrame& f, uint64_t now_us, std::vector<CanFrame>& out);
  void send_download_segment(std::vector<CanFrame>& out);
  void upload_initiate_response(const CanFrame& f, std::vector<CanFrame>& out);
  void upload_segment(const CanFrame& f, std::vector<CanFrame>& out);
  void request_segment(std::vector<CanFrame>& out) const;
  void block_download_ack(const CanFrame& f, std::vector<CanFrame>& out);
  void block_upload_initiate_response(const CanFrame& f, uint64_t now_us,
                                      std::vector<CanFrame>& out);
  void block_upload_end(const CanFrame& f, std::vector<CanFrame>& out);
};

SdoClient::SdoClient(uint32_t request_cob_id, uint32_t response_cob_id)
    : request_cob_id_(request_cob_id),
      response_cob_id_(response_cob_id),
      state_(std::make_unique<State>(*this)) {}

SdoClient::~SdoClient() = default;

bool SdoClient::done() const { return state_->t.phase == Phase::Idle; }

const SdoResult& SdoClient::result() const { return state_->result; }

void SdoClient::start_upload(uint16_t index, uint8_t sub, Mode mode, uint64_t now_us,
                             std::vector<CanFrame>& out) {
  State& s = *state_;
  s.begin(index, sub, now_us, out);
  if (mode == Mode::Block) {
    // 7.2.4.3.12: byte 4 blksize, byte 5 pst.
    const uint8_t blksize = std::clamp<uint8_t>(block_size_, 1, kMaxBlockSize);
    s.t.phase = Phase::BlockUploadInitiate;
    s.send(cmd_byte(ccs::kBlockUpload) | kBlockCrc | kBlockInitiate,
           blksize | (uint32_t{kProtocolSwitchThreshold} << 8), out);
    return;
  }
  s.t.phase = Phase::UploadInitiate;  // expedited or segmented: the server decides
  s.send(cmd_byte(ccs::kUploadInitiate), 0, out);
}

void SdoClient::start_download(uint16_t index, uint8_t sub, Bytes data, Mode mode, uint64_t now_us,
                               std::vector<CanFrame>& out) {
  State& s = *state_;
  s.begin(index, sub, now_us, out);
  const auto size = static_cast<uint32_t>(data.size());
  s.t.data = std::move(data);
  if (mode == Mode::Block) {
    s.t.phase = Phase::BlockDownloadInitiate;
    s.send(cmd_byte(ccs::kBlockDownload) | kBlockCrc | kBlockSize | kBlockInitiate, size, out);
    return;
  }
  s.t.phase = Phase::DownloadInitiate;
  if (mode == Mode::Auto && size >= 1 && size <= 4) {
    // 7.2.4.3.3 expedited, size indicated: n = number of unused bytes in 4..7.
    s.t.expedited = true;
    const uint8_t n = static_cast<uint8_t>(4 - size);
    s.send(cmd_byte(ccs::kDownloadInitiate) | (n << 2) | kExpedited | kSizeIndicated,
           decode<uint32_t>(s.t.data), out);
    return;
  }
  s.send(cmd_byte(ccs::kDownloadInitiate) | kSizeIndicated, size, out);
}

void SdoClient::on_frame(const CanFrame& frame, uint64_t now_us, std::vector<CanFrame>& out) {
  if (frame.id != response_cob_id_ || frame.rtr || done()) return;
  state_->response(frame, now_us, out);
}

void SdoClient::on_tick(uint64_t now_us, std::vector<CanFrame>& out) {
  State& s = *state_;
  if (done()) return;
  if (elapsed(now_us, s.t.last_rx_us) >= timeout_us_) return s.fail(SdoAbort::Timeout, out);
  // A stalled sub-block is acknowledged before the transfer times out (see the server).
  if (s.t.phase == Phase::BlockUploadSub)
    s.t.receiver.on_tick(now_us, timeout_us_ / 2, request_cob_id_, out);
}

void SdoClient::State::begin(uint16_t index, uint8_t sub, uint64_t now_us,
                             std::vector<CanFrame>& out) {
  if (t.phase != Phase::Idle) fail(SdoAbort::General, out);
  t = Transfer{};
  t.index = index;
  t.sub = sub;
  t.last_rx_us = now_us;
  result = SdoResult{};
  foreign = 0;
}

void SdoClient::State::finish(Bytes data) {
  result = SdoResult{};
  result.foreign_replies = foreign;
  result.data = std::move(data);
  t = Transfer{};
}

void SdoClient::State::fail(SdoAbort code, std::vector<CanFrame>& out) {
  out.push_back(abort_frame(client.request_cob_id_, t.index, t.sub, code));
  result = SdoResult{};
  result.abort = code;
  result.foreign_replies = foreign;
  t = Transfer{};
}

void SdoClient::State::send(uint8_t byte0, uint32_t value, std::vector<CanFrame>& out) const {
  out.push_back(frame(client.request_cob_id_, byte0, t.index, t.sub, value));
}

// CiA 301 7.2.4.3: which server answers the phase waits for.
bool SdoClient::State::expected(const CanFrame& f) const {
  const uint8_t b0 = f.data[0];
  const uint8_t cs = command(b0);
  const bool toggle_echoed = ((b0 & kToggle) != 0) == t.toggle;
  switch (t.phase) {
    case Phase::DownloadInitiate: return cs == scs::kDownloadInitiate && same_object(f);
    case Phase::DownloadSegment: return cs == scs::kDownloadSegment && toggle_echoed;
    case Phase::UploadInitiate: return cs == scs::kUploadInitiate && same_object(f);
    case Phase::UploadSegment: return cs == scs::kUploadSegment && toggle_echoed;
    case Phase::BlockDownloadInitiate:
      return cs == scs::kBlockDownload && block_sub(b0) == kBlockInitiate && same_object(f);
    case Phase::BlockDownloadSub: return cs == scs::kBlockDownload && block_sub(b0) == kBlockAck;
    case Phase::BlockDownloadEnd: return cs == scs::kBlockDownload && block_sub(b0) == kBlockEnd;
    case Phase::BlockUploadInitiate:
      // The server may answer a block upload like a normal upload (protocol switch).
      return (cs == scs::kUploadInitiate ||
              (cs == scs::kBlockUpload && (b0 & 0x01) == kBlockInitiate)) &&
             same_object(f);
    case Phase::BlockUploadEnd: return cs == scs::kBlockUpload && (b0 & 0x01) == kBlockEnd;
    case Phase::Idle:
    case Phase::BlockUploadSub: break;
  }
  return false;
}

void SdoClient::State::response(const CanFrame& f, uint64_t now_us, std::vector<CanFrame>& out) {
  if (f.dlc >= 1 && f.data[0] == kAbortByte) {
    if (f.dlc == 8 && !same_object(f)) {
      ++foreign;  // another transfer's abort
      return;
    }
    const auto code = f.dlc == 8 ? static_cast<SdoAbort>(get_u32(&f.data[4])) : SdoAbort::General;
    t = Transfer{};
    result = SdoResult{};
    result.abort = code == SdoAbort::None ? SdoAbort::General : code;
    result.aborted_by_server = true;
    result.foreign_replies = foreign;
    return;
  }
  if (f.dlc < 8) return fail(SdoAbort::BadCommand, out);
  if (t.phase == Phase::BlockUploadSub) {
    t.last_rx_us = now_us;
    SdoAbort a = t.receiver.on_segment(f, client.request_cob_id_, now_us, out);
    if (a != SdoAbort::None) return fail(a, out);
    if (t.receiver.finished()) t.phase = Phase::BlockUploadEnd;
    return;
  }
  if (!expected(f)) {
    ++foreign;  // not an answer to us: the timeout still counts from our last one
    return;
  }
  t.last_rx_us = now_us;
  switch (t.phase) {
    case Phase::DownloadInitiate:
      if (t.expedited) return finish();
      return send_download_segment(out);
    case Phase::DownloadSegment:
      if (t.sent_last) return finish();
      t.toggle = !t.toggle;
      return send_download_segment(out);
    case Phase::UploadInitiate: return upload_initiate_response(f, out);
    case Phase::UploadSegment: return upload_segment(f, out);
    case Phase::BlockDownloadInitiate: {
      const uint8_t blksize = f.data[4];
      if (!valid_block_size(blksize)) return fail(SdoAbort::InvalidBlockSize, out);
      t.sender.start(std::move(t.data), blksize);
      t.phase = Phase::BlockDownloadSub;
      return t.sender.send_sub_block(client.request_cob_id_, out);
    }
    case Phase::BlockDownloadSub: return block_download_ack(f, out);
    case Phase::BlockDownloadEnd: return finish();
    case Phase::BlockUploadInitiate:
      if (command(f.data[0]) == scs::kUploadInitiate) return upload_initiate_response(f, out);
      return block_upload_initiate_response(f, now_us, out);
    case Phase::BlockUploadEnd: return block_upload_end(f, out);
    case Phase::Idle:
    case Phase::BlockUploadSub: return;
  }
}

// 7.2.4.3.4: up to 7 bytes a segment, n = unused bytes, c on the last (also when the
// data is empty: one segment with n = 7 says so).
void SdoClient::State::send_download_segment(std::vector<CanFrame>& out) {
  t.phase = Phase::DownloadSegment;
  const size_t count = std::min(kSegmentBytes, t.data.size() - t.offset);
  t.sent_last = t.offset + count == t.data.size();
  const auto byte0 =
      static_cast<uint8_t>(cmd_byte(ccs::kDownloadSegment) | (t.toggle ? kToggle : 0) |
                           ((kSegmentBytes - count) << 1) | (t.sent_last ? kLastSegment : 0));
  out.push_back(raw_frame(client.request_cob_id_, byte0, t.data.data() + t.offset, count));
  t.offset += count;
}

// 7.2.4.3.6: expedited (with or without the size) ends here; otherwise segments follow.
void SdoClient::State::upload_initiate_response(const CanFrame& f, std::vector<CanFrame>& out) {
  const uint8_t b0 = f.data[0];
  if (b0 & kExpedited) {
    const bool sized = (b0 & kSizeIndicated) != 0;
    const size_t count = sized ? 4 - initiate_n(b0) : 4;
    finish(Bytes(f.data.begin() + 4, f.data.begin() + 4 + count));
    result.size_unspecified = !sized;
    return;
  }
  t.size_indicated = (b0 & kSizeIndicated) != 0;
  t.size = get_u32(&f.data[4]);
  if (t.size_indicated && t.size > kMaxTransferBytes) return fail(SdoAbort::OutOfMemory, out);
  t.phase = Phase::UploadSegment;
  t.toggle = false;
  request_segment(out);
}

// 7.2.4.3.7: 7 - n bytes (the toggle echoed the request's: see expected()); c ends it.
void SdoClient::State::upload_segment(const CanFrame& f, std::vector<CanFrame>& out) {
  const uint8_t b0 = f.data[0];
  const size_t count = kSegmentBytes - segment_n(b0);
  const size_t limit = t.size_indicated ? t.size : kMaxTransferBytes;
  if (t.data.size() + count > limit)
    return fail(t.size_indicated ? SdoAbort::LengthMismatch : SdoAbort::OutOfMemory, out);
  t.data.insert(t.data.end(), f.data.begin() + 1, f.data.begin() + 1 + count);
  if (b0 & kLastSegment) {
    if (t.size_indicated && t.data.size() != t.size) return fail(SdoAbort::LengthMismatch, out);
    return finish(std::move(t.data));
  }
  t.toggle = !t.toggle;
  request_segment(out);
}

// 7.2.4.3.7: only the command byte; bytes 1..7 are reserved.
void SdoClient::State::request_segment(std::vector<CanFrame>& out) const {
  const auto byte0 = static_cast<uint8_t>(cmd_byte(ccs::kUploadSegment) | (t.toggle ? kToggle : 0));
  out.push_back(raw_frame(client.request_cob_id_, byte0, nullptr, 0));
}

// 7.2.4.3.10: repeat from the server's ackseq, or end (7.2.4.3.11) with n and the CRC.
void SdoClient::State::block_download_ack(const CanFrame& f, std::vector<CanFrame>& out) {
  if (SdoAbort a = t.sender.on_ack(f.data[1], f.data[2]); a != SdoAbort::None) return fail(a, out);
  if (!t.sender.complete()) return t.sender.send_sub_block(client.request_cob_id_, out);
  uint8_t crc[2];
  put_u16(crc, t.sender.crc());
  const auto byte0 =
      static_cast<uint8_t>(cmd_byte(ccs::kBlockDownload) | (t.sender.end_n() << 2) | kBlockEnd);
  out.push_back(raw_frame(client.request_cob_id_, byte0, crc, 2));
  t.phase = Phase::BlockDownloadEnd;
}

// 7.2.4.3.12: sc and s in byte 0, the size in bytes 4..7; the client says "start".
void SdoClient::State::block_upload_initiate_response(const CanFrame& f, uint64_t now_us,
                                                      std::vector<CanFrame>& out) {
  const uint8_t b0 = f.data[0];
  t.crc = (b0 & kBlockCrc) != 0;
  t.size_indicated = (b0 & kBlockSize) != 0;
  t.size = get_u32(&f.data[4]);
  if (t.size_indicated && t.size > kMaxTransferBytes) return fail(SdoAbort::OutOfMemory, out);
  const uint8_t blksize = std::clamp<uint8_t>(client.block_size_, 1, kMaxBlockSize);
  t.receiver.start(blksize, t.size_indicated ? t.size : kMaxTransferBytes,
                   t.size_indicated ? SdoAbort::LengthMismatch : SdoAbort::OutOfMemory, now_us);
  t.phase = Phase::BlockUploadSub;
  out.push_back(
      raw_frame(client.request_cob_id_, cmd_byte(ccs::kBlockUpload) | kBlockStart, nullptr, 0));
}

// 7.2.4.3.15: n unused bytes in the last segment, the server's CRC over all data.
void SdoClient::State::block_upload_end(const CanFrame& f, std::vector<CanFrame>& out) {
  if (!t.receiver.trim(block_end_n(f.data[0]))) return fail(SdoAbort::BadCommand, out);
  Bytes& data = t.receiver.data();
  if (t.size_indicated && data.size() != t.size) return fail(SdoAbort::LengthMismatch, out);
  if (t.crc && crc16_ccitt(data) != get_u16(&f.data[1])) return fail(SdoAbort::CrcError, out);
  out.push_back(
      raw_frame(client.request_cob_id_, cmd_byte(ccs::kBlockUpload) | kBlockEnd, nullptr, 0));
  finish(std::move(data));
}

}  // namespace stepnode::od
