// stepctl hp --program: the manual's example listings (examples/hp44714a/, copied from the
// manual) parse as HP BASIC runs them - line numbers in order, a repeated number replacing
// the earlier line, `!` and `|` comments - and every command string is the module's words
// or the mainframe's (USE, WAIT, RST, ON INTR CALL, ENABLE INTR SYS, SUB/SUBEND, BEEP).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "tools/stepctl/hp_program.hpp"
#include "tools/stepctl/hp_words.hpp"

#ifndef STEPNODE_SOURCE_DIR
#error "stepctl_tests needs STEPNODE_SOURCE_DIR (see tools/CMakeLists.txt)"
#endif

namespace stepnode::tools {
namespace {

std::string example(const char* name) {
  std::ifstream in(std::string(STEPNODE_SOURCE_DIR) + "/examples/hp44714a/" + name);
  EXPECT_TRUE(in) << name;
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Figure 3-3: its second block (lines 70-150) replaces lines 70, 80 and 90 of the first.
TEST(HpProgram, Figure3_3RunsInLineOrderWithTheSecondBlockReplacingLines70To90) {
  std::vector<std::string> notes;
  const auto p = parse_hp_program(example("figure-3-3.bas"), &notes);
  EXPECT_EQ(notes.size(), 3u);
  std::vector<int> lines;
  for (const HpStatement& s : p) lines.push_back(s.line);
  std::vector<int> expected;
  for (int n = 10; n <= 250; n += 10) expected.push_back(n);
  EXPECT_EQ(lines, expected);
  EXPECT_EQ(p[6].text, "DELAY 5");         // line 70 of the second block
  EXPECT_EQ(p[8].text, "MOVE 20 NOWAIT");  // line 90
  EXPECT_EQ(p[10].kind, HpStatement::Pause);
  EXPECT_EQ(p.back().kind, HpStatement::End);
  const auto use = parse_hp_command_string(p[1].text);
  ASSERT_EQ(use.size(), 1u);
  EXPECT_EQ(use[0].kind, HpProgramCommand::Use);
  EXPECT_EQ(use[0].channel, 0);  // slot 5 channel 00
  EXPECT_EQ(parse_hp_command_string(p[0].text)[0].kind, HpProgramCommand::Reset);
  const auto wait = parse_hp_command_string(p[16].text);
  EXPECT_EQ(wait[0].kind, HpProgramCommand::Wait);
  EXPECT_EQ(wait[0].seconds, 10);
  // Every module command is the manual's words.
  for (const HpStatement& s : p)
    if (s.kind == HpStatement::Output)
      for (const HpProgramCommand& c : parse_hp_command_string(s.text))
        if (c.kind == HpProgramCommand::Module) {
          EXPECT_NO_THROW(plan_hp_words(c.words, 0)) << c.words;
        }
}

TEST(HpProgram, TheInterruptExamplesHaveTheirRoutineAndSystemInterrupt) {
  for (const char* name : {"interrupt-example.bas", "width-interrupt-example.bas"}) {
    SCOPED_TRACE(name);
    const auto p = parse_hp_program(example(name));
    std::vector<HpProgramCommand> all;
    for (const HpStatement& s : p)
      for (const HpProgramCommand& c : parse_hp_command_string(s.text)) all.push_back(c);
    ASSERT_GE(all.size(), 12u);
    EXPECT_EQ(all[0].kind, HpProgramCommand::Use);
    EXPECT_EQ(all[2].kind, HpProgramCommand::OnIntrCall);
    EXPECT_EQ(all[2].name, "INTRUPT");
    EXPECT_EQ(all[3].kind, HpProgramCommand::SystemInterrupt);
    EXPECT_TRUE(all[3].on);
    EXPECT_EQ(all[4].kind, HpProgramCommand::Module);  // the module's ENABLE INTR
    EXPECT_EQ(all[5].kind, HpProgramCommand::Sub);
    EXPECT_EQ(all[6].kind, HpProgramCommand::Beep);
    EXPECT_EQ(all[8].kind, HpProgramCommand::SubEnd);
    EXPECT_EQ(all.back().words, "HALT SGL");  // the comment is gone
  }
}

TEST(HpProgram, ListingRulesAndMistakes) {
  // Several commands in one string, a command's own USE, and a comment in quotes is text.
  const auto c = parse_hp_command_string("PSCALE 2; POS? USE 402;  ; WAIT 0.5");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[1].channel, 2);
  EXPECT_EQ(c[1].words, "POS? ");
  EXPECT_EQ(parse_hp_program("10 OUTPUT 709;\"POS 1 ! not a comment\"\n")[0].text,
            "POS 1 ! not a comment");
  EXPECT_THROW(parse_hp_program("10 OUTPUT 709;\"POS 0\"\nOUTPUT 709;\"POS 1\"\n"),
               std::invalid_argument);
  EXPECT_THROW(parse_hp_program("10 GOTO 10\n"), std::invalid_argument);
  EXPECT_THROW(parse_hp_program("10 OUTPUT 709;POS 0\n"), std::invalid_argument);
  EXPECT_THROW(parse_hp_program("! only a comment\n"), std::invalid_argument);
  EXPECT_THROW(parse_hp_command_string("USE 409"), std::invalid_argument);
  EXPECT_THROW(parse_hp_command_string("WAIT soon"), std::invalid_argument);
  // RST is the power-on state of 3-2 in the module's own words.
  const auto reset = plan_hp_words(hp_reset_words(), 1);
  EXPECT_GT(reset.size(), 15u);
  EXPECT_EQ(reset.front().index, 0x2114);  // TRIG HOLD first: an armed command is cancelled
  // 3-2: "all interrupts are disabled": before HALT SGL stops a motion, which an enabled
  // channel would report as an interrupt (found in review).
  const std::string words = hp_reset_words();
  ASSERT_NE(words.find("DISABLE INTR"), std::string::npos);
  EXPECT_LT(words.find("DISABLE INTR"), words.find("HALT SGL"));
}

}  // namespace
}  // namespace stepnode::tools
