// stepctl: a CANopen master on the command line for stepnode (and any CiA 301 device):
// NMT, SDO read/write/dump typed by the EDS, and a decoded view of the bus.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "od/sdo_abort.hpp"
#include "od/value_codec.hpp"
#include "tools/stepctl/axis_commands.hpp"
#include "tools/stepctl/drive_command.hpp"
#include "tools/stepctl/hp_command.hpp"
#include "tools/stepctl/hp_words.hpp"
#include "tools/stepctl/lss_command.hpp"
#include "tools/stepctl/master_bus.hpp"
#include "tools/stepctl/object_catalog.hpp"
#include "tools/stepctl/watch.hpp"

using namespace stepnode;
using namespace stepnode::tools;

namespace {

struct Failure : std::runtime_error {  // exit 1: the bus or the node said no
  using std::runtime_error::runtime_error;
};

std::string addr(uint16_t index, uint8_t sub) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04X:%02X", index, sub);
  return buf;
}

od::SdoClient::Mode mode_of(bool block) {
  return block ? od::SdoClient::Mode::Block : od::SdoClient::Mode::Auto;
}

void check(const od::SdoResult& r, uint8_t node, uint16_t index, uint8_t sub) {
  if (r.ok()) return;
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%08X", static_cast<uint32_t>(r.abort));
  throw Failure("node " + std::to_string(node) + " " + addr(index, sub) + ": " +
                (r.aborted_by_server ? "abort " : "failed ") + buf + " " +
                std::string(od::abort_text(r.abort)));
}

// ---- nmt ------------------------------------------------------------------------------
int cmd_nmt(MasterBus& bus, const std::string& what, int node, int timeout_ms) {
  static const std::map<std::string, std::pair<uint8_t, uint8_t>> commands = {
      {"start", {0x01, 0x05}},      {"stop", {0x02, 0x04}},       {"preop", {0x80, 0x7F}},
      {"reset-node", {0x81, 0x00}}, {"reset-comm", {0x82, 0x00}},
  };
  auto [cs, expect] = commands.at(what);
  bus.send(od::CanFrame(od::cob::kNmt, {cs, static_cast<uint8_t>(node)}));
  if (node == 0) {
    std::cout << "NMT " << what << " sent to all nodes\n";
    return 0;
  }
  // Confirmation: the node's heartbeat (or boot-up after a reset) with the new state.
  uint64_t deadline = monotonic_us() + static_cast<uint64_t>(timeout_ms) * 1000;
  while (monotonic_us() < deadline) {
    auto r = bus.receive(static_cast<int>((deadline - monotonic_us()) / 1000) + 1);
    if (r && r->frame.id == od::cob::kHeartbeat + static_cast<uint32_t>(node) &&
        r->frame.dlc == 1 && r->frame.data[0] == expect) {
      std::cout << "node " << node << ": "
                << (expect == 0 ? "boot-up after " + what : what + " confirmed") << "\n";
      return 0;
    }
  }
  throw Failure("node " + std::to_string(node) + ": no confirming heartbeat within " +
                std::to_string(timeout_ms) + " ms (is 0x1017 set?)");
}

// ---- read / write / dump -------------------------------------------------------------------
std::string show(const ObjectCatalog& cat, uint16_t index, uint8_t sub, const od::Bytes& data) {
  auto info = cat.find(index, sub);
  if (!info) return addr(index, sub) + " = " + od::format_value(od::DataType::Domain, data);
  bool hex = info->type == od::DataType::Unsigned32 && (index < 0x2000);
  return addr(index, sub) + " " + info->name + " = " + od::format_value(info->type, data, hex) +
         " (" + std::string(od::type_name(info->type)) + ")";
}

// An upload's value: an expedited answer without the size (another vendor's device, CiA
// 301 7.2.4.3.6) carries four bytes, of which the object's type in the EDS says how many.
od::Bytes value_of(const ObjectCatalog& cat, uint16_t index, uint8_t sub, const od::SdoResult& r) {
  auto info = cat.find(index, sub);
  return r.value_of_size(info ? od::fixed_size(info->type) : 0);
}

int cmd_read(MasterBus& bus, const ObjectCatalog& cat, int node, const std::string& object,
             bool block, const std::string& output) {
  auto [index, sub] = parse_object_address(object);
  od::SdoResult r = bus.upload(static_cast<uint8_t>(node), index, sub, mode_of(block));
  check(r, static_cast<uint8_t>(node), index, sub);
  const od::Bytes data = value_of(cat, index, sub, r);
  if (!output.empty()) {
    std::ofstream out(output, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data.data()),
              static_cast<std::streamsize>(data.size()));
    if (!out) throw Failure("cannot write " + output);
    std::cout << addr(index, sub) << ": " << data.size() << " bytes written to " << output << "\n";
    return 0;
  }
  std::cout << show(cat, index, sub, data) << "\n";
  return 0;
}

