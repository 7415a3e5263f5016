// SDO server (CiA 301 7.2.4). One transfer at a time; its phase says which request the
// server waits for next:
//   Idle             any initiate (download, upload, block download, block upload)
//   DownloadSegment  download segment (7.2.4.3.4)
//   UploadSegment    upload segment request (7.2.4.3.7)
//   BlockDownloadSub sub-block segments (7.2.4.3.10); every frame is a segment here
//   BlockDownloadEnd end block download (7.2.4.3.11)
//   BlockUploadStart start upload (7.2.4.3.13)
//   BlockUploadSub   the client's acknowledgement of a sub-block (7.2.4.3.14)
//   BlockUploadEnd   the client's end block upload response (7.2.4.3.15)
//
// Choices where CiA 301 leaves room:
// - A new initiate while a transfer is in progress drops the old transfer without a
//   frame and starts the new one (the client evidently gave up on the old one; an abort
//   for it would carry the same multiplexer and look like a refusal of the new request).
//   In BlockDownloadSub this cannot happen: there byte 0 is c|seqno by definition.
// - Requests with DLC < 8 are answered with abort 0x05040001: CiA 301 7.2.4.3.1 defines
//   every SDO frame with 8 data bytes. A frame whose byte 0 is 0x80 is an abort whatever
//   its DLC and is never answered, so two devices cannot bounce aborts forever.
// - Data that disagrees with the size the client itself indicated ends the transfer with
//   0x06070010 (length of service parameter does not match); a size indication that does
//   not fit the entry is refused at initiate with 0x06070012 / 0x06070013.
#include "od/sdo_server.hpp"

#include <algorithm>

#include "od/crc16.hpp"
#include "od/sdo_block.hpp"
#include "od/sdo_protocol.hpp"

namespace stepnode::od {

using namespace sdo;

namespace {

enum class Phase : uint8_t {
  Idle,
  DownloadSegment,
  UploadSegment,
  BlockDownloadSub,
  BlockDownloadEnd,
  BlockUploadStart,
  BlockUploadSub,
  BlockUploadEnd,
};

struct Transfer {
  Phase phase = Phase::Idle;
  uint16_t index = 0;
  uint8_t sub = 0;
  uint64_t last_rx_us = 0;
  bool toggle = false;                          // segmented: toggle bit the next request must carry
  bool size_indicated = false;                  // download: the client gave the size ...
  size_t size = 0;                              // ... this one
  size_t limit = 0;                             // download: most bytes accepted
  SdoAbort overflow = SdoAbort::LengthTooHigh;  // ... and the abort past it
  bool crc = false;                             // block download: the client computes the CRC (cc)
  Bytes data;                                   // download: received so far; upload: the value read
  size_t offset = 0;                            // segmented upload: bytes sent
  BlockSender sender;
  BlockReceiver receiver;
};

}  // namespace

struct SdoServer::State {
  explicit State(SdoServer& s) : server(s) {}

  SdoServer& server;
  Transfer t;

  void request(const CanFrame& req, uint64_t now_us, std::vector<CanFrame>& out);
  void tick(uint64_t now_us, std::vector<CanFrame>& out);

  void begin(const CanFrame& req, uint64_t now_us);
  void end() { t = Transfer{}; }
  void fail(SdoAbort code, std::vector<CanFrame>& out);
  void reject(const CanFrame& req, SdoAbort code, std::vector<CanFrame>& out);
  void respond(uint8_t byte0, uint32_t value, std::vector<CanFrame>& out) const;
  SdoAbort accept_size(const Entry& entry, bool indicated, uint32_t size);

