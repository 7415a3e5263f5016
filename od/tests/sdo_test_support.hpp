// Shared fixtures for the SDO tests: a small dictionary with every kind of entry the
// protocol cares about, frame helpers, and a simulated bus between a client and a server.
#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <initializer_list>
#include <vector>

#include "od/can_frame.hpp"
#include "od/dictionary.hpp"
#include "od/sdo_client.hpp"
#include "od/sdo_server.hpp"

namespace stepnode::od::sdotest {

constexpr uint8_t kNode = 0x05;
constexpr uint32_t kRx = cob::kSdoRx + kNode;  // client -> server
constexpr uint32_t kTx = cob::kSdoTx + kNode;  // server -> client
constexpr uint64_t kTimeout = 1'000'000;

// Objects of the test dictionary.
constexpr uint16_t kU8 = 0x2000;      // rw, 1..100
constexpr uint16_t kU16 = 0x2001;     // rw, 0x0100..0xF000
constexpr uint16_t kU32 = 0x2002;     // rw, 0x10..0xF0000000
constexpr uint16_t kI32 = 0x2003;     // rw, -1000..1000
constexpr uint16_t kRo = 0x2004;      // U32 ro
constexpr uint16_t kWo = 0x2005;      // U32 wo
constexpr uint16_t kString = 0x2006;  // VISIBLE_STRING, at most 30 chars
constexpr uint16_t kDomain = 0x2007;  // DOMAIN, at most 5000 bytes
constexpr uint16_t kRecord = 0x2008;  // RECORD: sub 1 U8, sub 2 U16
constexpr uint16_t kBool = 0x2009;    // BOOLEAN rw
constexpr uint16_t kU64 = 0x200A;     // U64 rw
constexpr uint16_t kMissing = 0x2FFF;

inline Bytes pattern(size_t n, uint8_t seed = 0) {
  Bytes b(n);
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>(i * 7 + seed + (i >> 8));
  return b;
}

inline void build_dictionary(Dictionary& d) {
  Entry& u8 = d.var(kU8, "U8", DataType::Unsigned8, Access::ReadWrite, encode<uint8_t>(5));
  u8.low = encode<uint8_t>(1);
  u8.high = encode<uint8_t>(100);
  Entry& u16 =
      d.var(kU16, "U16", DataType::Unsigned16, Access::ReadWrite, encode<uint16_t>(0x1234));
  u16.low = encode<uint16_t>(0x0100);
  u16.high = encode<uint16_t>(0xF000);
  Entry& u32 =
      d.var(kU32, "U32", DataType::Unsigned32, Access::ReadWrite, encode<uint32_t>(0x12345678));
  u32.low = encode<uint32_t>(0x10);
  u32.high = encode<uint32_t>(0xF0000000);
  Entry& i32 = d.var(kI32, "I32", DataType::Integer32, Access::ReadWrite, encode<int32_t>(-5));
  i32.low = encode<int32_t>(-1000);
  i32.high = encode<int32_t>(1000);
  d.var(kRo, "RO", DataType::Unsigned32, Access::ReadOnly, encode<uint32_t>(0xCAFEBABE));
  d.var(kWo, "WO", DataType::Unsigned32, Access::WriteOnly, encode<uint32_t>(0));
  d.var(kString, "String", DataType::VisibleString, Access::ReadWrite, encode_string("stepnode"))
      .max_length = 30;
  d.var(kDomain, "Domain", DataType::Domain, Access::ReadWrite, pattern(100)).max_length = 5000;
  Object& rec = d.record(kRecord, "Record");
  rec.add(1, "A", DataType::Unsigned8, Access::ReadWrite, {1});
  rec.add(2, "B", DataType::Unsigned16, Access::ReadWrite, {2, 0});
  d.var(kBool, "Bool", DataType::Boolean, Access::ReadWrite, {0});
  d.var(kU64, "U64", DataType::Unsigned64, Access::ReadWrite, encode<uint64_t>(0));
}

inline CanFrame req(std::initializer_list<uint8_t> bytes) { return CanFrame(kRx, bytes); }
inline CanFrame rsp(std::initializer_list<uint8_t> bytes) { return CanFrame(kTx, bytes); }

// The abort frame `cob` would carry for index:sub and code.
inline CanFrame abort_of(uint32_t cob, uint16_t index, uint8_t sub, uint32_t code) {
  return CanFrame(cob, {0x80, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), sub,
                        static_cast<uint8_t>(code), static_cast<uint8_t>(code >> 8),
                        static_cast<uint8_t>(code >> 16), static_cast<uint8_t>(code >> 24)});
}

// A client and a server on one simulated bus. Frames travel in order through one queue;
// the filters may drop, reorder or alter each batch a side sends. When nothing is in
// flight, time moves on and both sides tick (timeouts, stalled sub-blocks).
struct Link {
  Dictionary dict;
  SdoServer server{dict, kTx};
  SdoClient client{kRx, kTx};
  uint64_t now = 0;
  std::deque<CanFrame> bus;
  std::vector<CanFrame> log;  // every frame delivered, in order
  std::function<void(std::vector<CanFrame>&)> client_filter, server_filter;
  int batches_from_client = 0, batches_from_server = 0;

  Link() { build_dictionary(dict); }

  void send(std::vector<CanFrame>& out, bool from_client) {
    if (from_client && client_filter) client_filter(out);
    if (!from_client && server_filter) server_filter(out);
    (from_client ? batches_from_client : batches_from_server)++;
    for (const auto& f : out) bus.push_back(f);
    out.clear();
  }

  // Runs until the client is done (or nothing can happen any more).
  const SdoResult& run(size_t max_steps = 200'000) {
    std::vector<CanFrame> out;
    for (size_t step = 0; step < max_steps && !client.done(); ++step) {
      if (bus.empty()) {
        now += kTimeout / 4;
        server.on_tick(now, out);
        send(out, false);
        client.on_tick(now, out);
        send(out, true);
        continue;
      }
      CanFrame f = bus.front();
      bus.pop_front();
      log.push_back(f);
      now += 100;
      if (f.id == kRx) {
        server.on_request(f, now, out);
        send(out, false);
      } else {
        client.on_frame(f, now, out);
        send(out, true);
      }
    }
    // Let the last frames (end confirmations) reach the server.
    while (!bus.empty()) {
      CanFrame f = bus.front();
      bus.pop_front();
      log.push_back(f);
      if (f.id == kRx) server.on_request(f, now, out);
      out.clear();
    }
    return client.result();
  }

  const SdoResult& upload(uint16_t index, uint8_t sub, SdoClient::Mode mode) {
    std::vector<CanFrame> out;
    client.start_upload(index, sub, mode, now, out);
    send(out, true);
    return run();
  }

  const SdoResult& download(uint16_t index, uint8_t sub, Bytes data, SdoClient::Mode mode) {
    std::vector<CanFrame> out;
    client.start_download(index, sub, std::move(data), mode, now, out);
    send(out, true);
    return run();
  }

  // The first frame on `id` in the log (the initiate or its answer).
  CanFrame first(uint32_t id) const {
    for (const auto& f : log)
      if (f.id == id) return f;
    return CanFrame{};
  }

  size_t count(uint32_t id, uint8_t byte0, uint8_t mask = 0xFF) const {
    size_t n = 0;
    for (const auto& f : log)
      if (f.id == id && f.dlc > 0 && (f.data[0] & mask) == byte0) ++n;
    return n;
  }
};

}  // namespace stepnode::od::sdotest
