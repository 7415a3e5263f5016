// Fuzz target: the node's whole receive path. A Device with the profiles of the layout
// the first byte selects (support/layouts.hpp) on the simulated machine, wired as
// node/main.cpp wires it, started and put in NMT operational; then the input is a
// sequence of events, each one byte of kind and its fields:
//   0x0k LEN DATA..   a frame on COB-ID table[k] (the node's own RPDOs/SDO, NMT, SYNC, ...)
//   0x1k ID16 LEN DATA..  a frame on any 11-bit identifier
//   0x2k N            N+1 ms pass, with the 1 ms timer tick
//   0x3k N            N*10 us pass before the next event (frames between ticks)
//   0x4k N            a bus event (error passive, bus-off, ...), N % 7
//   0x5k N            the socket's receive-overrun count grows by N
//   other             as 0x0k
// LEN: bits 0-3 the DLC (capped at 8), bit 4 RTR. The oracle is the sanitizers: no crash,
// no leak, no undefined behaviour, no exception escaping the device.
#include <cstddef>
#include <cstdint>

#include "fuzz/support/byte_stream.hpp"
#include "fuzz/support/layouts.hpp"
#include "fuzz/support/virtual_node.hpp"

using namespace stepnode;

namespace {

constexpr uint8_t kId = 5;
// Every ms of virtual time is a tick of every axis and profile: 3 s keeps an input at tens
// of milliseconds under the sanitizers (a longer run adds little the ticks do not show).
constexpr uint64_t kMaxVirtualUs = 3'000'000;
constexpr int kMaxEvents = 2000;

uint32_t table_id(unsigned k) {
  static constexpr uint32_t kTable[16] = {
      0x000,       0x080,
      0x100,       0x200 + kId,  // NMT, SYNC, TIME, RPDO1
      0x300 + kId, 0x400 + kId,
      0x500 + kId, 0x600 + kId,  // RPDO2..4, SDO request
      0x701,       0x77F,
      0x081,       0x7E5,  // heartbeats (master, other), EMCY, LSS
      0x181,       0x585,
      0x700 + kId, 0x080,  // another's TPDO, our SDO id, our heartbeat id, SYNC
  };
  return kTable[k & 15];
}

od::CanFrame frame_with(uint32_t id, fuzz::ByteStream& in) {
  od::CanFrame f;
  f.id = id & 0x7FF;
  const uint8_t len = in.u8();
  f.dlc = static_cast<uint8_t>(std::min(len & 0x0F, 8));
  f.rtr = len & 0x10;
  for (unsigned i = 0; i < f.dlc; ++i) f.data[i] = in.u8();
  return f;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet_logs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteStream in(data, size);
  node::NodeOptions options;
  options.device.node_id = kId;
  options.layout = fuzz::layout_from(in.u8());
  fuzz::VirtualNode n(options);
  n.start_operational();
  const uint64_t start = n.now_us;
  uint32_t overruns = 0;
  for (int events = 0; !in.done() && events < kMaxEvents && n.now_us - start < kMaxVirtualUs;
       ++events) {
    const uint8_t op = in.u8();
    n.sent.clear();
    switch (op >> 4) {
      case 1: n.frame(frame_with(in.u16(), in)); break;
      case 2: n.advance_us(uint64_t{in.u8() + 1u} * 1000u); break;
      case 3: n.now_us += uint64_t{in.u8()} * 10u; break;
      case 4: n.device().on_bus_event(static_cast<node::BusEvent>(in.u8() % 7), n.now_us); break;
      case 5:
        overruns += in.u8();
        n.device().on_receive_overruns(overruns, n.now_us);
        break;
      default: n.frame(frame_with(table_id(op & 0x0F), in)); break;
    }
  }
  n.advance_us(10'000);  // what the last frames started runs on a little
  return 0;
}
