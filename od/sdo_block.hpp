// The two halves of an SDO block transfer (CiA 301 7.2.4.3.9 .. 7.2.4.3.16), shared by
// both sides: the client sends in block download and the server in block upload; the
// other side receives. Internal to od/ (used by sdo_server.cpp and sdo_client.cpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "od/can_frame.hpp"
#include "od/sdo_abort.hpp"
#include "od/value_codec.hpp"

namespace stepnode::od::sdo {

// Cuts the data into 7-byte segments and sends them in sub-blocks of blksize segments,
// numbered 1..blksize, the c bit on the segment that carries the last byte. An
// acknowledgement confirms `ackseq` segments; the next sub-block resumes after them,
// which is how segments the receiver missed are repeated (7.2.4.3.11 / 7.2.4.3.14).
class BlockSender {
 public:
  void start(Bytes data, uint8_t blksize);
  // Appends the next sub-block (at least one segment, even for empty data).
  void send_sub_block(uint32_t cob_id, std::vector<CanFrame>& out);
  // Applies the peer's ack: InvalidSequence when it confirms segments never sent,
  // InvalidBlockSize when the new blksize is not 1..127.
  SdoAbort on_ack(uint8_t ackseq, uint8_t blksize);
  // All data confirmed: time for the end phase.
  bool complete() const { return complete_; }
  // End phase: bytes of the last segment that carry no data, and the CRC of all data.
  uint8_t end_n() const;
  uint16_t crc() const;
  const Bytes& data() const { return data_; }

 private:
  Bytes data_;
  size_t acked_ = 0;  // bytes the receiver confirmed
  uint8_t blksize_ = 1;
  uint8_t sent_ = 0;        // segments in the sub-block in flight
  bool sent_last_ = false;  // ... and whether it carried the last one
  bool complete_ = false;
};

// Collects sub-block segments. In order segments are stored; the sub-block ends with
// seqno == blksize or the c bit, and the receiver answers with ackseq = last seqno in
// order (7.2.4.3.11 / 7.2.4.3.14). On a gap it answers at once with the last good seqno
// so that the sender repeats from there. Until the first good segment of a sub-block,
// out-of-order segments are ignored: after a gap ack they are the rest of the broken
// sub-block still on the bus. Duplicates are ignored too. A seqno of 0 or above blksize
// is a protocol error (0x05040003).
class BlockReceiver {
 public:
  // limit: the most data bytes the transfer may carry (padding of the last segment
  // aside); overflow_abort is returned when the sender goes past it.
  void start(uint8_t blksize, size_t limit, SdoAbort overflow_abort, uint64_t now_us);
  // Handles a segment frame (DLC 8, byte 0 = c | seqno); may append the ack.
  SdoAbort on_segment(const CanFrame& frame, uint32_t ack_cob_id, uint64_t now_us,
                      std::vector<CanFrame>& out);
  // Sub-block timer: segments came since the last ack but the sub-block stalled (its
  // first or last segment lost) for `stall_us`; ack what arrived so the sender repeats.
  void on_tick(uint64_t now_us, uint64_t stall_us, uint32_t ack_cob_id, std::vector<CanFrame>& out);
  // When on_tick would acknowledge a stalled sub-block (the last segment + `stall_us`);
  // nothing while no segment came since the last ack.
  std::optional<uint64_t> stall_deadline_us(uint64_t stall_us) const {
    if (finished_ || !activity_) return std::nullopt;
    return last_rx_us_ + stall_us;
  }
  // The segment with the c bit arrived and was acknowledged: the end phase follows.
  bool finished() const { return finished_; }
  // End phase: drops the n padding bytes of the last segment. False if n is impossible.
  bool trim(uint8_t n);
  Bytes& data() { return data_; }

 private:
  void ack(uint32_t cob_id, std::vector<CanFrame>& out);

  Bytes data_;
  size_t limit_ = 0;
  SdoAbort overflow_abort_ = SdoAbort::LengthTooHigh;
  uint8_t blksize_ = 1;
  uint8_t last_good_ = 0;  // seqno of the last in-order segment of this sub-block
  bool got_last_ = false;
  bool finished_ = false;
  bool activity_ = false;  // segments arrived since the last ack
  // This sub-block was acknowledged before its end (a gap): its leftovers ask nothing.
  bool gap_acked_ = false;
  uint64_t last_rx_us_ = 0;
};

}  // namespace stepnode::od::sdo
