#include "od/sdo_block.hpp"

#include <algorithm>

#include "od/crc16.hpp"
#include "od/sdo_protocol.hpp"

namespace stepnode::od::sdo {

void BlockSender::start(Bytes data, uint8_t blksize) {
  *this = BlockSender{};
  data_ = std::move(data);
  blksize_ = blksize;
}

void BlockSender::send_sub_block(uint32_t cob_id, std::vector<CanFrame>& out) {
  sent_ = 0;
  sent_last_ = false;
  size_t pos = acked_;
  // Empty data still needs one segment: it is the one that carries the c bit.
  while (sent_ < blksize_ && !sent_last_) {
    size_t count = std::min(kSegmentBytes, data_.size() - pos);
    sent_last_ = pos + count >= data_.size();
    ++sent_;
    uint8_t byte0 = static_cast<uint8_t>((sent_last_ ? kNoMoreSegments : 0) | sent_);
    out.push_back(raw_frame(cob_id, byte0, data_.data() + pos, count));
    pos += count;
  }
}

SdoAbort BlockSender::on_ack(uint8_t ackseq, uint8_t blksize) {
  if (ackseq > sent_) return SdoAbort::InvalidSequence;
  if (!valid_block_size(blksize)) return SdoAbort::InvalidBlockSize;
  acked_ = std::min(data_.size(), acked_ + size_t{ackseq} * kSegmentBytes);
  if (sent_last_ && ackseq == sent_) complete_ = true;
  blksize_ = blksize;
  return SdoAbort::None;
}

uint8_t BlockSender::end_n() const {
  if (data_.empty()) return kSegmentBytes;  // the single segment carries nothing
  return static_cast<uint8_t>((kSegmentBytes - data_.size() % kSegmentBytes) % kSegmentBytes);
}

uint16_t BlockSender::crc() const { return crc16_ccitt(data_); }

void BlockReceiver::start(uint8_t blksize, size_t limit, SdoAbort overflow_abort, uint64_t now_us) {
  *this = BlockReceiver{};
  blksize_ = blksize;
  // Whole segments: the last one is padded up to 7 bytes until the end phase trims it.
  size_t segments = std::max<size_t>(1, (limit + kSegmentBytes - 1) / kSegmentBytes);
  limit_ = segments * kSegmentBytes;
  overflow_abort_ = overflow_abort;
  last_rx_us_ = now_us;
}

SdoAbort BlockReceiver::on_segment(const CanFrame& frame, uint32_t ack_cob_id, uint64_t now_us,
                                   std::vector<CanFrame>& out) {
  uint8_t seqno = frame.data[0] & 0x7F;
  bool last = (frame.data[0] & kNoMoreSegments) != 0;
  if (finished_) return SdoAbort::BadCommand;  // the end phase expects no more segments
  if (seqno == 0 || seqno > blksize_) return SdoAbort::InvalidSequence;
  activity_ = true;
  last_rx_us_ = now_us;
  if (seqno == last_good_ + 1) {
    if (seqno == 1) gap_acked_ = false;  // a sub-block begins (again)
    if (data_.size() + kSegmentBytes > limit_) return overflow_abort_;
    data_.insert(data_.end(), frame.data.begin() + 1, frame.data.end());
    last_good_ = seqno;
    if (last) {
      got_last_ = true;
      ack(ack_cob_id, out);
    } else if (seqno == blksize_) {
      ack(ack_cob_id, out);
    }
  } else if ((last_good_ != 0 && seqno > last_good_ + 1) ||
             (last_good_ == 0 && !gap_acked_ && (seqno == blksize_ || last))) {
    // A gap: confirm what arrived, the sender repeats the rest. Or the sub-block's end with
    // its first segment lost: ackseq 0, the sender repeats the whole sub-block (7.2.4.3.10;
    // before, only the stall timer answered, after half the SDO timeout, later than clients
    // wait, python-canopen 0.3 s: found in review).
    gap_acked_ = true;
    ack(ack_cob_id, out);
  }
  // Otherwise a duplicate, or a leftover of a sub-block already acknowledged: ignore.
  return SdoAbort::None;
}

void BlockReceiver::on_tick(uint64_t now_us, uint64_t stall_us, uint32_t ack_cob_id,
                            std::vector<CanFrame>& out) {
  if (!finished_ && activity_ && elapsed(now_us, last_rx_us_) >= stall_us) ack(ack_cob_id, out);
}

void BlockReceiver::ack(uint32_t cob_id, std::vector<CanFrame>& out) {
  // The same byte for both directions: scs 5 / ss 2 (server) and ccs 5 / cs 2 (client).
  const uint8_t body[2] = {last_good_, blksize_};
  out.push_back(raw_frame(cob_id, cmd_byte(scs::kBlockDownload) | kBlockAck, body, 2));
  if (got_last_) finished_ = true;
  last_good_ = 0;
  activity_ = false;
}

bool BlockReceiver::trim(uint8_t n) {
  if (n > kSegmentBytes || n > data_.size()) return false;
  data_.resize(data_.size() - n);
  return true;
}

}  // namespace stepnode::od::sdo
