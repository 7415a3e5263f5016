// Random frames against the SDO server (and a client), deterministic seed. The frames are
// biased toward valid command specifiers and existing objects so that they reach deep
// into the state machines; every so often a real transfer runs to show the server still
// works. Meant to run under ASan + UBSan as well (STEPNODE_SANITIZE).
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "sdo_test_support.hpp"

namespace stepnode::od {
namespace {

using namespace sdotest;

// Abort codes the server may send: protocol errors and what the dictionary refuses.
const std::set<uint32_t> kServerAborts = {
    0x05030000, 0x05040000, 0x05040001, 0x05040002, 0x05040003, 0x05040004,
    0x05040005, 0x06010001, 0x06010002, 0x06020000, 0x06070010, 0x06070012,
    0x06070013, 0x06090011, 0x06090030, 0x06090031, 0x06090032};

const uint16_t kIndices[] = {kU8,     kU16,    kU32,    kI32,  kRo,  kWo,
                             kString, kDomain, kRecord, kBool, kU64, kMissing};

class Fuzzer {
 public:
  explicit Fuzzer(uint32_t seed) : rng_(seed) {}

  uint32_t below(uint32_t n) { return static_cast<uint32_t>(rng_() % n); }
  uint8_t byte() { return static_cast<uint8_t>(rng_()); }

  CanFrame frame(uint32_t id) {
    CanFrame f;
    f.id = id;
    f.dlc = below(10) < 8 ? 8 : static_cast<uint8_t>(below(9));
    for (auto& b : f.data) b = byte();
    // Byte 0: mostly a command specifier the receiver knows, with random flag bits.
    if (below(4) != 0) {
      static constexpr uint8_t kCs[] = {0, 1, 2, 3, 5, 6, 5, 6, 4};
      f.data[0] = static_cast<uint8_t>((kCs[below(9)] << 5) | (byte() & 0x1F));
      if (f.data[0] >> 5 == 4 && below(2)) f.data[0] = 0x80;
    }
    // Multiplexer: mostly an object that exists, sub-index 0..3.
    if (below(4) != 0) {
      put_u16(&f.data[1], kIndices[below(std::size(kIndices))]);
      f.data[3] = static_cast<uint8_t>(below(4));
    }
    // Sizes and block sizes: mostly small enough to be accepted.
    if (below(2) == 0) {
      f.data[4] = static_cast<uint8_t>(below(130));
      f.data[5] = static_cast<uint8_t>(below(3) == 0 ? below(30) : 0);
      f.data[6] = f.data[7] = 0;
    }
    return f;
  }

 private:
  std::mt19937 rng_;
};

// Plays a sloppy client: follows the server's answers with a plausible next request
// (right command, mostly right toggle / seqno / ackseq), so that random frames also land
// in the middle of segmented and block transfers.
class SloppyClient {
 public:
  void observe(const std::vector<CanFrame>& out) {
    if (out.empty()) return;
    const uint8_t b = out.front().data[0];
    if (b == 0x80) {
      phase_ = Phase::None;
    } else if (b == 0x60) {
      phase_ = Phase::DownloadSegment;
      toggle_ = false;
    } else if (phase_ == Phase::DownloadSegment && (b & 0xEF) == 0x20) {
      toggle_ = !(b & 0x10);
      if (sent_last_) phase_ = Phase::None;
    } else if (b == 0x40 || b == 0x41) {
      phase_ = Phase::UploadSegment;
      toggle_ = false;
    } else if (phase_ == Phase::UploadSegment && (b & 0xE0) == 0) {
      toggle_ = !(b & 0x10);
      if (b & 0x01) phase_ = Phase::None;
    } else if (b == 0xA4 || b == 0xA0) {
      phase_ = Phase::BlockDownload;
      seqno_ = 1;
    } else if (phase_ == Phase::BlockDownload && b == 0xA2) {
      seqno_ = 1;
      if (sent_last_) phase_ = Phase::BlockDownloadEnd;
    } else if (b == 0xC6 || b == 0xC4) {
      phase_ = Phase::BlockUploadStart;
    } else if (phase_ == Phase::BlockUploadStart || phase_ == Phase::BlockUploadAck) {
      const bool end = out.size() == 1 && (b & 0xE3) == 0xC1 && phase_ == Phase::BlockUploadAck;
      phase_ = end ? Phase::BlockUploadEnd : Phase::BlockUploadAck;
      segments_ = static_cast<uint8_t>(out.size());
    } else {
      phase_ = Phase::None;
    }
  }

  bool active() const { return phase_ != Phase::None; }

  CanFrame next(Fuzzer& fuzz) {
    CanFrame f = fuzz.frame(kRx);
    if (fuzz.below(20) != 0) f.dlc = 8;
    uint8_t& b = f.data[0];
    sent_last_ = false;
    switch (phase_) {
      case Phase::DownloadSegment:
        sent_last_ = fuzz.below(8) == 0;
        b = static_cast<uint8_t>((toggle_ ? 0x10 : 0) |
                                 (fuzz.below(4) == 0 ? fuzz.below(8) << 1 : 0) |
                                 (sent_last_ ? 1 : 0));
        if (fuzz.below(30) == 0) b ^= 0x10;
        break;
      case Phase::UploadSegment: b = static_cast<uint8_t>(0x60 | (toggle_ ? 0x10 : 0)); break;
      case Phase::BlockDownload:
        sent_last_ = fuzz.below(12) == 0;
        b = static_cast<uint8_t>((sent_last_ ? 0x80 : 0) |
                                 (fuzz.below(25) == 0 ? fuzz.below(128) : seqno_++));
        break;
      case Phase::BlockDownloadEnd:
        b = static_cast<uint8_t>(0xC1 | (fuzz.below(8) << 2));
        if (fuzz.below(2)) f.data[1] = f.data[2] = 0;  // CRC of nothing, for cc = 0 peers
        break;
      case Phase::BlockUploadStart: b = 0xA3; break;
      case Phase::BlockUploadAck:
        b = 0xA2;
        f.data[1] =
            static_cast<uint8_t>(fuzz.below(5) == 0 ? fuzz.below(segments_ + 2u) : segments_);
        f.data[2] = static_cast<uint8_t>(fuzz.below(20) == 0 ? fuzz.byte() : 1 + fuzz.below(127));
        break;
      case Phase::BlockUploadEnd: b = 0xA1; break;
      case Phase::None: break;
    }
    return f;
  }

