// DiscoveryPlan on its own: the order of reads and how odd answers are taken, without a bus.
#include <gtest/gtest.h>

#include <cstring>

#include "bridge/observer/discovery_plan.hpp"

namespace stepnode::bridge {
namespace {

od::SdoResult value(od::Bytes data) {
  od::SdoResult r;
  r.data = std::move(data);
  return r;
}
od::SdoResult none() {
  od::SdoResult r;
  r.abort = od::SdoAbort::NoObject;
  r.aborted_by_server = true;
  return r;
}
od::Bytes u32(uint32_t v) { return od::encode<uint32_t>(v); }

// Answers the plan until it is done; `answer` gives the result for each read.
template <class F>
std::vector<SdoRead> run(DiscoveryPlan& p, F answer) {
  std::vector<SdoRead> reads;
  while (!p.finished() && reads.size() < 1000) {
    reads.push_back(p.next());
    p.on_result(answer(reads.back()));
  }
  return reads;
}

TEST(DiscoveryPlanOrder, AStepnodeWithOneAxisAndTwoTpdos) {
  DiscoveryPlan p;
  bool mapping_seen_before_snapshot = false;
  const auto reads = run(p, [&](SdoRead r) -> od::SdoResult {
    if (r.index == 0x2001 && p.mapping_read()) mapping_seen_before_snapshot = true;
    switch (r.index) {
      case 0x1017: return value(od::encode<uint16_t>(250));
      case 0x1018: return value(u32(r.sub == 2 ? 0x53544550 : r.sub));
      case 0x1008: return value({'a', 'x', 0, 0});  // NUL padded
      case 0x2001: return value(od::encode<uint16_t>(0x0180));
      case 0x2011: return value(od::encode<double>(0.0));  // nonsense scale
      case 0x1800: return value(u32(0x40000185));
      case 0x1801: return value(u32(0xC0000285));  // invalid: no mapping read
      case 0x1802: return value(u32(0x385));
      case 0x1A00: return r.sub == 0 ? value({9}) : value(u32(0x20050020));  // 9 > 8 entries
      case 0x1A02: return r.sub == 0 ? value({0}) : none();
      case 0x2105: return value(u32(-5));
      case 0x2106: return value(u32(7));
      default: return none();
    }
  });
  const NodeInfo& i = p.info();
  EXPECT_TRUE(mapping_seen_before_snapshot);
  EXPECT_EQ(i.heartbeat_period_ms, 250);
  EXPECT_TRUE(i.heartbeat_period_read);
  EXPECT_EQ(i.vendor_id, 1u);
  EXPECT_EQ(i.serial, 4u);
  EXPECT_EQ(i.device_name, "ax");
  EXPECT_EQ(i.axes, 1);
  EXPECT_TRUE(i.is_stepnode());
  EXPECT_EQ(i.pscale[0], 1.0) << "a zero PSCALE is taken as 1";
  ASSERT_EQ(i.tpdos.size(), 2u);
  EXPECT_EQ(i.tpdos[0].cob_id, 0x185);
  EXPECT_EQ(i.tpdos[0].mapping.size(), 8u) << "at most 8 entries are read";
  EXPECT_EQ(i.tpdos[1].number, 2);
  EXPECT_TRUE(i.tpdos[1].mapping.empty());
  EXPECT_TRUE(i.snapshot[0].status_read);
  EXPECT_EQ(i.snapshot[0].status_bits, 0x0180);
  EXPECT_FALSE(i.snapshot[0].done_read);
  EXPECT_FALSE(i.snapshot[0].motor_read) << "0x2005 answered 'no object' here";
  for (const SdoRead& r : reads) EXPECT_NE(r.index, 0x1A01) << "TPDO2 is invalid";
  // The probe stopped at the first missing block.
  int probes = 0;
  for (const SdoRead& r : reads)
    probes += (r.index & 0xF0FF) == 0x2001 && r.index != 0x2001 ? 1 : 0;
  EXPECT_EQ(probes, 1) << "0x2101 probed once and found missing";
}

TEST(DiscoveryPlanOrder, WrongSizedAnswersAreTakenAsAbsent) {
  DiscoveryPlan p;
  run(p, [](SdoRead r) -> od::SdoResult {
    if (r.index == 0x1018) return value({1, 2});  // 2 bytes for a U32
    if (r.index == 0x1017) return value({1, 2, 3, 4});
    return none();
  });
  EXPECT_FALSE(p.info().identity_read);
  EXPECT_FALSE(p.info().heartbeat_period_read);
  EXPECT_FALSE(p.info().is_stepnode());
}

TEST(DiscoveryPlanOrder, ADeviceNameIsCutAtItsFirstNulAndPrintableAscii) {
  // VISIBLE_STRING is ISO 646. A third-party device's Latin-1 byte made NodeHealth carry
  // invalid UTF-8 (stepwatch --json's dump throws on it, ROS 2 readers cannot decode it)
  // and an escape byte went into stepwatch's table as is.
  for (auto [bytes, expected] :
       {std::pair<od::Bytes, std::string>{{'M', 0xFC, 'l', 'l', 'e', 'r'}, "M?ller"},
        {{'a', 'b', 0, 'x', 'y', 0, 0}, "ab"},
        {{0x1B, '[', '2', 'J', 'n'}, "?[2Jn"}}) {
    DiscoveryPlan p;
    run(p, [&](SdoRead r) -> od::SdoResult { return r.index == 0x1008 ? value(bytes) : none(); });
    EXPECT_EQ(p.info().device_name, expected);
  }
}

TEST(DiscoveryPlanOrder, ATpdoWithA29BitCobIdIsNotDecoded) {
  // Bit 29 set: the CAN-ID is 29 bits (CiA 301 7.5.2.35). Masked to 11 bits it named
  // another frame (0x18000185 -> node 5's TPDO1) and took its decoder slot.
  DiscoveryPlan p;
  run(p, [](SdoRead r) -> od::SdoResult {
    if (r.index == 0x1018) return value(u32(r.sub == 2 ? 0x53544550 : 0));
    if (r.index == 0x2001) return value(od::encode<uint16_t>(0));
    if (r.index == 0x1800) return value(u32(0x20000000u | 0x18000185u));
    if (r.index == 0x1801) return value(u32(0x285));
    if (r.index == 0x1A00 || r.index == 0x1A01) return value({0});
    return none();
  });
  ASSERT_EQ(p.info().tpdos.size(), 1u);
  EXPECT_EQ(p.info().tpdos[0].cob_id, 0x285);
}

TEST(DiscoveryPlanOrder, RemapAfterDoneReadsOnlyTheTpdos) {
  DiscoveryPlan p;
  auto answer = [](SdoRead r) -> od::SdoResult {
    if (r.index == 0x1018 && r.sub == 2) return value(u32(0x53544550));
    if (r.index == 0x1018) return value(u32(0));
    if (r.index == 0x2001) return value(od::encode<uint16_t>(0));
    if (r.index == 0x1800) return value(u32(0x185));
    if (r.index == 0x1A00) return value({0});
    return none();
  };
  run(p, answer);
  ASSERT_TRUE(p.finished());
  p.restart_tpdos();
  EXPECT_FALSE(p.finished());
  EXPECT_FALSE(p.mapping_read());
  const auto reads = run(p, answer);
  for (const SdoRead& r : reads)
    EXPECT_TRUE(r.index >= 0x1800 && r.index < 0x1C00) << std::hex << r.index;
  EXPECT_EQ(p.info().axes, 1) << "identity and axes kept";
}

}  // namespace
}  // namespace stepnode::bridge