int cmd_write(MasterBus& bus, const ObjectCatalog& cat, int node, const std::string& object,
              const std::string& value, const std::string& type_name, bool block) {
  auto [index, sub] = parse_object_address(object);
  od::DataType type;
  if (!type_name.empty()) {
    auto t = od::type_from_name(type_name);
    if (!t)
      throw std::invalid_argument("--type " + type_name +
                                  ": not a CiA 301 type name (e.g. UNSIGNED16)");
    type = *t;
  } else if (auto info = cat.find(index, sub)) {
    type = info->type;
  } else {
    throw std::invalid_argument("object " + addr(index, sub) + " is not in " + cat.source() +
                                "; give --type or --eds");
  }
  od::Bytes data;
  if (!value.empty() && value[0] == '@') {  // @FILE: the file's bytes (DOMAIN, strings)
    std::ifstream in(value.substr(1), std::ios::binary);
    if (!in) throw std::invalid_argument("cannot read " + value.substr(1));
    data.assign(std::istreambuf_iterator<char>(in), {});
  } else {
    data = od::parse_value(type, value);
  }
  od::SdoResult r = bus.download(static_cast<uint8_t>(node), index, sub, data, mode_of(block));
  check(r, static_cast<uint8_t>(node), index, sub);
  std::cout << show(cat, index, sub, data) << " written\n";
  return 0;
}

int cmd_dump(MasterBus& bus, const ObjectCatalog& cat, int node) {
  int failures = 0;
  for (const auto& o : cat.all()) {
    if (o.access == od::Access::WriteOnly) continue;
    od::SdoResult r =
        bus.upload(static_cast<uint8_t>(node), o.index, o.sub, od::SdoClient::Mode::Auto);
    if (r.abort == od::SdoAbort::Timeout)
      throw Failure("node " + std::to_string(node) + ": no SDO answer");
    if (r.ok()) {
      std::cout << show(cat, o.index, o.sub, value_of(cat, o.index, o.sub, r)) << "\n";
    } else if (r.abort != od::SdoAbort::NoObject && r.abort != od::SdoAbort::NoSubindex) {
      ++failures;
      std::cout << addr(o.index, o.sub) << " " << o.name << ": " << od::abort_text(r.abort) << "\n";
    }
  }
  return failures ? 1 : 0;
}

// ---- the command line -------------------------------------------------------------------
// Every option's value, whichever subcommand sets it.
struct Options {
  std::string iface = "vcan0", eds, type_name, output, sdo_cob_ids;
  int timeout_ms = 1000;
  bool block = false, passive = false;
  int seconds = 0;
  std::string nmt_what, object, value;
  int node = -1;
  // Axis commands.
  std::vector<std::string> axis_words;
  int axis = 1;
  double jog_seconds = 1.0;
  bool quiet = false;
  // HP 44714A words.
  std::string hp_words, hp_program;
  int hp_channel = 0, hp_wait_s = 120;
  DriveArgs drive_args;
  LssArgs lss_args;
};

// The subcommands that are not axis verbs (those are looked up by name: kAxisVerbs).
struct Subcommands {
  CLI::App* nmt = nullptr;
  CLI::App* read = nullptr;
  CLI::App* write = nullptr;
  CLI::App* dump = nullptr;
  CLI::App* watch = nullptr;
  CLI::App* hp = nullptr;
  CLI::App* drive = nullptr;
  CLI::App* lss = nullptr;
};

constexpr const char* kAxisVerbs[] = {"clear", "home", "move", "jog", "stop", "estop", "status"};

void add_bus_options(CLI::App& app, Options& o) {
  app.add_option("--iface", o.iface, "SocketCAN interface")->capture_default_str();
  app.add_option("--eds", o.eds,
                 "EDS file describing the node's objects (default: stepnode's own)");
  app.add_option("--timeout", o.timeout_ms, "SDO / confirmation timeout in ms")
      ->capture_default_str()
      ->check(CLI::Range(1, 3'600'000));  // -1 became ~2^64 us: a silent node's read never ended
  app.add_option(
      "--sdo-cob-ids", o.sdo_cob_ids,
      "SDO server channel to use, CLIENT_TO_SERVER,SERVER_TO_CLIENT as configured in the node's "
      "0x1201..0x1203 sub 1 and 2 (e.g. 0x695,0x6D5); default: 0x600+id,0x580+id (0x1200)");
}

