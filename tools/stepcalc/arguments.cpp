#include "tools/stepcalc/arguments.hpp"

#include <charconv>
#include <stdexcept>

namespace stepnode::tools {
namespace {

struct Word {
  const char* name;
  const char* range;
};

// The static ranges of B1.2 / SPM30 3.4; motion::stpcalc() narrows AQ5..AQ7 further.
constexpr Word kWords[] = {
    {"velocity resolution %AQ3", "20..65535"},
    {"base velocity %AQ4", "1..8190"},
    {"running velocity %AQ5", "2..8191, above %AQ4"},
    {"acceleration time %AQ6 (ms)", "1..27300"},
    {"deceleration time %AQ7 (ms)", "0..27300, 0 = same as %AQ6"},
};

// A whole decimal integer (an optional leading '-'), or nothing.
bool to_integer(const std::string& text, int64_t& value) {
  const char* first = text.data();
  const char* last = first + text.size();
  auto [end, ec] = std::from_chars(first, last, value);
  return ec == std::errc() && end == last && !text.empty();
}

}  // namespace

motion::StpcalcInput parse_input(const std::string& total, const std::vector<std::string>& aq) {
  if (aq.size() != 5)
    throw std::invalid_argument("expected TOTAL AQ3 AQ4 AQ5 AQ6 AQ7 (6 values), got " +
                                std::to_string(aq.size() + 1));
  motion::StpcalcInput in;
  if (total != "-") {
    int64_t t = 0;
    if (!to_integer(total, t))
      throw std::invalid_argument("total pulses '" + total +
                                  "' is not an integer (0..16777215, or - for none)");
    in.total = t;
  }
  int64_t v[5];
  for (size_t i = 0; i < 5; ++i)
    if (!to_integer(aq[i], v[i]))
      throw std::invalid_argument(std::string(kWords[i].name) + " '" + aq[i] +
                                  "' is not an integer (" + kWords[i].range + ")");
  in.aq3 = v[0], in.aq4 = v[1], in.aq5 = v[2], in.aq6 = v[3], in.aq7 = v[4];
  return in;
}

}  // namespace stepnode::tools
