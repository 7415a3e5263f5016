// stepnode: the node process. Parses the command line and runs the nodes it names (one, or
// many with `--node-id 1-32`) through node/node_process.*: one socket, one loop, one timer.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>

#include "canio/socketcan.hpp"
#include "node/config.hpp"
#include "node/device.hpp"
#include "node/node_process.hpp"
#include "od/eds.hpp"

using namespace stepnode;

int main(int argc, char** argv) {
  node::NodeConfig cfg;
  try {
    bool exit_now = false;
    int exit_code = 0;
    cfg = node::parse_command_line(argc, argv, exit_now, exit_code);
    if (exit_now) return exit_code;
    spdlog::set_level(spdlog::level::from_str(cfg.log_level));
    if (cfg.print_eds) {
      // The EDS of the device as configured (a refused mapping: its built-in record; of
      // many nodes, the first). The log would land in the EDS on stdout.
      spdlog::set_level(spdlog::level::off);
      node::Device device(cfg.options, cfg.object_defaults, [](const od::CanFrame&) {});
      std::cout << od::write_eds(device.dictionary(), device.canopen().device_info());
      return 0;
    }
    return node::run_node_process(cfg);
  } catch (const node::UsageError& e) {
    std::fprintf(stderr, "stepnode: %s\n", node::one_line(e.what()).c_str());
    return 2;
  } catch (const canio::InterfaceError& e) {
    // The interface named is missing or not CAN: a bad argument too.
    std::fprintf(stderr, "stepnode: %s\n", node::one_line(e.what()).c_str());
    return 2;
  } catch (const std::exception& e) {
    // A runtime failure (no SocketCAN in the kernel, a socket or epoll call refused): one
    // line, status 1.
    std::fprintf(stderr, "stepnode: %s\n", node::one_line(e.what()).c_str());
    return 1;
  }
}
