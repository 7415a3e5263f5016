// stepcalc: STPCALC (SPM30 Appendix B) beside the engine's exact values for the same move.
//   stepcalc TOTAL AQ3 AQ4 AQ5 AQ6 AQ7 [--json] [--plot FILE.svg|FILE.png]
#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>

#include "tools/stepcalc/profile_report.hpp"

using namespace stepnode;

int main(int argc, char** argv) {
  CLI::App app{"stepcalc: the Horner STPCALC profile calculator, and the engine's exact values beside it"};
  std::string total;
  std::vector<long long> aq;
  bool json = false;
  std::string plot;
  app.add_option("TOTAL", total, "total pulses 0..16777215, or - for a move without destination")->required();
  app.add_option("AQ", aq, "AQ3 velocity resolution, AQ4 base, AQ5 running, AQ6 accel ms, AQ7 decel ms")
      ->required()->expected(5);
  app.add_flag("--json", json, "one JSON object: STPCALC's values and an 'engine' object");
  app.add_option("--plot", plot, "draw velocity against time for both (.svg, or .png with rsvg-convert)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "stepcalc: %s\n", e.what());
    return 2;
  }
  motion::StpcalcInput in;
  try {
    if (total != "-") {
      size_t used = 0;
      long long t = std::stoll(total, &used);
      if (used != total.size()) throw std::invalid_argument(total);
      in.total = t;
    }
  } catch (const std::exception&) {
    std::fprintf(stderr, "stepcalc: total pulses '%s' is not a number (0..16777215, or -)\n", total.c_str());
    return 2;
  }
  in.aq3 = aq[0], in.aq4 = aq[1], in.aq5 = aq[2], in.aq6 = aq[3], in.aq7 = aq[4];
  tools::ProfileReport report;
  try {
    report = tools::make_report(in);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "stepcalc: %s\n", e.what());
    return 2;
  }
  std::cout << (json ? tools::report_json(report) : tools::report_text(report));
  if (!plot.empty()) {
    bool png = plot.size() > 4 && plot.substr(plot.size() - 4) == ".png";
    std::string svg_path = png ? plot + ".svg" : plot;
    std::ofstream(svg_path) << tools::report_svg(report);
    if (png) {
      std::string cmd = "rsvg-convert -o '" + plot + "' '" + svg_path + "'";
      int rc = std::system(cmd.c_str());
      std::remove(svg_path.c_str());
      if (rc != 0) {
        std::fprintf(stderr, "stepcalc: PNG needs rsvg-convert (Debian librsvg2-bin; tools/setup installs it)\n");
        return 1;
      }
    }
    if (!json) std::cout << "plot written to " << plot << "\n";
  }
  return 0;
}
