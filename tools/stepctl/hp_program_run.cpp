// `stepctl hp --program FILE`: runs a listing parsed by hp_program.cpp on the bus. The
// module's words go through run_hp_plan; the mainframe's (USE, WAIT, RST, ON INTR CALL,
// ENABLE INTR SYS, SUB ... SUBEND, BEEP) and BASIC's PAUSE and END are done here. An HP
// interrupt (the channel's event word 0x2n1D:2, looked at after every access and every
// 20 ms of a wait) calls the ON INTR routine while the system interrupt is enabled.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>

#include "node/profiles/hp44714a/objects.hpp"
#include "tools/stepctl/hp_command.hpp"
#include "tools/stepctl/hp_program.hpp"

namespace stepnode::tools {
namespace {

using namespace hp44714a::obj;
using Clock = std::chrono::steady_clock;

const char* event_text(uint8_t event) {
  switch (event) {
    case 1: return "pulses stopped following a MOVE";
    case 2: return "the SUSTAIN frequency or width was reached";
    case 4: return "a hard limit stopped pulses";
    case 8: return "HALT SGL stopped pulses";
    case 16: return "the HALT switch stopped pulses";
    default: return "interrupt";
  }
}

class ProgramRunner {
 public:
  ProgramRunner(MasterBus& bus, int node, unsigned channel, int wait_s)
      : bus_(bus),
        id_(static_cast<uint8_t>(node)),
        node_(node),
        channel_(channel),
        wait_s_(wait_s) {
    channels_.insert(channel);
  }

  int statement(const HpStatement& s) {
    if (s.kind == HpStatement::Pause) return pause(s.line ? s.line : s.file_line);
    if (s.kind != HpStatement::Output) return 0;
    for (const HpProgramCommand& c : parse_hp_command_string(s.text))
      if (int r = command(c); r != 0) return r;
    return 0;
  }

 private:
  int command(const HpProgramCommand& c) {
    if (!recording_.empty()) {  // inside SUB ... SUBEND: kept for the interrupt
      if (c.kind == HpProgramCommand::SubEnd) recording_.clear();
      else routines_[recording_].push_back(c);
      return 0;
    }
    switch (c.kind) {
      case HpProgramCommand::Use:
        channel_ = static_cast<unsigned>(c.channel);
        channels_.insert(channel_);
        return 0;
      case HpProgramCommand::Wait: return wait(c.seconds);
      case HpProgramCommand::Reset: return reset();
      case HpProgramCommand::OnIntrCall: handler_ = c.name; return 0;
      case HpProgramCommand::SystemInterrupt: system_interrupt_ = c.on; return 0;
      case HpProgramCommand::Sub:
        recording_ = c.name;
        routines_[c.name].clear();
        return 0;
      case HpProgramCommand::SubEnd: return 0;
      case HpProgramCommand::Beep:
        std::printf("BEEP\n");
        std::fflush(stdout);
        return 0;
      case HpProgramCommand::Module: break;
    }
    return module(c.words, c.channel >= 0 ? static_cast<unsigned>(c.channel) : channel_);
  }

  int module(const std::string& words, unsigned ch) {
    channels_.insert(ch);
    return run_hp_plan(bus_, node_, ch, plan_hp_words(words, ch), wait_s_,
                       [this] { poll_interrupts(); });
  }

  // RST slot: every channel of the module (those the node has) to its power-on state.
  int reset() {
    for (unsigned ch = 0; ch < 3; ++ch) {
      if (ch > 0 && !bus_.upload(id_, index(ch, kDone), 0).ok()) break;  // the node has fewer axes
      if (int r = module(hp_reset_words(), ch); r != 0) return r;
    }
    return 0;
  }

  int wait(double seconds) {
    const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(seconds));
    while (Clock::now() < end) {
      poll_interrupts();
      std::this_thread::sleep_for(
          std::min<Clock::duration>(std::chrono::milliseconds(20), end - Clock::now()));
    }
    poll_interrupts();
    return 0;
  }