// nmt, read, write, dump, watch.
void add_object_commands(CLI::App& app, Options& o, Subcommands& s) {
  s.nmt = app.add_subcommand("nmt", "NMT command: start|stop|preop|reset-node|reset-comm");
  s.nmt->add_option("command", o.nmt_what)
      ->required()
      ->check(CLI::IsMember({"start", "stop", "preop", "reset-node", "reset-comm"}));
  s.nmt->add_option("--node", o.node, "node id 1..127, or 0 for all nodes")
      ->required()
      ->check(CLI::Range(0, 127));

  s.read = app.add_subcommand("read", "read an object over SDO: read NODE INDEX[:SUB]");
  s.read->add_option("node", o.node)->required()->check(CLI::Range(1, 127));
  s.read->add_option("object", o.object, "e.g. 0x1017 or 0x1018:1")->required();
  s.read->add_flag("--block", o.block, "use SDO block transfer");
  s.read->add_option("--output", o.output, "write the raw bytes to a file (DOMAIN, EDS in 0x1021)");

  s.write = app.add_subcommand("write", "write an object over SDO: write NODE INDEX[:SUB] VALUE");
  s.write->add_option("node", o.node)->required()->check(CLI::Range(1, 127));
  s.write->add_option("object", o.object)->required();
  s.write->add_option("value", o.value, "number (decimal or 0x..), text, or @FILE")->required();
  s.write->add_option("--type", o.type_name, "CiA 301 type when the object is not in the EDS");
  s.write->add_flag("--block", o.block, "use SDO block transfer");

  s.dump = app.add_subcommand("dump", "read every object of a node: dump NODE");
  s.dump->add_option("node", o.node)->required()->check(CLI::Range(1, 127));

  s.watch = app.add_subcommand("watch", "decode the bus traffic of every node");
  s.watch->add_flag("--passive", o.passive, "never send (do not read PDO mappings over SDO)");
  s.watch->add_option("--seconds", o.seconds, "stop after this many seconds (0 = until Ctrl-C)")
      ->check(CLI::Range(0, 31'536'000));
}

// Axis commands: stepctl clear|home up|move abs 1000|jog up|stop|estop|status --node N --axis A
void add_axis_commands(CLI::App& app, Options& o) {
  auto add_axis_command = [&](const char* name, const char* help) {
    auto* sub = app.add_subcommand(name, help);
    sub->add_option("args", o.axis_words, "e.g. up|down, abs|rel POSITION");
    sub->add_option("--node", o.node, "node id 1..127")->required()->check(CLI::Range(1, 127));
    sub->add_option("--axis", o.axis, "axis 1..8")->capture_default_str()->check(CLI::Range(1, 8));
    sub->add_flag("--quiet", o.quiet, "no live progress line");
    return sub;
  };
  add_axis_command("clear", "axis: Clear Errors (%Q14)");
  add_axis_command("home", "axis: Find Home up|down (%Q4/%Q5), with live progress");
  add_axis_command("move", "axis: move abs|rel POSITION (%Q9/%Q8), with live progress");
  add_axis_command("jog", "axis: jog up|down for --seconds (level-sensitive %Q6/%Q7)")
      ->add_option("--seconds", o.jog_seconds, "how long the jog bit stays on")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 86400.0));
  add_axis_command("stop", "axis: Decelerate and Stop (%Q15)");
  add_axis_command("estop", "axis: Immediate Stop (%Q16)");
  add_axis_command("status", "axis: status bits in words, motor and encoder position");
}

// HP 44714A words: stepctl hp "PROFILE FREQ 100 800 200 25E-6; MOVE 20" --node 5 --axis 0
CLI::App* add_hp_command(CLI::App& app, Options& o) {
  auto* hp = app.add_subcommand("hp",
                                "HP 44714A commands in the manual's words, ';' between commands; "
                                "queries (POS?, DONE?, QPOS?, ERR?) print the answer");
  hp->add_option("words", o.hp_words,
                 "e.g. \"PROFILE FREQ 100 800 200 25E-6\", \"MOVE 20 NOWAIT\", \"POS?\"");
  hp->add_option("--program", o.hp_program,
                 "an HP BASIC listing of the module's commands (OUTPUT 709;\"...\", PAUSE, END; "
                 "USE, WAIT, RST, "
                 "ON INTR CALL, SUB/SUBEND, BEEP in the strings), run in line-number order");
  hp->add_option("--node", o.node, "node id 1..127")->required()->check(CLI::Range(1, 127));
  hp->add_option("--axis", o.hp_channel, "HP channel: 0 = the node's axis 1")
      ->capture_default_str()
      ->check(CLI::Range(0, 7));
  hp->add_option("--wait", o.hp_wait_s, "MOVE/SUSTAIN without NOWAIT: give up after this many s")
      ->capture_default_str()
      ->check(CLI::Range(1, 86400));
  return hp;
}

