// stepcalc's positional arguments: numbers, '-' for no total, refusals naming the range.
#include <gtest/gtest.h>

#include "tools/stepcalc/arguments.hpp"

namespace stepnode::tools {
namespace {

std::string refusal(const std::string& total, std::vector<std::string> aq) {
  try {
    parse_input(total, aq);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

TEST(StepcalcArguments, ParsesNumbersAndDashForNoTotal) {
  motion::StpcalcInput in = parse_input("10000", {"600", "100", "1000", "500", "0"});
  ASSERT_TRUE(in.total);
  EXPECT_EQ(*in.total, 10000);
  EXPECT_EQ(in.aq3, 600);
  EXPECT_EQ(in.aq4, 100);
  EXPECT_EQ(in.aq5, 1000);
  EXPECT_EQ(in.aq6, 500);
  EXPECT_EQ(in.aq7, 0);
  EXPECT_FALSE(parse_input("-", {"20", "1", "8191", "100", "0"}).total);
  // Range checks are make_report's; the parser keeps the numbers as given.
  EXPECT_EQ(*parse_input("-5", {"20", "1", "8191", "100", "0"}).total, -5);
}

TEST(StepcalcArguments, RefusesWhatIsNotAnIntegerWithTheLegalRange) {
  EXPECT_NE(refusal("abc", {"600", "100", "1000", "500", "0"}).find("0..16777215"),
            std::string::npos);
  EXPECT_NE(refusal("1e4", {"600", "100", "1000", "500", "0"}).find("0..16777215"),
            std::string::npos);
  EXPECT_NE(refusal("", {"600", "100", "1000", "500", "0"}).find("0..16777215"), std::string::npos);
  EXPECT_NE(refusal("99999999999999999999", {"600", "100", "1000", "500", "0"}).find("0..16777215"),
            std::string::npos);
  EXPECT_NE(refusal("10", {"x", "100", "1000", "500", "0"})
                .find("%AQ3 'x' is not an integer (20..65535)"),
            std::string::npos);
  EXPECT_NE(refusal("10", {"600", "1.5", "1000", "500", "0"}).find("1..8190"), std::string::npos);
  EXPECT_NE(refusal("10", {"600", "100", "fast", "500", "0"}).find("2..8191"), std::string::npos);
  EXPECT_NE(refusal("10", {"600", "100", "1000", "", "0"}).find("1..27300"), std::string::npos);
  EXPECT_NE(refusal("10", {"600", "100", "1000", "500", "0x10"}).find("0..27300"),
            std::string::npos);
  EXPECT_NE(refusal("10", {"600", "100", "1000", "500"}).find("6 values"), std::string::npos);
}

}  // namespace
}  // namespace stepnode::tools