  void download_initiate(const CanFrame& req, uint64_t now_us, std::vector<CanFrame>& out);
  void download_segment(const CanFrame& req, std::vector<CanFrame>& out);
  void upload_initiate(const CanFrame& req, uint64_t now_us, std::vector<CanFrame>& out);
  void answer_upload(Bytes data, std::vector<CanFrame>& out);
  void upload_segment(const CanFrame& req, std::vector<CanFrame>& out);
  void block_download_initiate(const CanFrame& req, uint64_t now_us, std::vector<CanFrame>& out);
  void block_download_segment(const CanFrame& req, uint64_t now_us, std::vector<CanFrame>& out);
  void block_download_end(const CanFrame& req, std::vector<CanFrame>& out);
  void block_upload_initiate(const CanFrame& req, uint64_t now_us, std::vector<CanFrame>& out);
  void block_upload_ack(const CanFrame& req, std::vector<CanFrame>& out);
};

SdoServer::SdoServer(Dictionary& dictionary, uint32_t tx_cob_id)
    : dictionary_(dictionary), tx_cob_id_(tx_cob_id), state_(std::make_unique<State>(*this)) {}

SdoServer::~SdoServer() = default;

void SdoServer::on_request(const CanFrame& request, uint64_t now_us, std::vector<CanFrame>& out) {
  state_->request(request, now_us, out);
}

void SdoServer::on_tick(uint64_t now_us, std::vector<CanFrame>& out) { state_->tick(now_us, out); }

void SdoServer::reset() { state_->end(); }

bool SdoServer::busy() const { return state_->t.phase != Phase::Idle; }

std::optional<uint64_t> SdoServer::next_deadline_us() const {
  const Transfer& t = state_->t;
  if (t.phase == Phase::Idle) return std::nullopt;
  // tick() aborts once elapsed >= timeout: the first instant is exactly last + timeout.
  const uint64_t timeout = t.last_rx_us + timeout_us_;
  if (t.phase != Phase::BlockDownloadSub) return timeout;
  const std::optional<uint64_t> stall = t.receiver.stall_deadline_us(timeout_us_ / 2);
  return stall ? std::min(*stall, timeout) : timeout;
}

void SdoServer::State::request(const CanFrame& req, uint64_t now_us, std::vector<CanFrame>& out) {
  if (req.rtr) return;  // SDOs are never remote frames (7.2.4.3.1): nothing to answer
  // 7.2.4.3.17: ccs 4 is an abort whatever its unused bits 4..0 (answering one with an
  // abort: found in review); the transfer ends, an abort is not confirmed. In a block
  // download's sub-block byte 0 is c | seqno, so there only 0x80 (seqno 0) is the abort.
  const bool abort =
      req.dlc >= 1 && (req.data[0] == kAbortByte ||
                       (t.phase != Phase::BlockDownloadSub && command(req.data[0]) == ccs::kAbort));
  if (abort) {
    end();
    return;
  }
  if (req.dlc < 8) return reject(req, SdoAbort::BadCommand, out);
  t.last_rx_us = now_us;
  if (t.phase == Phase::BlockDownloadSub) return block_download_segment(req, now_us, out);

  const uint8_t b0 = req.data[0];
  switch (command(b0)) {
    case ccs::kDownloadInitiate: return download_initiate(req, now_us, out);
    case ccs::kUploadInitiate: return upload_initiate(req, now_us, out);
    case ccs::kDownloadSegment:
      if (t.phase == Phase::DownloadSegment) return download_segment(req, out);
      break;
    case ccs::kUploadSegment:
      if (t.phase == Phase::UploadSegment) return upload_segment(req, out);
      break;
    case ccs::kBlockDownload:
      if ((b0 & 0x01) == kBlockInitiate) return block_download_initiate(req, now_us, out);
      if (t.phase == Phase::BlockDownloadEnd) return block_download_end(req, out);
      break;
    case ccs::kBlockUpload:
      switch (block_sub(b0)) {
        case kBlockInitiate: return block_upload_initiate(req, now_us, out);
        case kBlockStart:
          if (t.phase != Phase::BlockUploadStart) break;
          t.phase = Phase::BlockUploadSub;
          return t.sender.send_sub_block(server.tx_cob_id_, out);
        case kBlockAck:
          if (t.phase == Phase::BlockUploadSub) return block_upload_ack(req, out);
          break;
        case kBlockEnd:
          if (t.phase == Phase::BlockUploadEnd) return end();  // done, nothing to answer
          break;
      }
      break;
    default: break;  // 7 is not a command specifier
  }
  reject(req, SdoAbort::BadCommand, out);
}

void SdoServer::State::tick(uint64_t now_us, std::vector<CanFrame>& out) {
  if (t.phase == Phase::Idle) return;
  if (elapsed(now_us, t.last_rx_us) >= server.timeout_us_) return fail(SdoAbort::Timeout, out);
  // A stalled sub-block is acknowledged well before the transfer would time out, the way
  // CANopenNode does, so that a lost first or last segment gets repeated.
  if (t.phase == Phase::BlockDownloadSub)
    t.receiver.on_tick(now_us, server.timeout_us_ / 2, server.tx_cob_id_, out);
}

void SdoServer::State::begin(const CanFrame& req, uint64_t now_us) {
  t = Transfer{};
  t.index = frame_index(req);
  t.sub = frame_sub(req);
  t.last_rx_us = now_us;
}

void SdoServer::State::fail(SdoAbort code, std::vector<CanFrame>& out) {
  out.push_back(abort_frame(server.tx_cob_id_, t.index, t.sub, code));
  end();
}

// An abort for a request outside a transfer names the multiplexer the request carried
// (as far as its DLC goes); inside a transfer, the transfer's. Only initiate requests
// carry one (CiA 301 7.2.4.3): in a stray segment, sub-block end or ack, bytes 1..3 are
// data, so its abort names 0000:00 rather than an object made of those bytes.
void SdoServer::State::reject(const CanFrame& req, SdoAbort code, std::vector<CanFrame>& out) {
  if (t.phase == Phase::Idle) {
    const uint8_t b0 = req.dlc >= 1 ? req.data[0] : 0;
    const uint8_t cs = command(b0);
    const bool multiplexed =
        req.dlc >= 1 && (cs == ccs::kDownloadInitiate || cs == ccs::kUploadInitiate ||
                         (cs == ccs::kBlockDownload && (b0 & 0x01) == kBlockInitiate) ||
                         (cs == ccs::kBlockUpload && block_sub(b0) == kBlockInitiate));
    t.index = multiplexed ? static_cast<uint16_t>((req.dlc > 1 ? req.data[1] : 0) |
                                                  (req.dlc > 2 ? req.data[2] << 8 : 0))
                          : 0;
    t.sub = multiplexed && req.dlc > 3 ? req.data[3] : 0;
  }
  fail(code, out);
}

void SdoServer::State::respond(uint8_t byte0, uint32_t value, std::vector<CanFrame>& out) const {
  out.push_back(frame(server.tx_cob_id_, byte0, t.index, t.sub, value));
}

// Checks a download's size indication against the entry before any data moves and sets
// the bound the received data must stay within.
SdoAbort SdoServer::State::accept_size(const Entry& entry, bool indicated, uint32_t size) {
  const size_t fixed = fixed_size(entry.type);
  const size_t capacity = fixed ? fixed : entry.max_length ? entry.max_length : kMaxTransferBytes;
  const SdoAbort too_big =
      (fixed || entry.max_length) ? SdoAbort::LengthTooHigh : SdoAbort::OutOfMemory;
  t.size_indicated = indicated;
  t.size = size;
  if (!indicated) {
    t.limit = capacity;
    t.overflow = too_big;
    return SdoAbort::None;
  }
  if (fixed && size < fixed) return SdoAbort::LengthTooLow;
  if (size > capacity) return too_big;
  t.limit = size;
  t.overflow = SdoAbort::LengthMismatch;
  return SdoAbort::None;
}

// 7.2.4.3.3: expedited (data in bytes 4..7) or the start of a segmented download.
void SdoServer::State::download_initiate(const CanFrame& req, uint64_t now_us,
                                         std::vector<CanFrame>& out) {
  begin(req, now_us);
  Dictionary& dict = server.dictionary_;
  if (SdoAbort a = dict.check_write_access(t.index, t.sub); a != SdoAbort::None)
    return fail(a, out);
  const Entry& entry = *dict.find(t.index, t.sub);
  const uint8_t b0 = req.data[0];
  if (b0 & kExpedited) {
    size_t count = 4;
    if (b0 & kSizeIndicated) {
      count = 4 - initiate_n(b0);
    } else if (size_t fixed = fixed_size(entry.type); fixed != 0 && fixed < 4) {
      count = fixed;  // size not indicated: the entry's own size, as CANopenNode does
    }
    SdoAbort a = dict.write(t.index, t.sub, std::span(&req.data[4], count), WriteOrigin::Sdo);
    if (a != SdoAbort::None) return fail(a, out);
    respond(cmd_byte(scs::kDownloadInitiate), 0, out);
    return end();
  }
  if (SdoAbort a = accept_size(entry, b0 & kSizeIndicated, get_u32(&req.data[4]));
      a != SdoAbort::None)
    return fail(a, out);
  t.phase = Phase::DownloadSegment;
  respond(cmd_byte(scs::kDownloadInitiate), 0, out);
}

// 7.2.4.3.4: 7 - n bytes per segment, the toggle alternating from 0; c ends the transfer.
void SdoServer::State::download_segment(const CanFrame& req, std::vector<CanFrame>& out) {
  const uint8_t b0 = req.data[0];
  if (((b0 & kToggle) != 0) != t.toggle) return fail(SdoAbort::ToggleBit, out);
  const size_t count = kSegmentBytes - segment_n(b0);
  if (t.data.size() + count > t.limit) return fail(t.overflow, out);
  t.data.insert(t.data.end(), req.data.begin() + 1, req.data.begin() + 1 + count);
  t.toggle = !t.toggle;
  const uint8_t answer = static_cast<uint8_t>(cmd_byte(scs::kDownloadSegment) | (b0 & kToggle));
  if (!(b0 & kLastSegment)) return out.push_back(raw_frame(server.tx_cob_id_, answer, nullptr, 0));
  if (t.size_indicated && t.data.size() != t.size) return fail(SdoAbort::LengthMismatch, out);
  if (SdoAbort a = server.dictionary_.write(t.index, t.sub, t.data, WriteOrigin::Sdo);
      a != SdoAbort::None)
    return fail(a, out);
  out.push_back(raw_frame(server.tx_cob_id_, answer, nullptr, 0));
  end();
}

// 7.2.4.3.6: the value is read once here; the whole transfer sends that snapshot.
void SdoServer::State::upload_initiate(const CanFrame& req, uint64_t now_us,
                                       std::vector<CanFrame>& out) {
  begin(req, now_us);
  ReadResult r = server.dictionary_.read(t.index, t.sub);
  if (!r.ok()) return fail(r.abort, out);
  answer_upload(std::move(r.data), out);
}

// Expedited when 1..4 bytes, else segmented with the size indicated (also for 0 bytes,
// which expedited cannot express: n counts only 0..3 unused bytes).
void SdoServer::State::answer_upload(Bytes data, std::vector<CanFrame>& out) {
  const uint8_t cmd = cmd_byte(scs::kUploadInitiate);
  if (!data.empty() && data.size() <= 4) {
    const uint8_t n = static_cast<uint8_t>(4 - data.size());
    CanFrame f =
        frame(server.tx_cob_id_, cmd | (n << 2) | kExpedited | kSizeIndicated, t.index, t.sub);
    std::copy(data.begin(), data.end(), f.data.begin() + 4);
    out.push_back(f);
    return end();
  }
  respond(cmd | kSizeIndicated, static_cast<uint32_t>(data.size()), out);
  t.data = std::move(data);
  t.phase = Phase::UploadSegment;
}

// 7.2.4.3.7: up to 7 bytes a segment, the answer echoing the request's toggle bit.
void SdoServer::State::upload_segment(const CanFrame& req, std::vector<CanFrame>& out) {
  const uint8_t b0 = req.data[0];
  if (((b0 & kToggle) != 0) != t.toggle) return fail(SdoAbort::ToggleBit, out);
  const size_t count = std::min(kSegmentBytes, t.data.size() - t.offset);
  const bool last = t.offset + count == t.data.size();
  const uint8_t answer =
      static_cast<uint8_t>(cmd_byte(scs::kUploadSegment) | (b0 & kToggle) |
                           ((kSegmentBytes - count) << 1) | (last ? kLastSegment : 0));
  out.push_back(raw_frame(server.tx_cob_id_, answer, t.data.data() + t.offset, count));
  t.offset += count;
  t.toggle = !t.toggle;
  if (last) end();
}

// 7.2.4.3.9: the answer offers this server's blksize and says that it checks the CRC.
void SdoServer::State::block_download_initiate(const CanFrame& req, uint64_t now_us,
                                               std::vector<CanFrame>& out) {
  begin(req, now_us);
  Dictionary& dict = server.dictionary_;
  if (SdoAbort a = dict.check_write_access(t.index, t.sub); a != SdoAbort::None)
    return fail(a, out);
  const uint8_t b0 = req.data[0];
  if (SdoAbort a = accept_size(*dict.find(t.index, t.sub), b0 & kBlockSize, get_u32(&req.data[4]));
      a != SdoAbort::None)
    return fail(a, out);
  t.crc = (b0 & kBlockCrc) != 0;
  const uint8_t blksize = std::clamp<uint8_t>(server.block_size_, 1, kMaxBlockSize);
  t.receiver.start(blksize, t.limit, t.overflow, now_us);
  t.phase = Phase::BlockDownloadSub;
  respond(cmd_byte(scs::kBlockDownload) | kBlockCrc | kBlockInitiate, blksize, out);
}

void SdoServer::State::block_download_segment(const CanFrame& req, uint64_t now_us,
                                              std::vector<CanFrame>& out) {
  SdoAbort a = t.receiver.on_segment(req, server.tx_cob_id_, now_us, out);
  if (a != SdoAbort::None) return fail(a, out);
  if (t.receiver.finished()) t.phase = Phase::BlockDownloadEnd;
}

// 7.2.4.3.11: n unused bytes in the last segment, then the CRC over all data (when the
// client computes one) before the value goes into the dictionary.
void SdoServer::State::block_download_end(const CanFrame& req, std::vector<CanFrame>& out) {
  if (!t.receiver.trim(block_end_n(req.data[0]))) return fail(SdoAbort::BadCommand, out);
  const Bytes& data = t.receiver.data();
  if (t.size_indicated && data.size() != t.size) return fail(SdoAbort::LengthMismatch, out);
  if (t.crc && crc16_ccitt(data) != get_u16(&req.data[1])) return fail(SdoAbort::CrcError, out);
  if (SdoAbort a = server.dictionary_.write(t.index, t.sub, data, WriteOrigin::Sdo);
      a != SdoAbort::None)
    return fail(a, out);
  out.push_back(
      raw_frame(server.tx_cob_id_, cmd_byte(scs::kBlockDownload) | kBlockEnd, nullptr, 0));
  end();
}

// 7.2.4.3.12: byte 4 is the client's blksize, byte 5 the protocol switch threshold.
// Data no longer than a non-zero pst goes by the normal upload protocol instead, answered
// exactly like an upload initiate (CiA 301 lets the server switch; the client follows).
void SdoServer::State::block_upload_initiate(const CanFrame& req, uint64_t now_us,
                                             std::vector<CanFrame>& out) {
  begin(req, now_us);
  ReadResult r = server.dictionary_.read(t.index, t.sub);
  if (!r.ok()) return fail(r.abort, out);
  const uint8_t blksize = req.data[4];
  const uint8_t pst = req.data[5];
  if (pst != 0 && r.data.size() <= pst) return answer_upload(std::move(r.data), out);
  if (!valid_block_size(blksize)) return fail(SdoAbort::InvalidBlockSize, out);
  const auto size = static_cast<uint32_t>(r.data.size());
  t.sender.start(std::move(r.data), blksize);
  t.phase = Phase::BlockUploadStart;
  respond(cmd_byte(scs::kBlockUpload) | kBlockCrc | kBlockSize | kBlockInitiate, size, out);
}

// 7.2.4.3.14: the client confirms ackseq segments and sets the next blksize; repeat
// from there, or go to the end phase (7.2.4.3.15) once the last segment is confirmed.
void SdoServer::State::block_upload_ack(const CanFrame& req, std::vector<CanFrame>& out) {
  if (SdoAbort a = t.sender.on_ack(req.data[1], req.data[2]); a != SdoAbort::None)
    return fail(a, out);
  if (!t.sender.complete()) return t.sender.send_sub_block(server.tx_cob_id_, out);
  uint8_t crc[2];
  put_u16(crc, t.sender.crc());
  const uint8_t end_cmd = cmd_byte(scs::kBlockUpload) | (t.sender.end_n() << 2) | kBlockEnd;
  out.push_back(raw_frame(server.tx_cob_id_, static_cast<uint8_t>(end_cmd), crc, 2));
  t.phase = Phase::BlockUploadEnd;
}

}  // namespace stepnode::od
