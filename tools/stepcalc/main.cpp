// stepcalc: the Horner STPCALC calculator (SPM30 Appendix B) with the engine's exact values
// for the same move beside every figure.
//   stepcalc TOTAL AQ3 AQ4 AQ5 AQ6 AQ7 [--json] [--stpcalc-peak] [--plot FILE.svg|FILE.png]
// TOTAL is 0..16777215 or '-' (a move without destination). Bad input: exit 2, one line.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "tools/stepcalc/arguments.hpp"
#include "tools/stepcalc/cia402_command.hpp"
#include "tools/stepcalc/png_export.hpp"
#include "tools/stepcalc/profile_report.hpp"
#include "tools/stepcalc/svg_plot.hpp"

using namespace stepnode;

namespace {

int run(int argc, char** argv) {
  // `stepcalc cia402 ...`: a CiA 402 move instead of the Horner registers.
  if (argc > 1 && std::string(argv[1]) == "cia402") return tools::run_cia402(argc - 1, argv + 1);
  CLI::App app{
      "stepcalc: the Horner STPCALC profile calculator (SPM30 Appendix B), with the pulse\n"
      "engine's exact values for the same move beside STPCALC's."};
  std::string total;
  std::vector<std::string> aq;
  bool json = false, stpcalc_peak = false;
  std::string plot;
  app.add_option("TOTAL", total,
                 "total pulses 0..16777215, or - for a move without destination (jog)")
      ->required();
  app.add_option(
         "AQ3_AQ7", aq,
         "velocity resolution AQ3 (20..65535), base velocity AQ4 (1..8190), running velocity AQ5\n"
         "(AQ4+1..8191), acceleration ms AQ6 and deceleration ms AQ7 (1..(AQ5-AQ4)/0.3, at most "
         "27300;\n"
         "AQ7 0 = AQ6)")
      ->required()
      ->expected(5);
  app.add_flag(
      "--json", json,
      "print one JSON object: STPCALC's values and an \"engine\" object with the same keys");
  app.add_flag(
      "--stpcalc-peak", stpcalc_peak,
      "the engine as an axis with 0x2n09:13 set: a short move cruises at STPCALC's peak velocity\n"
      "instead of turning where its ramps meet (halfway with equal ramps, SPM30 3.4.5)");
  app.add_option("--plot", plot,
                 "draw velocity against time, STPCALC's and the engine's: FILE.svg, or FILE.png "
                 "(rsvg-convert)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::fprintf(stderr,
                 "stepcalc: %s (usage: stepcalc TOTAL AQ3 AQ4 AQ5 AQ6 AQ7 [--json] "
                 "[--stpcalc-peak] [--plot FILE])\n",
                 e.what());
    return 2;
  }
  if (!plot.empty() && !tools::plot_path_ok(plot)) {
    std::fprintf(stderr, "stepcalc: --plot '%s' must name a .svg or .png file\n", plot.c_str());
    return 2;
  }
  tools::ProfileReport report;
  try {
    report = tools::make_report(tools::parse_input(total, aq), stpcalc_peak);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "stepcalc: %s\n", e.what());
    return 2;
  }
  std::cout << (json ? tools::report_json(report) : tools::report_text(report));
  if (plot.empty()) return 0;
  try {
    tools::write_plot(tools::render_svg(report), plot);
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "stepcalc: %s\n", e.what());
    return 1;
  }
  if (!json) std::cout << "plot written to " << plot << "\n";
  return 0;
}

}  // namespace

// Anything the parser or the engine did not expect (out of memory, a broken pipe on output)
// ends the program with one line and status 1, never std::terminate.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "stepcalc: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "stepcalc: unexpected error\n";
  }
  return 1;
}
