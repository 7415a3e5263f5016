#include "tools/stepctl/lss_command.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace stepnode::tools {
namespace {

constexpr uint32_t kMasterToSlave = 0x7E5, kSlaveToMaster = 0x7E4;
constexpr uint8_t kSwitchGlobal = 0x04, kConfigureNodeId = 0x11, kConfigureBitTiming = 0x13,
                  kActivateBitTiming = 0x15, kStore = 0x17, kSwitchSelective = 0x40,
                  kSwitchSelectiveAnswer = 0x44, kIdentifySlave = 0x4F, kFastScan = 0x51,
                  kInquireVendor = 0x5A, kInquireNodeId = 0x5E;
constexpr uint8_t kFastScanReset =
    0x80;  // BitChecked 0x80: every non-configured slave answers, and restarts
constexpr const char* kPartNames[] = {"vendor-ID", "product code", "revision number",
                                      "serial number"};
using Identity = std::array<uint32_t, 4>;

class LssMaster {
 public:
  LssMaster(MasterBus& bus, int timeout_ms) : bus_(bus), timeout_ms_(timeout_ms) {}

  void send(uint8_t cs, std::array<uint8_t, 7> rest = {}) {
    od::CanFrame f(kMasterToSlave,
                   {cs, rest[0], rest[1], rest[2], rest[3], rest[4], rest[5], rest[6]});
    bus_.send(f);
  }
  void send_u32(uint8_t cs, uint32_t v, uint8_t b5 = 0, uint8_t b6 = 0, uint8_t b7 = 0) {
    send(cs, {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8), static_cast<uint8_t>(v >> 16),
              static_cast<uint8_t>(v >> 24), b5, b6, b7});
  }
  // The first answer with command specifier `cs` within `timeout_ms` (other frames skipped).
  std::optional<od::CanFrame> answer(uint8_t cs, int timeout_ms) {
    const uint64_t deadline = monotonic_us() + static_cast<uint64_t>(timeout_ms) * 1000;
    for (uint64_t now = monotonic_us(); now < deadline; now = monotonic_us()) {
      auto r = bus_.receive(static_cast<int>((deadline - now + 999) / 1000));
      if (!r) break;
      if (r->frame.id == kSlaveToMaster && r->frame.dlc == 8 && r->frame.data[0] == cs)
        return r->frame;
    }
    return std::nullopt;
  }
  od::CanFrame confirmed(uint8_t cs, const char* service) {
    auto a = answer(cs, timeout_ms_);
    if (!a)
      throw std::runtime_error(std::string("no LSS slave answered ") + service + " within " +
                               std::to_string(timeout_ms_) +
                               " ms (is one in configuration state?)");
    return *a;
  }
  // A fast scan request is answered by every slave that matches: the first answer decides,
  // the later ones (up to a settle time of silence) belong to the same request and are
  // swallowed, or the next request would take one for its own.
  bool scan_answer() {
    if (!answer(kIdentifySlave, scan_timeout_ms)) return false;
    const int settle_ms = std::max(20, scan_timeout_ms / 4);
    while (answer(kIdentifySlave, settle_ms)) {
    }
    return true;
  }
  void drain() {
    while (bus_.receive(0)) {
    }
  }
  int scan_timeout_ms = 100;

 private:
  MasterBus& bus_;
  int timeout_ms_;
};

std::string hex8(uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08X", v);
  return b;
}

uint32_t u32_at(const od::CanFrame& f) { return od::get_u32(&f.data[1]); }

uint32_t parse_u32(const std::string& text, const char* what) {
  size_t used = 0;
  unsigned long long v = 0;
  try {
    // Decimal, or hex after 0x: a leading zero is no octal ("010" was sent as 8).
    const bool hex = text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X');
    v = std::stoull(text, &used, hex ? 16 : 10);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || v > 0xFFFFFFFFull || text[0] == '-')
    throw std::invalid_argument(std::string(what) + " " + text +
                                ": must be an integer 0..4294967295 (or 0x...)");
  return static_cast<uint32_t>(v);
}

// Configure node-ID, configure bit timing and store answer with an error code (byte 1).
void check_error(const od::CanFrame& a, const char* service, const char* error1) {
  const uint8_t error = a.data[1];
  if (error == 0) return;
  const std::string why = error == 1                          ? error1
                          : error == 2 && a.data[0] == kStore ? "storage media access error"
                          : error == 0xFF
                              ? "manufacturer-specific error " + std::to_string(a.data[2])
                              : "error " + std::to_string(error);
  throw std::runtime_error(std::string(service) + " refused by the slave: " + why);
}