 private:
  enum class Phase {
    None,
    DownloadSegment,
    UploadSegment,
    BlockDownload,
    BlockDownloadEnd,
    BlockUploadStart,
    BlockUploadAck,
    BlockUploadEnd,
  };
  Phase phase_ = Phase::None;
  bool toggle_ = false;
  bool sent_last_ = false;
  uint8_t seqno_ = 1;
  uint8_t segments_ = 0;
};

void expect_well_formed(const std::vector<CanFrame>& out, uint32_t id) {
  for (const auto& f : out) {
    ASSERT_EQ(f.dlc, 8);
    ASSERT_EQ(f.id, id);
    ASSERT_FALSE(f.rtr);
    if (f.data[0] == 0x80 && id == kTx) {
      // An abort (a block-upload segment is never seqno 0 with the c bit).
      ASSERT_TRUE(kServerAborts.count(get_u32(&f.data[4]))) << std::hex << get_u32(&f.data[4]);
    }
  }
}

TEST(SdoFuzz, RandomFramesNeverBreakTheServer) {
  Dictionary dict;
  build_dictionary(dict);
  dict.at(kDomain, 0).max_length = 5000;
  SdoServer server(dict, kTx);
  server.set_block_size(16);
  Fuzzer fuzz(0x5D0F022u);
  uint64_t now = 0;
  std::vector<CanFrame> out;
  SloppyClient sloppy;
  std::set<uint8_t> kinds;  // byte 0 of every answer seen
  size_t answers = 0, transfers = 0;

  for (int i = 0; i < 200'000; ++i) {
    now += fuzz.below(2000);
    if (fuzz.below(200) == 0) now += kTimeout / 2;  // let timers fire now and then
    CanFrame f = sloppy.active() && fuzz.below(10) < 8 ? sloppy.next(fuzz) : fuzz.frame(kRx);
    out.clear();
    server.on_request(f, now, out);
    answers += out.size();
    for (const auto& r : out) kinds.insert(r.data[0]);
    sloppy.observe(out);
    expect_well_formed(out, kTx);
    out.clear();
    server.on_tick(now, out);
    sloppy.observe(out);
    expect_well_formed(out, kTx);
    if (HasFatalFailure()) return;

    // A real transfer every 2000 frames, after the random one in progress timed out.
    if (i % 2000 == 1999) {
      now += kTimeout;
      out.clear();
      server.on_tick(now, out);
      ASSERT_FALSE(server.busy());
      out.clear();
      SdoClient client(kRx, kTx);
      const auto mode = static_cast<SdoClient::Mode>(fuzz.below(3));
      Bytes data = pattern(fuzz.below(300), static_cast<uint8_t>(i));
      std::deque<CanFrame> bus;
      client.start_download(kDomain, 0, data, mode, now, out);
      for (int step = 0; step < 10'000 && !out.empty(); ++step) {
        for (const auto& x : out) bus.push_back(x);
        out.clear();
        while (!bus.empty() && out.empty()) {
          CanFrame x = bus.front();
          bus.pop_front();
          if (x.id == kRx) server.on_request(x, now, out);
          else client.on_frame(x, now, out);
        }
      }
      ASSERT_TRUE(client.done());
      ASSERT_TRUE(client.result().ok()) << abort_text(client.result().abort);
      ASSERT_EQ(dict.value(kDomain, 0), data);
      ASSERT_FALSE(server.busy());
      ++transfers;
    }
  }
  EXPECT_GT(answers, 100'000u);
  // The random requests reached every kind of answer, not just aborts.
  for (uint8_t kind : {0x20, 0x30, 0x60, 0x41, 0x43, 0x4F, 0x00, 0x10, 0xA4, 0xA2, 0xA1, 0xC6})
    EXPECT_TRUE(kinds.count(kind)) << std::hex << int{kind};
  EXPECT_EQ(transfers, 100u);
}

TEST(SdoFuzz, RandomFramesNeverBreakTheClient) {
  Fuzzer fuzz(0xC11E27u);
  SdoClient client(kRx, kTx);
  client.set_block_size(8);
  uint64_t now = 0;
  std::vector<CanFrame> out;
  for (int i = 0; i < 50'000; ++i) {
    now += fuzz.below(5000);
    out.clear();
    if (client.done()) {
      const uint16_t index = kIndices[fuzz.below(std::size(kIndices))];
      const auto mode = static_cast<SdoClient::Mode>(fuzz.below(3));
      if (fuzz.below(2)) client.start_upload(index, 0, mode, now, out);
      else client.start_download(index, 0, pattern(fuzz.below(40)), mode, now, out);
    }
    client.on_frame(fuzz.frame(kTx), now, out);
    client.on_tick(now, out);
    expect_well_formed(out, kRx);
    if (HasFatalFailure()) return;
  }
}

}  // namespace
}  // namespace stepnode::od
