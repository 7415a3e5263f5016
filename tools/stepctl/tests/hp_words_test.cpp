// stepctl hp: the manual's words (HP 44714A chapter 3, Command Summary) become the right
// object accesses on the right channel, defaults as the manual gives them, bad words refused.
#include <gtest/gtest.h>

#include <stdexcept>

#include "node/profiles/hp44714a/objects.hpp"
#include "tools/stepctl/hp_words.hpp"

namespace stepnode::tools {
namespace {

using namespace hp44714a::obj;

double real(const HpAccess& a) { return od::decode<double>(a.data); }

TEST(HpWords, ProfileFreqWritesTheFourValuesThenApplies) {
  auto p = plan_hp_words("PROFILE FREQ 100 800 200 25E-6", 0);
  ASSERT_EQ(p.size(), 6u);
  EXPECT_EQ(p[0].index, 0x2010);
  EXPECT_EQ(p[0].sub, hp44714a::profile_sub::kMode);
  EXPECT_EQ(p[0].data, od::Bytes{0});
  EXPECT_EQ(real(p[1]), 100);
  EXPECT_EQ(real(p[2]), 800);
  EXPECT_EQ(real(p[3]), 200);
  EXPECT_EQ(real(p[4]), 25e-6);
  EXPECT_EQ(p[5].sub, hp44714a::profile_sub::kApply);
  EXPECT_EQ(plan_hp_words("profile width 1e-3 10e-3 5e-3 20e-3", 2)[0].index, 0x2210);
  EXPECT_EQ(plan_hp_words("profile width 1e-3 10e-3 5e-3 20e-3", 2)[0].data, od::Bytes{1});
}

TEST(HpWords, MoveAndSustainSetNowaitAndWaitWithoutIt) {
  auto p = plan_hp_words("MOVE -30", 1);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0].index, 0x2112);
  EXPECT_EQ(p[0].sub, hp44714a::move_sub::kNowait);
  EXPECT_EQ(p[0].data, od::Bytes{0});
  EXPECT_EQ(p[1].sub, hp44714a::move_sub::kRelative);
  EXPECT_EQ(real(p[1]), -30);
  EXPECT_EQ(p[2].kind, HpAccess::WaitWhileRunning);
  p = plan_hp_words("MOVE 3 ABS NOWAIT", 0);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0].data, od::Bytes{1});
  EXPECT_EQ(p[1].sub, hp44714a::move_sub::kAbsolute);
  p = plan_hp_words("SUSTAIN 10 NOWAIT", 0);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[1].index, 0x2013);
  EXPECT_EQ(real(p[1]), 10);
}

TEST(HpWords, DefaultsOfTrigStandbyQindexAndSenses) {
  EXPECT_EQ(plan_hp_words("TRIG", 0)[0].data, od::Bytes{2});  // TRIG alone is SGL (3-14)
  EXPECT_EQ(plan_hp_words("TRIG SYS", 0)[0].data, od::Bytes{3});
  EXPECT_EQ(plan_hp_words("TRIG INT", 0)[0].data, od::Bytes{1});
  auto s = plan_hp_words("STANDBY", 0);  // no mode: ON, sense unchanged (3-6)
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].sub, hp44714a::output_sub::kStandbyMode);
  EXPECT_EQ(s[0].data, od::Bytes{1});
  s = plan_hp_words("STANDBY AUTO LO", 0);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].sub, hp44714a::output_sub::kStandbySense);
  EXPECT_EQ(s[0].data, od::Bytes{0});
  EXPECT_EQ(s[1].data, od::Bytes{2});
  auto q = plan_hp_words("QINDEX", 0);  // default SGL (3-21)
  EXPECT_EQ(q[0].data, od::Bytes{2});
  auto pulse = plan_hp_words("PULSE SD LH", 0);  // NDIR sense defaults to PSTP's
  ASSERT_EQ(pulse.size(), 3u);
  EXPECT_EQ(pulse[0].data, od::Bytes{1});
  EXPECT_EQ(pulse[1].data, od::Bytes{1});
  EXPECT_EQ(pulse[2].data, od::Bytes{0});
  EXPECT_EQ(plan_hp_words("DELAY 5", 0)[0].data, od::encode<uint16_t>(5000));
  EXPECT_EQ(plan_hp_words("HALT SGL", 0)[0].sub, hp44714a::limits_sub::kHaltSgl);
  EXPECT_EQ(plan_hp_words("HALT OFF", 0)[0].data, od::Bytes{2});
}

