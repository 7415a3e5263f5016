#include "tools/stepctl/hp_program.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <sstream>
#include <stdexcept>

namespace stepnode::tools {
namespace {

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::vector<std::string> words_of(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(upper(w));
  return out;
}

// The line without its comment: `!` (or the listing's `|`) outside quotes ends it.
std::string without_comment(const std::string& line) {
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    if (line[i] == '"') quoted = !quoted;
    else if (!quoted && (line[i] == '!' || line[i] == '|')) return line.substr(0, i);
  }
  return line;
}

std::string error_at(int file_line, const std::string& what) {
  return "line " + std::to_string(file_line) + ": " + what;
}

// One statement of the listing (its number already taken off).
HpStatement statement(const std::string& text, int file_line) {
  HpStatement s;
  s.file_line = file_line;
  const std::string up = upper(text);
  if (up.rfind("OUTPUT", 0) == 0) {
    // OUTPUT 709;"...": the string between the first pair of quotes.
    const auto open = text.find('"'),
               close = open == std::string::npos ? open : text.find('"', open + 1);
    if (close == std::string::npos)
      throw std::invalid_argument(error_at(file_line, "OUTPUT needs a quoted command string"));
    s.text = text.substr(open + 1, close - open - 1);
    return s;
  }
  const std::string first = words_of(text).at(0);
  if (first == "PAUSE") s.kind = HpStatement::Pause;
  else if (first == "END") s.kind = HpStatement::End;
  else if (first == "ENTER" || first == "PRINT") s.kind = HpStatement::Ignored;
  else
    throw std::invalid_argument(
        error_at(file_line, "'" + first + "' is not OUTPUT, PAUSE, ENTER, PRINT or END"));
  return s;
}

// "USE ssc": slot s, channel cc; the channel is cc.
int channel_of(const std::string& w) {
  size_t used = 0;
  int n = -1;
  try {
    n = std::stoi(w, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != w.size() || n < 0)
    throw std::invalid_argument("USE: '" + w + "' is not a slot and channel (e.g. 500)");
  if (n % 100 > 7)
    throw std::invalid_argument("USE " + w + ": channel " + std::to_string(n % 100) +
                                " is not one of a node's axes 0..7");
  return n % 100;
}

double seconds_of(const std::string& w) {
  size_t used = 0;
  double v = -1;
  try {
    v = std::stod(w, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != w.size() || !(v >= 0))
    throw std::invalid_argument("WAIT: '" + w + "' is not a number of seconds");
  return v;
}

HpProgramCommand command_of(const std::string& text) {
  HpProgramCommand c;
  const auto w = words_of(text);
  const std::string& first = w.at(0);
  if (first == "USE") {
    if (w.size() != 2) throw std::invalid_argument("USE takes one slot and channel (e.g. USE 500)");
    c.kind = HpProgramCommand::Use;
    c.channel = channel_of(w[1]);
  } else if (first == "WAIT") {
    if (w.size() != 2) throw std::invalid_argument("WAIT takes a number of seconds");
    c.kind = HpProgramCommand::Wait;
    c.seconds = seconds_of(w[1]);
  } else if (first == "RST") {
    c.kind = HpProgramCommand::Reset;
  } else if (w.size() == 4 && first == "ON" && w[1] == "INTR" && w[2] == "CALL") {
    c.kind = HpProgramCommand::OnIntrCall;
    c.name = w[3];
  } else if (w.size() == 3 && (first == "ENABLE" || first == "DISABLE") && w[1] == "INTR" &&
             w[2] == "SYS") {
    c.kind = HpProgramCommand::SystemInterrupt;
    c.on = first == "ENABLE";
  } else if (first == "SUB" || first == "SUBEND" || first == "BEEP") {
    if (first == "SUB" && w.size() != 2) throw std::invalid_argument("SUB takes a name");
    c.kind = first == "SUB"      ? HpProgramCommand::Sub
             : first == "SUBEND" ? HpProgramCommand::SubEnd
                                 : HpProgramCommand::Beep;
    if (first == "SUB") c.name = w[1];
  } else {
    // The module's words, with the channel of a trailing "USE ssc" for this command only.
    c.words = text;
    if (w.size() >= 3 && w[w.size() - 2] == "USE") {
      c.channel = channel_of(w.back());
      const std::string up = upper(text);
      c.words = text.substr(0, up.rfind("USE"));
    }
  }
  return c;
}

}  // namespace

std::vector<HpStatement> parse_hp_program(const std::string& listing,
                                          std::vector<std::string>* notes) {
  std::map<int, HpStatement> numbered;
  std::vector<HpStatement> in_order;
  std::istringstream in(listing);
  int file_line = 0;
  for (std::string raw; std::getline(in, raw);) {
    ++file_line;
    std::string text = trim(without_comment(raw));
    if (text.empty()) continue;
    int number = 0;
    size_t digits = 0;
    while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits]))) ++digits;
    if (digits > 0) {
      number = std::stoi(text.substr(0, digits));
      text = trim(text.substr(digits));
      if (text.empty()) continue;  // a numbered empty line
    }
    if ((number > 0 && !in_order.empty()) || (number == 0 && !numbered.empty()))
      throw std::invalid_argument(
          error_at(file_line, "a listing has line numbers on every line or on none"));
    HpStatement s = statement(text, file_line);
    s.line = number;
    if (number == 0) {
      in_order.push_back(s);
      continue;
    }
    if (numbered.contains(number) && notes)
      notes->push_back("line " + std::to_string(number) + " (file line " +
                       std::to_string(file_line) + ") replaces the earlier line " +
                       std::to_string(number));
    numbered[number] = s;
  }
  if (numbered.empty() && in_order.empty())
    throw std::invalid_argument("the program has no statements");
  for (const auto& [number, s] : numbered) in_order.push_back(s);
  return in_order;
}

std::vector<HpProgramCommand> parse_hp_command_string(const std::string& text) {
  std::vector<HpProgramCommand> out;
  std::istringstream in(text);
  for (std::string one; std::getline(in, one, ';');)
    if (!trim(one).empty()) out.push_back(command_of(trim(one)));
  return out;
}

std::string hp_reset_words() {
  // The power-on/reset state of 3-2. Interrupts off before HALT SGL stops a running motion:
  // "all interrupts are disabled" at a reset, so its stop must raise none. PSCALE before
  // PROFILE: PROFILE FREQ values are in the units of the PSCALE in effect (3-9).
  return "TRIG HOLD; DISABLE INTR; HALT SGL; PSCALE 1; PROFILE FREQ 0 250 500 50E-6; DELAY 0; "
         "STANDBY AUTO HI; "
         "PULSE SS LO LO; HALT LO; HARDLIM LO LO; QSCALE 1; QINDEX OFF; TRIG AUTO";
}

}  // namespace stepnode::tools
