// Fuzz target: the bridge's bus side (bridge/observer: discovery over SDO, heartbeat
// health, TPDO and EMCY decoding) on the observer tests' virtual bus, with a node that
// answers from a real stepnode dictionary behind od's SDO server (FakeNode; the first byte
// picks a stepnode with the default profiles, a CiA 402 only one, one with PSCALE and the
// HP objects, or a third-party device). Then events, one byte of kind (bits 5-7) and its
// fields:
//   0 the node boots          1 N: its heartbeat state becomes N (the node's NMT state)
//   2 N: N+1 ms pass          3 K V32: the node's axis values change, it sends TPDO K
//   4 CODE16 REG M5: EMCY     5 ID16 LEN DATA..: any frame on the bus (the node answers
//                               its SDO requests: a master may remap it under the observer)
//   6 N: the node's SDO server misbehaves (silent, aborts, holds then releases)
//   7 CLASS32 STATUS: a CAN error frame reaches the observer
// The frames the observer sends reach the node, and its answers the observer, in order.
#include <cstddef>
#include <cstdint>
#include <stdexcept>

#include "bridge/observer/tests/test_bus.hpp"
#include "fuzz/support/byte_stream.hpp"

using namespace stepnode;
using bridge::test::FakeNode;
using bridge::test::FakeNodeOptions;

namespace {

FakeNodeOptions node_options(uint8_t selector) {
  FakeNodeOptions o;
  o.axes = 1 + (selector >> 2) % 3;
  switch (selector & 3) {
    case 0: break;  // a stepnode with the default profiles
    case 1: o.horner = o.hp = o.user = false, o.cia402 = true; break;
    case 2: o.pscale = 0.5, o.hp_objects = true, o.cia402 = true; break;
    default: o.stepnode = false; break;  // another vendor's device
  }
  return o;
}

od::CanFrame any_frame(fuzz::ByteStream& in) {
  od::CanFrame f;
  f.id = in.u16() & 0x7FF;
  const uint8_t len = in.u8();
  f.dlc = static_cast<uint8_t>(std::min(len & 0x0F, 8));
  f.rtr = len & 0x10;
  for (unsigned i = 0; i < f.dlc; ++i) f.data[i] = in.u8();
  return f;
}

void send_tpdo(bridge::test::TestBus& bus, FakeNode& node, uint8_t k, uint32_t value) {
  od::Dictionary& d = node.dictionary();
  if (!d.object(static_cast<uint16_t>(0x1800 + k)) || !d.object(static_cast<uint16_t>(0x1A00 + k)))
    return;
  // The values the TPDO may carry: an axis' status and positions, or a drive's statusword.
  const unsigned axis = k / 4;
  if (d.find(horner::obj::index(axis, horner::obj::kStatusBits), 0))
    node.set_status(axis, static_cast<uint16_t>(value));
  if (d.find(static_cast<uint16_t>(0x6041 + 0x800 * axis), 0))
    d.put<uint16_t>(static_cast<uint16_t>(0x6041 + 0x800 * axis), 0, static_cast<uint16_t>(value));
  try {
    bus.send(node.tpdo(k));
  } catch (const std::out_of_range&) {
    // the fake node's own packing met a mapping it cannot pack: not the observer's concern
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteStream in(data, size);
  bridge::ObserverConfig config;
  config.random_seed = 1;  // the collision jitter: the same input, the same run
  bridge::test::TestBus bus(config);
  FakeNode node(node_options(in.u8()));
  bus.add(node);
  bus.boot(node);
  for (int events = 0; !in.done() && events < 1000 && bus.now_us < 120'000'000; ++events) {
    const uint8_t op = in.u8();
    switch (op >> 5) {
      case 0: bus.boot(node); break;
      case 1: bus.beat_of(node).state = in.u8(); break;
      case 2: bus.run_ms(in.u8() + 1u); break;
      case 3: {
        const uint8_t k = in.u8() % 32;
        send_tpdo(bus, node, k, in.u16() | (static_cast<uint32_t>(in.u16()) << 16));
        break;
      }
      case 4: {
        const uint16_t code = in.u16();
        const uint8_t reg = in.u8();
        bus.send(node.emcy(code, reg, {in.u8(), in.u8(), in.u8(), in.u8(), in.u8()}));
        break;
      }
      case 5: bus.send(any_frame(in)); break;
      case 6: {
        const uint8_t n = in.u8();
        node.silent = n & 1;
        node.abort_next = (n >> 1) & 3;
        if (n & 0x80) bus.release(node, n & 0x40);
        else node.hold = n & 0x40;
        break;
      }
      default: {
        bridge::ObservedFrame of;
        of.error_frame = true;
        of.error_class = in.u16() | (static_cast<uint32_t>(in.u16()) << 16);
        of.controller_status = in.u8();
        std::vector<od::CanFrame> out;
        bus.observer.on_frame(of, bus.now_us, out);
        break;
      }
    }
  }
  bus.run_ms(2000);  // discovery and retries that the last events started run to the end
  return 0;
}
