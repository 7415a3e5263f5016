// The command line of `stepctl drive` (its subcommands and options); what they do is
// drive_command.cpp.
#include <cstdint>

#include "tools/stepctl/drive_command.hpp"

namespace stepnode::tools {

CLI::App* add_drive_command(CLI::App& app, DriveArgs& args) {
  auto* drive =
      app.add_subcommand("drive",
                         "CiA 402 drive (profiles = [\"cia402\"]): status, enable, disable, "
                         "quick-stop, fault-reset, pp, pv, home");
  drive->require_subcommand(1);
  const auto u32 = CLI::Range(int64_t{0}, int64_t{0xFFFF'FFFF});
  auto add = [&](const char* name, const char* help) {
    auto* sub = drive->add_subcommand(name, help);
    sub->add_option("--node", args.node, "node id 1..127")->required()->check(CLI::Range(1, 127));
    sub->add_option("--axis", args.axis, "axis 1..8 (objects at index + 0x800 * (axis - 1))")
        ->capture_default_str()
        ->check(CLI::Range(1, 8));
    sub->add_flag("--quiet", args.quiet, "no progress lines");
    sub->callback([&args, name] { args.verb = name; });
    return sub;
  };
  auto add_wait = [&](CLI::App* sub) {
    sub->add_option("--wait", args.wait_s, "give up waiting for the motion after this many s")
        ->capture_default_str()
        ->check(CLI::Range(1, 86400));
  };
  add("status", "state (6041h) in words, mode (6061h), statusword bits, 603Fh, 6064h, 606Ch");
  add_wait(add("enable", "device control to Operation enabled (fault reset first)"));
  add_wait(add("disable", "Disable operation, then Shutdown: to Ready to switch on"));
  add("quick-stop", "Quick stop (6040h = 0x0B): to Quick stop active or Switch on disabled");
  add_wait(
      add("fault-reset", "Fault reset (rising edge of 6040h bit 7): Fault to Switch on disabled"));

  auto* pp =
      add("pp",
          "profile position: 6060h = 1, 607Ah = TARGET, set-point handshake, live progress to "
          "target reached");
  pp->add_option("target", args.target, "target position (position units)")
      ->required()
      ->check(CLI::Range(int64_t{INT32_MIN}, int64_t{INT32_MAX}));
  pp->add_flag("--relative", args.relative, "relative to the preceding target (controlword bit 6)");
  pp->add_flag("--immediate", args.immediate, "change set immediately (controlword bit 5)");
  pp->add_option("--velocity", args.velocity, "6081h profile velocity")->check(u32);
  pp->add_option("--acceleration", args.acceleration, "6083h profile acceleration")->check(u32);
  pp->add_option("--deceleration", args.deceleration, "6084h profile deceleration")->check(u32);
  pp->add_flag("--no-wait", args.no_wait, "return once the set-point is acknowledged");
  add_wait(pp);

  auto* pv = add(
      "pv",
      "profile velocity: 6060h = 3, 60FFh = VELOCITY, until velocity reached (speed zero for 0)");
  pv->add_option("velocity", args.target, "target velocity (velocity units), signed")
      ->required()
      ->check(CLI::Range(int64_t{INT32_MIN}, int64_t{INT32_MAX}));
  pv->add_option("--acceleration", args.acceleration, "6083h profile acceleration")->check(u32);
  pv->add_option("--deceleration", args.deceleration, "6084h profile deceleration")->check(u32);
  pv->add_flag("--no-wait", args.no_wait, "return once the target velocity is written");
  add_wait(pv);

  auto* home = add("home", "homing: 6060h = 6, homing operation start, until homing attained");
  home->add_option(
          "--method", args.method,
          "6098h homing method (CiA 402-2: 1..35, 37; stepnode: -1, -2, -17, -18 on a hard stop)")
      ->check(CLI::Range(-128, 127));
  home->add_option("--switch-speed", args.switch_speed, "6099h:1 speed during search for switch")
      ->check(u32);
  home->add_option("--zero-speed", args.zero_speed, "6099h:2 speed during search for zero")
      ->check(u32);
  home->add_option("--acceleration", args.acceleration, "609Ah homing acceleration")->check(u32);
  home->add_option("--offset", args.home_offset, "607Ch home offset (the home position's position)")
      ->check(CLI::Range(int64_t{INT32_MIN}, int64_t{INT32_MAX}));
  home->add_flag("--no-wait", args.no_wait, "return once the homing has started");
  add_wait(home);
  return drive;
}

}  // namespace stepnode::tools