  // PAUSE: the operator presses CONTINUE. At a terminal, Enter; otherwise the program goes
  // on when no channel it used is still running (when an operator would press it).
  int pause(int line) {
    if (isatty(STDIN_FILENO)) {
      std::fprintf(stderr, "PAUSE (line %d): press Enter to continue\n", line);
      std::string ignored;
      std::getline(std::cin, ignored);
      return 0;
    }
    const auto deadline = Clock::now() + std::chrono::seconds(wait_s_);
    for (;;) {
      bool running = false;
      for (unsigned ch : channels_) {
        od::SdoResult r = bus_.upload(id_, index(ch, kDone), 0);
        running = running || (r.ok() && static_cast<int8_t>(r.data.at(0)) == -2);
      }
      if (!running) return 0;
      if (Clock::now() > deadline) {
        std::fprintf(stderr, "stepctl: PAUSE (line %d): still running after %d s\n", line, wait_s_);
        return 1;
      }
      poll_interrupts();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  uint8_t events(unsigned ch) {
    od::SdoResult r = bus_.upload(id_, index(ch, kInterrupt), hp44714a::intr_sub::kEvents);
    return r.ok() ? r.data.at(0) : 0;
  }

  // An interrupt is a new event word on a channel; the routine runs on that channel.
  void poll_interrupts() {
    if (in_routine_ || !system_interrupt_ || handler_.empty()) return;
    for (unsigned ch : channels_) {
      const uint8_t e = events(ch);
      if (e == 0 || e == last_events_[ch]) {
        last_events_[ch] = e;
        continue;
      }
      std::printf("INTR channel %u: %s\n", ch, event_text(e));
      std::fflush(stdout);
      in_routine_ = true;
      const unsigned saved = channel_;
      channel_ = ch;
      for (const HpProgramCommand& c : routines_[handler_])
        if (command(c) != 0) failed_ = true;
      channel_ = saved;
      in_routine_ = false;
      last_events_[ch] = events(ch);  // the routine's ENABLE INTR cleared it
    }
  }

 public:
  bool failed() const { return failed_; }

 private:
  MasterBus& bus_;
  uint8_t id_;
  int node_;
  unsigned channel_;
  int wait_s_;
  std::set<unsigned> channels_;
  std::string handler_, recording_;
  bool system_interrupt_ = false, in_routine_ = false, failed_ = false;
  std::map<std::string, std::vector<HpProgramCommand>> routines_;
  std::map<unsigned, uint8_t> last_events_;
};

// Every command string planned before the bus: a word that is not the manual's is exit 2.
void check_program(const std::vector<HpStatement>& program, unsigned channel) {
  for (const HpStatement& s : program) {
    if (s.kind != HpStatement::Output) continue;
    try {
      for (const HpProgramCommand& c : parse_hp_command_string(s.text)) {
        if (c.kind == HpProgramCommand::Use) channel = static_cast<unsigned>(c.channel);
        if (c.kind == HpProgramCommand::Module)
          plan_hp_words(c.words, c.channel >= 0 ? static_cast<unsigned>(c.channel) : channel);
      }
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("line " + std::to_string(s.file_line) + ": " + e.what());
    }
  }
}

}  // namespace

void check_hp_program(const std::string& listing, unsigned channel) {
  check_program(parse_hp_program(listing), channel);
}

int run_hp_program(MasterBus& bus, int node, unsigned channel, const std::string& listing,
                   int wait_timeout_s) {
  std::vector<std::string> notes;
  const std::vector<HpStatement> program = parse_hp_program(listing, &notes);
  check_program(program, channel);
  for (const std::string& n : notes) std::fprintf(stderr, "stepctl: %s\n", n.c_str());
  ProgramRunner runner(bus, node, channel, wait_timeout_s);
  for (const HpStatement& s : program) {
    if (s.kind == HpStatement::End) break;
    if (int r = runner.statement(s); r != 0) return r;
  }
  return runner.failed() ? 1 : 0;
}

}  // namespace stepnode::tools