// Command Summary 4-2: "HARDLIM PLIMn_sense [NLIMn_sense]"; without NLIMn_sense the
// negative limit takes the positive one's sense, as "HARDLIM HI USE 402" sets both (3-17).
TEST(HpWords, Hp4_2_HardlimNlimSenseDefaultsToPlims) {
  auto h = plan_hp_words("HARDLIM HI", 0);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h[0].sub, hp44714a::limits_sub::kPlimSense);
  EXPECT_EQ(h[0].data, od::Bytes{1});
  EXPECT_EQ(h[1].sub, hp44714a::limits_sub::kNlimSense);
  EXPECT_EQ(h[1].data, od::Bytes{1});
  h = plan_hp_words("HARDLIM LO", 1);
  EXPECT_EQ(h[1].index, 0x2117);
  EXPECT_EQ(h[1].data, od::Bytes{0});
  h = plan_hp_words("HARDLIM HI LO", 0);
  EXPECT_EQ(h[0].data, od::Bytes{1});
  EXPECT_EQ(h[1].data, od::Bytes{0});
  EXPECT_THROW(plan_hp_words("HARDLIM", 0), std::invalid_argument);
}

// Command Summary 4-3: "TEST Initiates a pass/fail self test. Syntax: TEST slot": the test,
// then its answer read back (the slot is the node given with --node).
TEST(HpWords, Hp4_3_TestRunsTheSelfTestAndReadsItsAnswer) {
  for (const char* words : {"TEST", "TEST 5"}) {
    auto t = plan_hp_words(words, 2);
    ASSERT_EQ(t.size(), 2u) << words;
    EXPECT_EQ(t[0].kind, HpAccess::Write);
    EXPECT_EQ(t[0].index, 0x221F);
    EXPECT_EQ(t[0].sub, hp44714a::test_sub::kRun);
    EXPECT_EQ(t[0].data, od::Bytes{1});
    EXPECT_EQ(t[1].kind, HpAccess::Read);
    EXPECT_EQ(t[1].sub, hp44714a::test_sub::kResult);
    EXPECT_EQ(t[1].label, "TEST");
  }
  EXPECT_THROW(plan_hp_words("TEST FIVE", 0), std::invalid_argument);
}

TEST(HpWords, QueriesReadAndSeveralCommandsInOneString) {
  auto p = plan_hp_words("POS 0; PSCALE 2; MOVE 1 REL; POS?", 0);
  ASSERT_EQ(p.size(), 6u);
  EXPECT_EQ(p.back().kind, HpAccess::Read);
  EXPECT_EQ(p.back().index, 0x201B);
  EXPECT_EQ(plan_hp_words("DONE?", 0)[0].index, 0x2018);
  EXPECT_EQ(plan_hp_words("QPOS?", 0)[0].sub, hp44714a::quad_sub::kQpos);
  EXPECT_EQ(plan_hp_words("ENABLE INTR", 0)[0].data, od::Bytes{1});
  EXPECT_EQ(plan_hp_words("DISABLE INTR", 0)[0].data, od::Bytes{0});
}

TEST(HpWords, BadWordsAreRefusedBeforeAnythingIsSent) {
  EXPECT_THROW(plan_hp_words("PROFILE FREQ 100 800 200", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("PROFILE SPEED 1 2 3 4", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("MOVE ten", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("MOVE 10 SIDEWAYS", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("PSCALE 0", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("DELAY 70", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("TRIG NOW", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("MOVE 10 USE 400", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words("FLY 10", 0), std::invalid_argument);
  EXPECT_THROW(plan_hp_words(" ; ", 0), std::invalid_argument);
}

TEST(HpWords, TextsAreTheManuals) {
  EXPECT_EQ(hp_error_text(91), "MUST STOP TO CHANGE DIRECTION");
  EXPECT_EQ(hp_done_text(-3), "waiting for trigger");
  EXPECT_EQ(hp_conflict_text(5), "min > max");
  EXPECT_EQ(hp_conflict_text(7), "mode change while a MOVE or SUSTAIN waits for its trigger");
}

}  // namespace
}  // namespace stepnode::tools