void configure_node_id(LssMaster& m, uint8_t node_id) {
  m.drain();
  m.send(kConfigureNodeId, {node_id});
  check_error(m.confirmed(kConfigureNodeId, "configure node-ID"), "configure node-ID",
              "node-ID out of range");
}

void store(LssMaster& m) {
  m.drain();
  m.send(kStore);
  check_error(m.confirmed(kStore, "store configuration"), "store configuration", "not supported");
}

void print_identity(const Identity& id) {
  for (unsigned i = 0; i < 4; ++i) std::printf("%s 0x%08X\n", kPartNames[i], id[i]);
}

// One fast scan (CiA 305 8.4.11): finds the non-configured slave whose identity matches bit
// by bit from bit 31 down (a 0 answered keeps the bit 0; silence makes it 1), confirms each
// part with LSSNext, and leaves that slave, alone, in configuration state.
std::optional<Identity> fast_scan(LssMaster& m) {
  m.drain();
  m.send_u32(kFastScan, 0, kFastScanReset, 0, 0);
  if (!m.scan_answer()) return std::nullopt;
  Identity id{};
  for (uint8_t sub = 0; sub < 4; ++sub) {
    for (int bit = 31; bit >= 0; --bit) {
      m.drain();
      m.send_u32(kFastScan, id[sub], static_cast<uint8_t>(bit), sub, sub);
      if (!m.scan_answer()) id[sub] |= 1u << bit;
    }
    const auto next = static_cast<uint8_t>((sub + 1) % 4);
    m.drain();
    m.send_u32(kFastScan, id[sub], 0, sub, next);
    if (!m.scan_answer())
      throw std::runtime_error(std::string("fast scan: the ") + kPartNames[sub] + " found (" +
                               hex8(id[sub]) + ") was not confirmed: a slave left the scan");
  }
  return id;
}

int cmd_fast_scan(LssMaster& m, const LssArgs& args) {
  m.scan_timeout_ms = args.scan_timeout_ms;
  int found = 0;
  for (;;) {
    auto id = fast_scan(m);
    if (!id) break;
    ++found;
    print_identity(*id);
    if (!args.assign) break;  // the slave found stays in configuration state
    const int node_id = *args.assign + found - 1;
    if (node_id > 127) throw std::runtime_error("fast scan: more slaves than node-IDs up to 127");
    configure_node_id(m, static_cast<uint8_t>(node_id));
    if (args.store) store(m);
    // Waiting: the slave takes its node-ID and boots; it no longer takes part in a scan.
    m.send(kSwitchGlobal, {0});
    std::printf("node-ID %d configured%s\n", node_id, args.store ? " and stored" : "");
  }
  std::printf("%d non-configured slave%s found\n", found, found == 1 ? "" : "s");
  return 0;
}

int cmd_inquire(LssMaster& m, const std::string& what) {
  if (what == "node-id") {
    m.drain();
    m.send(kInquireNodeId);
    const uint8_t id = m.confirmed(kInquireNodeId, "inquire node-ID").data[1];
    if (id == 0xFF) std::printf("node-ID none (0xFF)\n");
    else std::printf("node-ID %u\n", id);
    return 0;
  }
  if (what != "identity")
    throw std::invalid_argument("lss inquire " + what + ": identity or node-id");
  Identity id{};
  for (uint8_t i = 0; i < 4; ++i) {
    m.drain();
    m.send(static_cast<uint8_t>(kInquireVendor + i));
    id[i] = u32_at(m.confirmed(static_cast<uint8_t>(kInquireVendor + i), "inquire identity"));
  }
  print_identity(id);
  return 0;
}

int cmd_switch(LssMaster& m, const std::vector<std::string>& w) {
  if (w.size() == 3 && w[1] == "global" && (w[2] == "waiting" || w[2] == "configuration")) {
    m.send(kSwitchGlobal, {static_cast<uint8_t>(w[2] == "configuration")});
    return 0;
  }
  if (w.size() != 6 || w[1] != "selective")
    throw std::invalid_argument(
        "lss switch: global waiting|configuration, or selective VENDOR PRODUCT REVISION SERIAL");
  Identity id{};
  for (unsigned i = 0; i < 4; ++i) id[i] = parse_u32(w[2 + i], kPartNames[i]);
  m.drain();
  for (uint8_t i = 0; i < 4; ++i) m.send_u32(static_cast<uint8_t>(kSwitchSelective + i), id[i]);
  m.confirmed(kSwitchSelectiveAnswer, "switch state selective");
  std::printf("the slave is in configuration state\n");
  return 0;
}

