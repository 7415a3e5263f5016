// `stepctl hp --program FILE`: an HP BASIC listing of the module's commands, as the manual's
// examples are written (Figure 3-3, the interrupt examples of 3-16 and 3-28), run on the bus.
// Pure: the listing in, the statements and the meaning of each command string out;
// hp_program_run.cpp runs them.
//
// What a listing may hold, and what it means:
//   - line numbers: honoured as BASIC does - statements run in line-number order and a line
//     given again replaces the earlier one (Figure 3-3's second block replaces lines 70-90
//     of the first); a listing without numbers runs in file order;
//   - `!` starts a comment outside quotes (`|` too: the manual's interrupt listing prints it);
//   - OUTPUT 709;"..."  - the mainframe's command string, commands separated by ';';
//   - PAUSE (the operator's CONTINUE), END; ENTER and PRINT are accepted and do nothing (a
//     query's answer is printed anyway).
// In a command string, besides the module's own words (hp_words.hpp):
//   USE ssc (slot s, channel cc: the channel; the slot is --node), a trailing USE ssc on one
//   command, WAIT s, RST [slot] (the module's power-on state, 3-2), ON INTR CALL name,
//   ENABLE INTR SYS / DISABLE INTR SYS (the mainframe's system interrupt), SUB name ...
//   SUBEND (an interrupt routine, kept, not run), BEEP.
#pragma once
#include <string>
#include <vector>

namespace stepnode::tools {

struct HpStatement {
  enum Kind { Output, Pause, End, Ignored } kind = Output;
  int line = 0;       // the listing's line number (0: none)
  int file_line = 0;  // where it is in the file (for messages)
  std::string text;   // Output: the command string
};

// The statements in the order they run. `notes` gets a line for each replaced line number.
// Throws std::invalid_argument naming the file line and the rule.
std::vector<HpStatement> parse_hp_program(const std::string& listing,
                                          std::vector<std::string>* notes = nullptr);

// One command of a command string.
struct HpProgramCommand {
  enum Kind {
    Module,
    Use,
    Wait,
    Reset,
    OnIntrCall,
    SystemInterrupt,
    Sub,
    SubEnd,
    Beep
  } kind = Module;
  std::string words;   // Module: the module's words, without a trailing USE
  int channel = -1;    // Use, or a Module command's own USE (-1: the current channel)
  double seconds = 0;  // Wait
  bool on = false;     // SystemInterrupt
  std::string name;    // OnIntrCall, Sub
};

// The commands of one OUTPUT string, split at ';' (empty ones dropped). Throws
// std::invalid_argument for a mainframe command given wrongly (USE without a channel...).
std::vector<HpProgramCommand> parse_hp_command_string(const std::string& text);

// RST: the power-on state of one channel (3-2) in the module's words: a running or armed
// command is cancelled first, interrupts disabled.
std::string hp_reset_words();

}  // namespace stepnode::tools