// The text of `stepctl hp --program FILE` (unreadable: exit 2).
std::string read_listing(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument("hp --program: cannot read '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  if (text.str().empty()) throw std::invalid_argument("hp --program: '" + path + "' is empty");
  return text.str();
}

// A refusal of the node or of the drive is a runtime failure (exit 1); bad words were
// refused before the bus (exit 2).
template <class F>
int as_failure(F run) {
  try {
    return run();
  } catch (const std::runtime_error& e) {
    throw Failure(e.what());
  }
}

// The subcommand given, on the bus. Throws Failure (exit 1) or another exception (exit 2).
int run_subcommand(CLI::App& app, const Options& o, const Subcommands& s) {
  ObjectCatalog catalog(o.eds);
  if (*s.watch) return run_watch(o.iface, catalog, o.passive, o.seconds);
  std::string listing;
  if (*s.hp) {  // bad words: exit 2 before the bus
    if (o.hp_words.empty() == o.hp_program.empty())
      throw std::invalid_argument("hp: give either the words or --program FILE");
    if (o.hp_program.empty()) plan_hp_words(o.hp_words, static_cast<unsigned>(o.hp_channel));
    else
      check_hp_program(listing = read_listing(o.hp_program), static_cast<unsigned>(o.hp_channel));
  }
  std::optional<SdoCobIds> channel;
  if (!o.sdo_cob_ids.empty())
    channel = parse_sdo_cob_ids(o.sdo_cob_ids);  // bad: exit 2 before the bus
  MasterBus bus(o.iface);
  bus.set_sdo_timeout_ms(o.timeout_ms);
  if (channel) bus.set_sdo_cob_ids(*channel);
  if (*s.nmt) return cmd_nmt(bus, o.nmt_what, o.node, o.timeout_ms);
  if (*s.read) return cmd_read(bus, catalog, o.node, o.object, o.block, o.output);
  if (*s.write) return cmd_write(bus, catalog, o.node, o.object, o.value, o.type_name, o.block);
  if (*s.dump) return cmd_dump(bus, catalog, o.node);
  if (*s.hp && !listing.empty())
    return run_hp_program(bus, o.node, static_cast<unsigned>(o.hp_channel), listing, o.hp_wait_s);
  if (*s.hp)
    return run_hp_command(bus, o.node, static_cast<unsigned>(o.hp_channel), o.hp_words,
                          o.hp_wait_s);
  if (*s.drive) return as_failure([&] { return run_drive_command(bus, catalog, o.drive_args); });
  if (*s.lss) return as_failure([&] { return run_lss_command(bus, o.lss_args, o.timeout_ms); });
  for (const char* verb : kAxisVerbs) {
    if (!*app.get_subcommand(verb)) continue;
    std::vector<std::string> words{verb};
    words.insert(words.end(), o.axis_words.begin(), o.axis_words.end());
    return as_failure(
        [&] { return run_axis_command(bus, o.node, o.axis, words, o.jog_seconds, o.quiet); });
  }
  return 0;
}

int stepctl(int argc, char** argv) {
  CLI::App app{"stepctl: CANopen master for stepnode nodes (NMT, SDO, bus watch)"};
  app.require_subcommand(1);
  Options options;
  Subcommands subcommands;
  add_bus_options(app, options);
  add_object_commands(app, options, subcommands);
  add_axis_commands(app, options);
  subcommands.hp = add_hp_command(app, options);
  // CiA 402: stepctl drive status|enable|disable|quick-stop|fault-reset|pp|pv|home --node N --axis
  // A
  subcommands.drive = add_drive_command(app, options.drive_args);
  // CiA 305: stepctl lss switch|configure|activate-bit-timing|store|inquire|fast-scan
  subcommands.lss = add_lss_command(app, options.lss_args);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "stepctl: %s\n", e.what());
    return 2;
  }
  try {
    return run_subcommand(app, options, subcommands);
  } catch (const Failure& e) {
    std::fprintf(stderr, "stepctl: %s\n", e.what());
    return 1;
  } catch (const SdoChannelBusy& e) {  // a runtime failure, not bad arguments
    std::fprintf(stderr, "stepctl: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stepctl: %s\n", e.what());
    return 2;
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return stepctl(argc, argv);
  } catch (const std::exception& e) {  // the command line itself could not be built
    std::fprintf(stderr, "stepctl: %s\n", e.what());
    return 1;
  }
}
