#include "tools/stepctl/frame_decoder.hpp"

#include <cstdio>

#include "node/profiles/hp44714a/objects.hpp"
#include "od/emcy_text.hpp"
#include "od/sdo_abort.hpp"
#include "od/value_codec.hpp"

namespace stepnode::tools {
namespace {

std::string fmt(const char* f, unsigned a, unsigned b = 0, unsigned c = 0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

// The state in bits 6..0: a node guarding answer has its toggle in bit 7 (CiA 301 7.2.8.3.2).
const char* nmt_state(uint8_t s) {
  switch (s & 0x7F) {
    case 0x00: return "boot-up";
    case 0x04: return "stopped";
    case 0x05: return "operational";
    case 0x7F: return "pre-operational";
    default: return "unknown state";
  }
}

}  // namespace

std::string hex_bytes(const uint8_t* data, size_t n) {
  std::string out;
  for (size_t i = 0; i < n; ++i) out += fmt(i ? " %02x" : "%02x", data[i]);
  return out;
}

void FrameDecoder::forget_node(uint8_t node) {
  std::erase_if(pdos_, [node](const auto& kv) { return kv.second.node == node; });
}

std::string FrameDecoder::object_name(uint16_t index, uint8_t sub) const {
  std::string addr = fmt("0x%04X:%02X", index, sub);
  if (auto info = catalog_.find(index, sub)) return addr + " " + info->name;
  return addr;
}

std::string FrameDecoder::describe(const od::CanFrame& f) {
  const uint8_t* d = f.data.data();
  uint32_t id = f.id;
  if (f.rtr) return fmt("remote request 0x%03X", id);
  if (id == 0x000) {
    if (f.dlc != 2) return "NMT (malformed, DLC " + std::to_string(f.dlc) + ")";
    const char* cmd = d[0] == 0x01   ? "start"
                      : d[0] == 0x02 ? "stop"
                      : d[0] == 0x80 ? "enter pre-operational"
                      : d[0] == 0x81 ? "reset node"
                      : d[0] == 0x82 ? "reset communication"
                                     : "unknown command";
    return std::string("NMT ") + cmd + (d[1] ? fmt(" node %u", d[1]) : " all nodes");
  }
  if (id == 0x080) return f.dlc ? fmt("SYNC counter %u", d[0]) : "SYNC";
  if (id > 0x080 && id < 0x100) {
    uint8_t node = static_cast<uint8_t>(id - 0x80);
    if (f.dlc < 8) return fmt("EMCY node %u (malformed, DLC %u)", node, f.dlc);
    uint16_t code = od::get_u16(d);
    // stepctl speaks to stepnodes: the HP channels' codes in the manual's words.
    const char* hp = hp44714a::emcy_text(code);
    return fmt("EMCY node %u: 0x%04X ", node, code) +
           (hp ? std::string(hp) : od::emcy_code_text(code)) +
           fmt("; error register 0x%02X (", d[2]) + od::error_register_text(d[2]) +
           "); manufacturer " + hex_bytes(d + 3, 5);
  }
  if (id == 0x100) return "TIME " + hex_bytes(d, f.dlc);
  if (id > 0x580 && id < 0x600) return describe_sdo(f, false);
  if (id > 0x600 && id < 0x680) return describe_sdo(f, true);
  if (id > 0x700 && id < 0x780) {
    uint8_t node = static_cast<uint8_t>(id - 0x700);
    if (f.dlc != 1) return fmt("heartbeat node %u (malformed, DLC %u)", node, f.dlc);
    return fmt("heartbeat node %u: ", node) + nmt_state(d[0]);
  }
  if (pdos_.contains(id) || (id >= 0x180 && id < 0x580)) return describe_pdo(f);
  return fmt("0x%03X [%u] ", id, f.dlc) + hex_bytes(d, f.dlc);
}

std::optional<std::string> FrameDecoder::describe_block(const od::CanFrame& f, bool request,
                                                        uint8_t node) {
  const uint8_t* d = f.data.data();
  Block& b = blocks_[node & 0x7F];
  if (d[0] == 0x80) {  // an abort ends any transfer (no segment has seqno 0)
    b = Block::None;
    return std::nullopt;
  }
  const bool segments_from_client = b == Block::Download || b == Block::DownloadLast;
  const bool segments_from_server = b == Block::Upload || b == Block::UploadLast;
  if ((request && segments_from_client) || (!request && segments_from_server)) {
    const bool last = (d[0] & 0x80) != 0;
    if (last) b = request ? Block::DownloadLast : Block::UploadLast;
    return fmt("block segment %u", d[0] & 0x7F) + (last ? ", last: " : ": ") + hex_bytes(d + 1, 7);
  }
  const uint8_t cs = d[0] >> 5;
  if (cs == 5 && (d[0] & 3) == 2) {  // an acknowledgement of a sub-block (either side)
    if (b == Block::DownloadLast) b = Block::DownloadEnd;
    if (b == Block::UploadLast) b = Block::UploadEnd;
    return fmt("block ack: ackseq %u, next blksize %u", d[1], d[2]);
  }
  if (request && cs == 6) b = (d[0] & 1) ? Block::None : Block::Download;  // initiate / end
  if (request && cs == 5 && (d[0] & 3) == 3) b = Block::Upload;            // start upload
  if (request && cs == 5 && (d[0] & 3) == 1) b = Block::None;              // end response
  if (!request && cs == 5 && (d[0] & 3) == 1 && b == Block::DownloadEnd) b = Block::None;
  return std::nullopt;
}

std::string FrameDecoder::describe_sdo(const od::CanFrame& f, bool request) {
  const uint8_t* d = f.data.data();
  uint8_t node = static_cast<uint8_t>(f.id - (request ? 0x600 : 0x580));
  std::string head = fmt(request ? "SDO node %u request: " : "SDO node %u response: ", node);
  if (f.dlc != 8) return head + "malformed (DLC " + std::to_string(f.dlc) + ")";
  if (auto block = describe_block(f, request, node)) return head + *block;
  uint8_t cs = d[0] >> 5;
  uint16_t index = od::get_u16(d + 1);
  uint8_t sub = d[3];
  if (cs == 4) {
    uint32_t code = od::get_u32(d + 4);
    return head + "abort " + object_name(index, sub) + fmt(": 0x%08X ", code) +
           std::string(od::abort_text(code));
  }
  bool expedited = d[0] & 0x02, sized = d[0] & 0x01;
  if (request) {
    switch (cs) {
      case 1:
        if (expedited) {
          size_t n = sized ? 4 - ((d[0] >> 2) & 3) : 4;
          return head + "download " + object_name(index, sub) + " = " + hex_bytes(d + 4, n);
        }
        return head + "download " + object_name(index, sub) +
               (sized ? fmt(", %u bytes (segmented)", od::get_u32(d + 4)) : " (segmented)");
      case 0:
        return head + fmt("download segment toggle %u", (d[0] >> 4) & 1) +
               ((d[0] & 1) ? ", last" : "");
      case 2: return head + "upload " + object_name(index, sub);
      case 3: return head + fmt("upload segment toggle %u", (d[0] >> 4) & 1);
      case 5: return head + "block upload " + (d[0] & 3 ? "" : object_name(index, sub));
      case 6: return head + "block download " + (d[0] & 1 ? "end" : object_name(index, sub));
      default: return head + "block segment/unknown " + hex_bytes(d, 8);
    }
  }
  switch (cs) {
    case 3: return head + "download " + object_name(index, sub) + " done";
    case 1: return head + fmt("download segment toggle %u done", (d[0] >> 4) & 1);
    case 2:
      if (expedited) {
        size_t n = sized ? 4 - ((d[0] >> 2) & 3) : 4;
        return head + "upload " + object_name(index, sub) + " = " + hex_bytes(d + 4, n);
      }
      return head + "upload " + object_name(index, sub) +
             fmt(", %u bytes (segmented)", od::get_u32(d + 4));
    case 0: {
      size_t n = 7 - ((d[0] >> 1) & 7);
      return head + fmt("upload segment toggle %u", (d[0] >> 4) & 1) +
             ((d[0] & 1) ? ", last: " : ": ") + hex_bytes(d + 1, n);
    }
    default: return head + "block transfer " + hex_bytes(d, 8);
  }
}

std::string FrameDecoder::describe_pdo(const od::CanFrame& f) const {
  auto it = pdos_.find(f.id);
  if (it == pdos_.end()) {
    // Pre-defined connection set: 0x180/0x280/0x380/0x480 TPDO1-4, 0x200.. RPDO1-4.
    unsigned fn = f.id >> 7, node = f.id & 0x7F;
    bool tpdo = fn % 2 == 1;
    unsigned number = (fn - (tpdo ? 3 : 4)) / 2 + 1;
    return fmt(tpdo ? "TPDO%u node %u" : "RPDO%u node %u", number, node) +
           " (mapping unknown): " + hex_bytes(f.data.data(), f.dlc);
  }
  const PdoLayout& p = it->second;
  std::string out = fmt(p.transmit ? "TPDO%u node %u:" : "RPDO%u node %u:", p.number, p.node);
  size_t need = od::mapping_bytes(p.mapping);
  if (f.dlc < need)
    return out + fmt(" too short (%u of %u bytes): ", f.dlc, static_cast<unsigned>(need)) +
           hex_bytes(f.data.data(), f.dlc);
  size_t offset = 0;
  std::span<const uint8_t> data(f.data.data(), f.dlc);
  for (const auto& m : p.mapping) {
    uint64_t raw = od::read_bits(data, offset, m.bits);
    offset += m.bits;
    if (m.dummy()) continue;
    auto info = catalog_.find(m.index, m.sub);
    od::DataType type = info ? info->type : od::DataType::Unsigned32;
    od::Bytes bytes = od::encode<uint64_t>(raw);
    bytes.resize((m.bits + 7) / 8);
    out += " " + (info ? info->name : fmt("0x%04X:%02X", m.index, m.sub)) + " = " +
           od::format_value(type, bytes);
    out += ";";
  }
  if (!out.empty() && out.back() == ';') out.pop_back();
  return out;
}

}  // namespace stepnode::tools
