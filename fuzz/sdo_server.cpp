// Fuzz target: od's SDO server (expedited, segmented, block) against the stepnode
// dictionary with every profile, with an oracle: nothing is written without a
// confirmation. After every request the whole dictionary is compared with its state
// before; any changed value must come with the response that confirms a download's end:
//   0x60 to an expedited initiate, 0x20/0x30 to the last download segment (c = 1), or
//   0xA1 to the end of a block download.
// An abort, a segment that is not the last, a timeout or an upload must leave every value
// as it was. The input: a byte that sets the server's block size, then events:
//   op bits 0-3: DLC (capped at 8), bits 4-5: 0/1 a request of DLC bytes that follow,
//   2 time passes (next byte x 10 ms) and the server's tick runs, 3 the server is reset
//   (NMT reset communication).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "fuzz/support/byte_stream.hpp"
#include "node/device_objects.hpp"
#include "od/sdo_server.hpp"

using namespace stepnode;

namespace {

constexpr uint8_t kId = 5;

// Built once (building it costs far more than a request); its values go back to the
// defaults before every input, so an input sees the same dictionary when replayed alone.
od::Dictionary& dictionary() {
  static od::Dictionary* d = [] {
    auto* od = new od::Dictionary;
    od::DeviceInfo info;
    info.node_id = kId;
    node::build_device_objects(*od, info, node::DeviceLayout{.axes = 1, .cia402 = true});
    return od;
  }();
  return *d;
}

std::vector<od::Bytes> snapshot(od::Dictionary& d) {
  std::vector<od::Bytes> v;
  for (const auto& [index, object] : d.objects())
    for (const auto& [sub, e] : object.entries) v.push_back(e.value);
  return v;
}

bool confirms_download_end(const od::CanFrame& request, const std::vector<od::CanFrame>& out) {
  if (out.empty() || out.front().dlc != 8) return false;
  const uint8_t q = request.data[0], r = out.front().data[0];
  if (r == 0x60 && (q >> 5) == 1 && (q & 0x02)) return true;           // expedited download
  if ((r & 0xEF) == 0x20 && (q >> 5) == 0 && (q & 0x01)) return true;  // last segment
  return r == 0xA1;                                                    // block download end
}

// Reading 0x1010/0x1011 refreshes their value (on_read): a change an upload may make.
bool is_upload_response(const std::vector<od::CanFrame>& out) {
  if (out.empty()) return false;
  const uint8_t scs = out.front().data[0] >> 5;
  return scs == 2 || scs == 0 || scs == 6;
}

[[noreturn]] void fail(const char* what, const od::CanFrame& request,
                       const std::vector<od::CanFrame>& out) {
  std::fprintf(stderr, "sdo_server oracle: %s\nrequest dlc %u:", what, request.dlc);
  for (unsigned i = 0; i < request.dlc; ++i) std::fprintf(stderr, " %02X", request.data[i]);
  for (const od::CanFrame& f : out) {
    std::fprintf(stderr, "\nresponse %03X:", f.id);
    for (unsigned i = 0; i < f.dlc; ++i) std::fprintf(stderr, " %02X", f.data[i]);
  }
  std::fprintf(stderr, "\n");
  std::abort();
}

void check_changes(od::Dictionary& d, const std::vector<od::Bytes>& before,
                   const od::CanFrame* request, const std::vector<od::CanFrame>& out) {
  size_t i = 0;
  for (const auto& [index, object] : d.objects())
    for (const auto& [sub, e] : object.entries) {
      if (e.value != before[i++]) {
        if (request && e.on_read && is_upload_response(out)) continue;
        std::fprintf(stderr, "changed: %04X:%02X\n", index, sub);
        if (!request) fail("a value changed on the server's tick (timeout)", od::CanFrame{}, out);
        if (!confirms_download_end(*request, out))
          fail("a value changed without a download confirmation", *request, out);
      }
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteStream in(data, size);
  od::Dictionary& d = dictionary();
  d.reset_to_defaults(0x0000, 0xFFFF);
  od::SdoServer server(d, od::cob::kSdoTx + kId);
  server.set_block_size(static_cast<uint8_t>(1 + in.u8() % 127));
  uint64_t now_us = 1'000'000;
  std::vector<od::CanFrame> out;
  for (int events = 0; !in.done() && events < 4000; ++events) {
    const uint8_t op = in.u8();
    out.clear();
    const std::vector<od::Bytes> before = snapshot(d);
    switch ((op >> 4) & 3) {
      case 2:
        now_us += uint64_t{in.u8()} * 10'000u;
        server.on_tick(now_us, out);
        check_changes(d, before, nullptr, out);
        break;
      case 3: server.reset(); break;
      default: {
        od::CanFrame request;
        request.id = od::cob::kSdoRx + kId;
        request.dlc = static_cast<uint8_t>(std::min(op & 0x0F, 8));
        for (unsigned i = 0; i < request.dlc; ++i) request.data[i] = in.u8();
        server.on_request(request, now_us, out);
        check_changes(d, before, &request, out);
      }
    }
  }
  return 0;
}
