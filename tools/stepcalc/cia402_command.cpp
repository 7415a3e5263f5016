// stepcalc cia402 DISTANCE --velocity V --acceleration A [--deceleration D]
//   [--profile-type 0|3] [--jerk J | --jerks J1 J2 J3 J4] [--json] [--plot FILE.svg|FILE.png]
#include "tools/stepcalc/cia402_command.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "tools/stepcalc/cia402_profile.hpp"
#include "tools/stepcalc/png_export.hpp"
#include "tools/stepcalc/svg_plot.hpp"

namespace stepnode::tools {

int run_cia402(int argc, char** argv) {
  CLI::App app{
      "stepcalc cia402: a CiA 402 profile position move from standstill, run in the pulse\n"
      "engine as the drive runs it, beside the closed form of the same profile."};
  app.name("stepcalc cia402");
  Cia402Move m;
  std::optional<uint32_t> deceleration, jerk;
  std::vector<uint32_t> jerks;
  bool json = false;
  std::string plot;
  auto u32 = CLI::Range(uint32_t{0}, UINT32_MAX);
  app.add_option("DISTANCE", m.distance, "steps to move (607Ah from 0), 1..2147483647")->required();
  app.add_option("--velocity", m.velocity, "6081h profile velocity, steps/s")
      ->required()
      ->check(u32);
  app.add_option("--acceleration", m.acceleration, "6083h profile acceleration, steps/s^2")
      ->required()
      ->check(u32);
  app.add_option("--deceleration", deceleration, "6084h profile deceleration (default: 6083h)")
      ->check(u32);
  app.add_option("--profile-type", m.profile_type,
                 "6086h: 0 linear ramp (default), 3 jerk-limited");
  auto* one = app.add_option("--jerk", jerk, "60A4h:1..4 all this jerk, steps/s^3 (0: not limited)")
                  ->check(u32);
  app.add_option("--jerks", jerks,
                 "60A4h:1..4: begin acceleration, begin deceleration, end acceleration, end "
                 "deceleration jerk")
      ->expected(4)
      ->excludes(one);
  app.add_flag("--json", json, "one JSON object instead of the table");
  app.add_option("--plot", plot, "velocity against time, closed form and engine: FILE.svg or .png");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::fprintf(stderr,
                 "stepcalc: %s (usage: stepcalc cia402 DISTANCE --velocity V --acceleration A "
                 "[--deceleration D] [--profile-type 0|3] [--jerk J | --jerks J1 J2 J3 J4])\n",
                 e.what());
    return 2;
  }
  m.deceleration = deceleration.value_or(m.acceleration);
  for (int i = 0; i < 4; ++i) m.jerk[i] = jerk ? *jerk : jerks.empty() ? 10'000 : jerks[i];
  if (!plot.empty() && !plot_path_ok(plot)) {
    std::fprintf(stderr, "stepcalc: --plot '%s' must name a .svg or .png file\n", plot.c_str());
    return 2;
  }
  Cia402Report r;
  try {
    r = make_cia402_report(m);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "stepcalc: %s\n", e.what());
    return 2;
  }
  std::cout << (json ? cia402_json(r) : cia402_text(r));
  if (plot.empty()) return 0;
  try {
    write_plot(render_svg(cia402_plot(r)), plot);
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "stepcalc: %s\n", e.what());
    return 1;
  }
  if (!json) std::cout << "plot written to " << plot << "\n";
  return 0;
}

}  // namespace stepnode::tools
