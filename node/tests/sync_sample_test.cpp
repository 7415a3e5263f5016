// SYNC in the receive path (issue 13): the synchronous TPDOs leave from the SYNC frame's
// handler with values sampled at the SYNC's arrival at the interface (its kernel
// timestamp), not at the later moment the process handles it, so every node on a bus
// reports the same instant. Expected positions come from the simulated machine's own
// record of the steps it received (its trace), not from the TPDO path.
#include <gtest/gtest.h>

#include "node/profiles/horner/bits.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/sim/objects.hpp"
#include "node/tests/node_harness.hpp"

namespace stepnode::node::test {
namespace {

class SyncSampleTest : public NodeHarness {
 protected:
  static constexpr uint32_t kTpdo2 = 0x285;  // axis 1: motor position, encoder position
  void SetUp() override {
    NodeHarness::SetUp();
    using namespace horner::obj;
    device->machine().axes.at(0).trace_into(&trace);
    nmt(0x01);
    ASSERT_EQ(sdo_write(0x1801, 2, 1, 1), 0u);  // TPDO2 synchronous, every SYNC
    ASSERT_EQ(sdo_write(sim::obj::index(0, sim::obj::kSwitches),
                        sim::switches_sub::kUpperLimitEnabled, 0, 1),
              0u);
    ASSERT_EQ(sdo_write(index(0, kCommandBits), 0, horner::command::kClearErrors, 2), 0u);
    ASSERT_EQ(sdo_write(index(0, kCommandBits), 0, 0, 2), 0u);
    ASSERT_EQ(sdo_write(index(0, kCommandBits), 0, horner::command::kJogUp, 2), 0u);
    advance_ms(200);  // at its running velocity
  }
  // Steps the machine received up to and including `us`.
  int32_t steps_until(uint64_t us) {
    const motion::Tick limit = device->axes().ticks(us);
    int32_t n = 0;
    for (const auto& s : trace)
      if (s.time <= limit) n += s.direction;
    return n;
  }
  // The position in the one TPDO2 the SYNC handled at `t` with this arrival made.
  int32_t sync_at(uint64_t arrival_us) {
    const size_t before = sent.size();
    device->on_frame(CanFrame(0x80, {}), t, arrival_us);
    auto tpdo = with_id(kTpdo2, before);
    EXPECT_EQ(tpdo.size(), 1u);
    return tpdo.empty() ? 0 : static_cast<int32_t>(od::get_u32(tpdo[0].data.data()));
  }
  std::vector<sim::TracedStep> trace;
};

TEST_F(SyncSampleTest, TheTpdoReportsThePositionAtTheSyncsArrival) {
  const uint64_t last_tick = t;
  t += 4'000;                                  // handled 4 ms after the last tick...
  const uint64_t arrival = last_tick + 1'250;  // ...but it arrived 1.25 ms after it
  const int32_t reported = sync_at(arrival);
  EXPECT_EQ(reported, steps_until(arrival));
  EXPECT_LT(reported, steps_until(t)) << "the axis moved on between arrival and handling";
}

TEST_F(SyncSampleTest, WithoutATimestampItReportsTheHandlingTime) {
  t += 4'000;
  const int32_t reported = sync_at(0);  // first: the trace grows as the SYNC advances the axes
  EXPECT_EQ(reported, steps_until(t));
}

TEST_F(SyncSampleTest, AnArrivalBeforeTheLastAdvanceReportsThatAdvance) {
  const uint64_t last_tick = t;
  t += 3'000;
  const int32_t reported = sync_at(last_tick - 500);
  EXPECT_EQ(reported, steps_until(last_tick));  // never backwards
}

}  // namespace
}  // namespace stepnode::node::test