int cmd_configure(LssMaster& m, const std::vector<std::string>& w) {
  if (w.size() == 3 && w[1] == "node-id") {
    const uint32_t id = w[2] == "none" ? 0xFF : parse_u32(w[2], "node-ID");
    if (id != 0xFF && (id < 1 || id > 127))
      throw std::invalid_argument("lss configure node-id " + w[2] + ": 1..127 or none");
    configure_node_id(m, static_cast<uint8_t>(id));
    std::printf("node-ID %s configured (in effect at the slave's next reset communication)\n",
                w[2].c_str());
    return 0;
  }
  if (w.size() == 3 && w[1] == "bit-timing") {
    auto index = lss_bit_timing_index(parse_u32(w[2], "bit rate"));
    if (!index)
      throw std::invalid_argument("lss configure bit-timing " + w[2] +
                                  ": 1000, 800, 500, 250, 125, 50, 20 or 10 (kbit/s)");
    m.drain();
    m.send(kConfigureBitTiming, {0, *index});  // table selector 0: CiA 305's table
    check_error(m.confirmed(kConfigureBitTiming, "configure bit timing"), "configure bit timing",
                "bit rate not supported");
    std::printf("bit timing %s kbit/s configured (table index %u)\n", w[2].c_str(), *index);
    return 0;
  }
  throw std::invalid_argument("lss configure: node-id N|none, or bit-timing KBIT");
}

}  // namespace

std::optional<uint8_t> lss_bit_timing_index(unsigned kbit) {
  // Index 5 is reserved, 9 is automatic bit rate detection.
  constexpr std::array<unsigned, 9> kTable{1000, 800, 500, 250, 125, 0, 50, 20, 10};
  for (size_t i = 0; i < kTable.size(); ++i)
    if (kTable[i] == kbit && kbit != 0) return static_cast<uint8_t>(i);
  return std::nullopt;
}

CLI::App* add_lss_command(CLI::App& app, LssArgs& args) {
  auto* lss = app.add_subcommand(
      "lss",
      "LSS master (CiA 305): switch global waiting|configuration, switch selective "
      "V P R S, configure node-id N|bit-timing KBIT, activate-bit-timing, store, "
      "inquire identity|node-id, fast-scan");
  lss->add_option("words", args.words, "the service and its arguments")->required();
  lss->add_option("--delay", args.delay_ms, "activate-bit-timing: switch delay in ms")
      ->check(CLI::Range(0, 65535));
  lss->add_option("--assign", args.assign,
                  "fast-scan: give the slaves found node-IDs from this one up")
      ->check(CLI::Range(1, 127));
  lss->add_flag("--store", args.store, "fast-scan --assign: store each slave's configuration");
  lss->add_option("--scan-timeout", args.scan_timeout_ms,
                  "fast-scan: ms of silence that mean no match")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000));
  return lss;
}

int run_lss_command(MasterBus& bus, const LssArgs& args, int timeout_ms) {
  LssMaster m(bus, timeout_ms);
  const std::vector<std::string>& w = args.words;
  const std::string& service = w.at(0);
  if (service == "switch") return cmd_switch(m, w);
  if (service == "configure") return cmd_configure(m, w);
  if (service == "inquire" && w.size() == 2) return cmd_inquire(m, w[1]);
  if (service == "store" && w.size() == 1) {
    store(m);
    std::printf("configuration stored\n");
    return 0;
  }
  if (service == "activate-bit-timing" && w.size() == 1) {
    m.send(kActivateBitTiming,
           {static_cast<uint8_t>(args.delay_ms), static_cast<uint8_t>(args.delay_ms >> 8)});
    return 0;
  }
  if (service == "fast-scan" && w.size() == 1) return cmd_fast_scan(m, args);
  throw std::invalid_argument("lss " + service +
                              ": not an LSS service (switch, configure, activate-bit-timing, "
                              "store, inquire, fast-scan)");
}

}  // namespace stepnode::tools
