// SDO wire format shared by the client and the server (CiA 301 7.2.4.3): command
// specifiers, bit fields of byte 0, and builders for the 8-byte frames. Every SDO frame
// has DLC 8 (CiA 301 7.2.4.3.1); reserved bytes are sent as zero.
#pragma once
#include <cstddef>
#include <cstdint>

#include "od/can_frame.hpp"
#include "od/sdo_abort.hpp"

namespace stepnode::od::sdo {

// Command specifier: bits 7..5 of byte 0 (CiA 301 7.2.4.3.3 .. 7.2.4.3.17).
namespace ccs {  // client -> server
constexpr uint8_t kDownloadSegment = 0;
constexpr uint8_t kDownloadInitiate = 1;
constexpr uint8_t kUploadInitiate = 2;
constexpr uint8_t kUploadSegment = 3;
constexpr uint8_t kAbort = 4;
constexpr uint8_t kBlockUpload = 5;
constexpr uint8_t kBlockDownload = 6;
}  // namespace ccs
namespace scs {  // server -> client
constexpr uint8_t kUploadSegment = 0;
constexpr uint8_t kDownloadSegment = 1;
constexpr uint8_t kUploadInitiate = 2;
constexpr uint8_t kDownloadInitiate = 3;
constexpr uint8_t kAbort = 4;
constexpr uint8_t kBlockDownload = 5;
constexpr uint8_t kBlockUpload = 6;
}  // namespace scs

constexpr uint8_t command(uint8_t byte0) { return static_cast<uint8_t>(byte0 >> 5); }
constexpr uint8_t cmd_byte(uint8_t cs) { return static_cast<uint8_t>(cs << 5); }

// Initiate (7.2.4.3.3 / 7.2.4.3.6): n in bits 3..2, e bit 1, s bit 0.
constexpr uint8_t kExpedited = 0x02;
constexpr uint8_t kSizeIndicated = 0x01;
constexpr uint8_t initiate_n(uint8_t byte0) { return (byte0 >> 2) & 0x03; }
// Segments (7.2.4.3.4 / 7.2.4.3.7): t bit 4, n in bits 3..1, c bit 0.
constexpr uint8_t kToggle = 0x10;
constexpr uint8_t kLastSegment = 0x01;
constexpr uint8_t segment_n(uint8_t byte0) { return (byte0 >> 1) & 0x07; }
constexpr size_t kSegmentBytes = 7;

// Block transfer (7.2.4.3.9 .. 7.2.4.3.16). Block download: the client's cs is bit 0
// (0 initiate, 1 end), the server's ss bits 1..0 (0 initiate, 1 end, 2 sub-block ack).
// Block upload: the client's cs bits 1..0 (0 initiate, 1 end, 2 ack, 3 start), the
// server's ss bit 0 (0 initiate, 1 end). Both sides support the CRC (cc / sc, bit 2);
// the block-download initiate carries s in bit 1, the block-upload initiate response too.
constexpr uint8_t kBlockCrc = 0x04;
constexpr uint8_t kBlockSize = 0x02;
constexpr uint8_t kBlockInitiate = 0;
constexpr uint8_t kBlockEnd = 1;
constexpr uint8_t kBlockAck = 2;
constexpr uint8_t kBlockStart = 3;
constexpr uint8_t block_sub(uint8_t byte0) { return byte0 & 0x03; }
constexpr uint8_t block_end_n(uint8_t byte0) { return (byte0 >> 2) & 0x07; }
// Sub-block segments: c bit 7, seqno 1..127 in bits 6..0.
constexpr uint8_t kNoMoreSegments = 0x80;
constexpr uint8_t kMaxBlockSize = 127;
constexpr bool valid_block_size(uint8_t blksize) {
  return blksize >= 1 && blksize <= kMaxBlockSize;
}

// The abort transfer frame (7.2.4.3.17); an SDO frame that starts with 0x80.
constexpr uint8_t kAbortByte = 0x80;

// Largest object a transfer will buffer when neither the entry nor the peer bounds it:
// stops a peer that never sets the c bit from growing memory without limit.
constexpr size_t kMaxTransferBytes = size_t{16} * 1024 * 1024;

// A DLC 8 frame: byte 0, the multiplexer (index, sub) and the 4-byte data field.
inline CanFrame frame(uint32_t cob_id, uint8_t byte0, uint16_t index, uint8_t sub,
                      uint32_t value = 0) {
  CanFrame f;
  f.id = cob_id;
  f.dlc = 8;
  f.data[0] = byte0;
  put_u16(&f.data[1], index);
  f.data[3] = sub;
  put_u32(&f.data[4], value);
  return f;
}

// A DLC 8 frame from byte 0 and up to seven raw bytes (segments), zero padded.
inline CanFrame raw_frame(uint32_t cob_id, uint8_t byte0, const uint8_t* bytes, size_t count) {
  CanFrame f;
  f.id = cob_id;
  f.dlc = 8;
  f.data[0] = byte0;
  for (size_t i = 0; i < count && i < kSegmentBytes; ++i) f.data[1 + i] = bytes[i];
  return f;
}

inline CanFrame abort_frame(uint32_t cob_id, uint16_t index, uint8_t sub, SdoAbort code) {
  return frame(cob_id, kAbortByte, index, sub, static_cast<uint32_t>(code));
}

inline uint16_t frame_index(const CanFrame& f) { return get_u16(&f.data[1]); }
inline uint8_t frame_sub(const CanFrame& f) { return f.data[3]; }

// Elapsed time that tolerates a clock that went backwards (treated as no time passed).
inline uint64_t elapsed(uint64_t now_us, uint64_t since_us) {
  return now_us > since_us ? now_us - since_us : 0;
}

}  // namespace stepnode::od::sdo
