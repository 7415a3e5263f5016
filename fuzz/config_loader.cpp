// Fuzz target: the node's configuration, from the TOML text to a started node. The input
// is the config file; it is loaded as `stepnode --config FILE --iface fuzz0 --state-dir
// DIR` loads it (node/config.cpp: toml++, the keys' rules, [defaults]), then the Device
// is built from it (the profiles' objects, the defaults applied over them) and started,
// put in NMT operational, run for 100 ms of virtual time, and its EDS written as
// --print-eds writes it. A bad file must be a UsageError (stepnode prints one line and
// exits 2); any other exception, a crash or undefined behaviour is a bug.
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "fuzz/support/virtual_node.hpp"
#include "node/config.hpp"
#include "od/eds.hpp"

using namespace stepnode;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet_logs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string dir = fuzz::fresh_state_dir().string();
  const std::string file = dir + "/config.toml";
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  std::string args[] = {"stepnode", "--config", file, "--iface", "fuzz0", "--state-dir", dir};
  char* argv[std::size(args)];
  for (size_t i = 0; i < std::size(args); ++i) argv[i] = args[i].data();
  node::NodeConfig cfg;
  try {
    bool exit_now = false;
    int exit_code = 0;
    cfg = node::parse_command_line(static_cast<int>(std::size(args)), argv, exit_now, exit_code);
    if (exit_now) return 0;
    fuzz::VirtualNode n(cfg.options, cfg.object_defaults);
    n.start_operational();
    n.advance_us(100'000);
    (void)od::write_eds(n.device().dictionary(), n.device().canopen().device_info());
  } catch (const node::UsageError&) {
    // refused with one line, as the process does: the expected outcome for a bad file
  }
  return 0;
}
