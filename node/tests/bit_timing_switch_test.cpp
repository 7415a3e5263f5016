// CiA 305 activate bit timing carried out (README, "LSS"): the switch delay waited before the
// controller switches and again after it, nothing sent in those two periods; and the node
// handing the command to the process with the bit rate of CiA 305's table (index 3: 250
// kbit/s) and the delay of the frame (bytes 1-2, little-endian ms).
#include "node/bit_timing_switch.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "node/deadline.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

struct Applied {
  std::vector<uint32_t> rates;
  std::string answer;  // what the interface says
};

TEST(BitTimingSwitch, SwitchesAfterOneDelayAndIsSilentForTwo) {
  Applied applied;
  BitTimingSwitch sw([&](uint32_t rate) {
    applied.rates.push_back(rate);
    return applied.answer;
  });
  const uint64_t t0 = 5'000'000;
  EXPECT_EQ(sw.next_deadline_us(), kNoDeadline);
  EXPECT_FALSE(sw.silent(t0));
  sw.activate(250, 100, t0);
  EXPECT_TRUE(sw.silent(t0));
  EXPECT_EQ(sw.next_deadline_us(), t0 + 100'000);
  sw.on_tick(t0 + 99'999);
  EXPECT_TRUE(applied.rates.empty());
  sw.on_tick(t0 + 100'000);
  EXPECT_EQ(applied.rates, std::vector<uint32_t>{250'000});
  EXPECT_EQ(sw.next_deadline_us(), t0 + 200'000);
  EXPECT_TRUE(sw.silent(t0 + 199'999));
  sw.on_tick(t0 + 199'999);
  EXPECT_TRUE(sw.active());
  sw.on_tick(t0 + 200'000);
  EXPECT_FALSE(sw.active());
  EXPECT_FALSE(sw.silent(t0 + 200'000));
  EXPECT_EQ(sw.next_deadline_us(), kNoDeadline);
  EXPECT_EQ(applied.rates.size(), 1u);
}

TEST(BitTimingSwitch, EveryNodeOfAProcessHearsTheBroadcastOnceIsEnough) {
  Applied applied;
  BitTimingSwitch sw([&](uint32_t rate) {
    applied.rates.push_back(rate);
    return std::string();
  });
  sw.activate(500, 10, 1'000);
  sw.activate(500, 10, 1'000);  // the second node of the process
  sw.activate(125, 50, 2'000);  // changes nothing while one is under way
  sw.on_tick(11'000);
  sw.on_tick(21'000);
  EXPECT_EQ(applied.rates, std::vector<uint32_t>{500'000});
  EXPECT_FALSE(sw.active());
}

TEST(BitTimingSwitch, AnInterfaceThatRefusesStillEndsTheSilenceOnTime) {
  Applied applied;
  applied.answer = "vcan0: bit rate 250000 bit/s: Operation not supported";
  BitTimingSwitch sw([&](uint32_t rate) {
    applied.rates.push_back(rate);
    return applied.answer;
  });
  sw.activate(250, 0, 7);  // a delay of 0: switch and speak at once
  EXPECT_EQ(sw.next_deadline_us(), 7u);
  sw.on_tick(7);
  EXPECT_EQ(applied.rates.size(), 1u);
  EXPECT_FALSE(sw.active());
}

class ActivateBitTimingNode : public NodeHarness {
 protected:
  struct Call {
    unsigned kbit;
    uint16_t delay_ms;
    uint64_t at;
  };
  std::vector<Call> calls;
  void SetUp() override {
    NodeOptions o;
    o.device.node_id = kId;
    o.state_dir = dir.path;
    o.activate_bit_timing = [this](unsigned kbit, uint16_t delay_ms, uint64_t now_us) {
      calls.push_back({kbit, delay_ms, now_us});
    };
    make(o);
  }
  void lss(std::initializer_list<uint8_t> bytes) {
    CanFrame f(0x7E5, {0, 0, 0, 0, 0, 0, 0, 0});
    size_t i = 0;
    for (uint8_t b : bytes) f.data[i++] = b;
    frame(f);
  }
};

TEST_F(ActivateBitTimingNode, TheProcessGetsTheTablesBitRateAndTheFramesDelay) {
  lss({0x04, 0x01});        // switch state global: configuration
  lss({0x13, 0x00, 0x03});  // configure bit timing: table 0, index 3
  EXPECT_EQ(sent.back(), CanFrame(0x7E4, {0x13, 0x00, 0, 0, 0, 0, 0, 0}));  // success
  EXPECT_TRUE(calls.empty());
  lss({0x15, 0x2C, 0x01});  // activate bit timing, switch delay 300 ms
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(calls[0].kbit, 250u);
  EXPECT_EQ(calls[0].delay_ms, 300);
  EXPECT_EQ(calls[0].at, t);
}

}  // namespace
}  // namespace stepnode::node::test
