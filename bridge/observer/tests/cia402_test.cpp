// CiA 402 axes on the bridge: the statusword's state coding (checked against the drive's
// own table), discovery of a CiA 402 only stepnode (no 0x2n00 objects: found by 1000h and
// 67FFh + 0x800 * a), of another vendor's drive, and of a device with both profiles;
// TPDO frames written from the standard into DriveStatus, the objects at any axis offset,
// the error code read again when a fault comes or goes.
#include <gtest/gtest.h>

#include "bridge/observer/discovery_plan.hpp"
#include "node/profiles/cia402/drive_state.hpp"
#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

FakeNodeOptions cia402_only(uint8_t id, unsigned axes) {
  return FakeNodeOptions{
      .id = id, .axes = axes, .horner = false, .hp = false, .user = false, .cia402 = true};
}

// Requests (upload initiate) the observer sent, by index.
std::vector<uint16_t> uploads(const TestBus& bus) {
  std::vector<uint16_t> out;
  for (const od::CanFrame& f : bus.observer_sent)
    if (f.data[0] == 0x40) out.push_back(od::get_u16(&f.data[1]));
  return out;
}
size_t count(const std::vector<uint16_t>& v, uint16_t index) {
  return static_cast<size_t>(std::count(v.begin(), v.end(), index));
}

void set_mapping(FakeNode& node, unsigned k, uint32_t cob, std::vector<uint32_t> words) {
  auto& d = node.dictionary();
  const auto comm = static_cast<uint16_t>(0x1800 + k), map = static_cast<uint16_t>(0x1A00 + k);
  uint8_t i = 0;
  for (uint32_t w : words) d.put<uint32_t>(map, ++i, w);
  d.put<uint8_t>(map, 0, i);
  d.put<uint32_t>(comm, 1, 0x40000000u | cob);
}

TEST(DriveState, StatuswordStateCodingAsTheStandardsTable) {
  // 6041h written from the standard's table, with bits it leaves open set as a drive may.
  EXPECT_EQ(drive_state_of(0x0000), DriveState::NotReadyToSwitchOn);
  EXPECT_EQ(drive_state_of(0x0250), DriveState::SwitchOnDisabled);  // + voltage, remote
  EXPECT_EQ(drive_state_of(0x0231), DriveState::ReadyToSwitchOn);
  EXPECT_EQ(drive_state_of(0x0233), DriveState::SwitchedOn);
  EXPECT_EQ(drive_state_of(0x0637), DriveState::OperationEnabled);  // + remote, target reached
  EXPECT_EQ(drive_state_of(0x0217), DriveState::QuickStopActive);
  EXPECT_EQ(drive_state_of(0x021F), DriveState::FaultReactionActive);
  EXPECT_EQ(drive_state_of(0x0218), DriveState::Fault);
  EXPECT_EQ(drive_state_of(0x0238), DriveState::Fault) << "bit 5 is open in Fault";
  // Patterns the table does not define.
  for (uint16_t sw : {0x0009, 0x0061, 0x0063, 0x0067, 0x0048, 0x0001 | 0x0040, 0x0005})
    EXPECT_EQ(drive_state_of(sw), DriveState::Unknown) << std::hex << sw;
}

TEST(DriveState, AgreesWithTheDrivesOwnStatusword) {
  using cia402::State;
  const std::pair<State, DriveState> states[] = {
      {State::NotReadyToSwitchOn, DriveState::NotReadyToSwitchOn},
      {State::SwitchOnDisabled, DriveState::SwitchOnDisabled},
      {State::ReadyToSwitchOn, DriveState::ReadyToSwitchOn},
      {State::SwitchedOn, DriveState::SwitchedOn},
      {State::OperationEnabled, DriveState::OperationEnabled},
      {State::QuickStopActive, DriveState::QuickStopActive},
      {State::FaultReactionActive, DriveState::FaultReactionActive},
      {State::Fault, DriveState::Fault},
  };
  for (auto [node_state, bridge_state] : states) {
    const uint16_t sw = cia402::state_bits(node_state);
    EXPECT_EQ(drive_state_of(sw), bridge_state) << cia402::name(node_state);
    // The caller's bits (warning, target reached, internal limit, 12, 13, 14, 15) change nothing.
    EXPECT_EQ(drive_state_of(static_cast<uint16_t>(sw | 0xFD80)), bridge_state)
        << cia402::name(node_state);
  }
}

struct Cia402Only : ::testing::Test {
  TestBus bus;
  FakeNode node{cia402_only(5, 2)};
  void SetUp() override {
    node.set_drive(0, 0x0250, 0);  // Switch on disabled before the bridge comes
    node.set_drive_position(0, 1234, 0);
    node.set_drive_fault(0, 0, -3);
    bus.add(node);
    bus.boot(node);
    bus.run_ms(100);
    ASSERT_TRUE(bus.observer.node_health(5, bus.now_us).discovered);
  }
};

TEST_F(Cia402Only, IsDiscoveredBy67FFhWithoutHornerObjects) {
  const NodeHealthSample h = bus.observer.node_health(5, bus.now_us);
  EXPECT_TRUE(h.is_stepnode) << "the product code says so, and it has CiA 402 axes";
  EXPECT_EQ(h.axes, 2);
  EXPECT_EQ(h.sdo_failures, 0u);
  const auto reads = uploads(bus);
  EXPECT_EQ(count(reads, 0x1000), 1u);
  EXPECT_EQ(count(reads, 0x2001), 1u) << "the Horner probe is made once and finds nothing";
  for (uint16_t i : reads)
    if (i >= 0x2000 && i < 0x2800) {
      EXPECT_EQ(i, 0x2001) << std::hex << i << ": no other 0x2n00 read";
    }
  EXPECT_EQ(count(reads, 0x67FF), 1u);
  EXPECT_EQ(count(reads, 0x6FFF), 1u);
  EXPECT_EQ(count(reads, 0x77FF), 1u) << "axis 3's 67FFh: absent, the end of the probe";
  // The snapshot: statusword ... error code of both axes.
  for (uint16_t base : {0x6041, 0x6061, 0x6064, 0x606C, 0x60F4, 0x603F}) {
    EXPECT_EQ(count(reads, base), 1u) << std::hex << base;
    EXPECT_EQ(count(reads, static_cast<uint16_t>(base + 0x800)), 1u) << std::hex << base + 0x800;
  }
  // A bridge that came late publishes the idle drives at once.
  ASSERT_EQ(bus.sink.drives.size(), 2u);
  const DriveStatusSample& d = bus.sink.drives[0];
  EXPECT_EQ(d.node, 5);
  EXPECT_EQ(d.axis, 1);
  EXPECT_TRUE(d.statusword_known);
  EXPECT_EQ(d.statusword, 0x0250);
  EXPECT_EQ(d.state(), DriveState::SwitchOnDisabled);
  EXPECT_EQ(d.position_actual, 1234);
  EXPECT_EQ(d.following_error, -3);
  EXPECT_EQ(bus.sink.drives[1].axis, 2);
  EXPECT_EQ(bus.sink.drives[1].statusword, 0x0200)
      << "the table's value: Not ready to switch on, remote";
  EXPECT_TRUE(bus.sink.statuses.empty());
  EXPECT_TRUE(bus.sink.positions.empty());
}

TEST_F(Cia402Only, TpdoFramesFromTheStandardBecomeDriveStatus) {
  bus.sink.clear();
  // TPDO1 (0x180 + id) {6041h U16, 6061h I8}: 0x0637 = Operation enabled (0x27), voltage
  // enabled (bit 4), remote (bit 9), target reached (bit 10); mode 1, profile position.
  bus.send(od::CanFrame(0x185, {0x37, 0x06, 0x01}));
  ASSERT_EQ(bus.sink.drives.size(), 1u);
  DriveStatusSample d = bus.sink.drives[0];
  EXPECT_EQ(d.node, 5);
  EXPECT_EQ(d.axis, 1);
  EXPECT_EQ(d.statusword, 0x0637);
  EXPECT_EQ(d.state(), DriveState::OperationEnabled);
  EXPECT_EQ(d.mode_display, 1);
  EXPECT_EQ(d.position_actual, 1234) << "the last known value is carried";
  EXPECT_EQ(d.can_time_ns, bus.now_us * 1000);
  // TPDO2 (0x280 + id) {6064h I32, 606Ch I32}: -1000 and +2500.
  bus.send(od::CanFrame(0x285, {0x18, 0xFC, 0xFF, 0xFF, 0xC4, 0x09, 0x00, 0x00}));
  ASSERT_EQ(bus.sink.drives.size(), 2u);
  d = bus.sink.drives[1];
  EXPECT_EQ(d.position_actual, -1000);
  EXPECT_EQ(d.velocity_actual, 2500);
  EXPECT_EQ(d.statusword, 0x0637);
  // Every TPDO is published (not only changes), like AxisPosition.
  bus.send(od::CanFrame(0x185, {0x37, 0x06, 0x01}));
  EXPECT_EQ(bus.sink.drives.size(), 3u);
  // Axis 2: TPDO3 {6841h, 6861h}, TPDO4 {6864h, 686Ch}; mode -1 (manufacturer) sign-extends.
  bus.send(od::CanFrame(0x385, {0x33, 0x02, 0xFF}));
  ASSERT_EQ(bus.sink.drives.size(), 4u);
  EXPECT_EQ(bus.sink.drives[3].axis, 2);
  EXPECT_EQ(bus.sink.drives[3].state(), DriveState::SwitchedOn);
  EXPECT_EQ(bus.sink.drives[3].mode_display, -1);
  // Nothing on the Horner topics; a short TPDO is refused.
  EXPECT_TRUE(bus.sink.statuses.empty());
  EXPECT_TRUE(bus.sink.positions.empty());
  bus.send(od::CanFrame(0x285, {1, 2, 3}));
  EXPECT_EQ(bus.sink.drives.size(), 4u);
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).bad_frames, 1u);
}

TEST_F(Cia402Only, TheNodesOwnTpdosAsItPacksThem) {
  bus.sink.clear();
  node.set_drive(1, 0x0237, 8);
  node.set_drive_position(1, 777, -55);
  bus.send(node.tpdo(2));
  bus.send(node.tpdo(3));
  ASSERT_EQ(bus.sink.drives.size(), 2u);
  EXPECT_EQ(bus.sink.drives[1].axis, 2);
  EXPECT_EQ(bus.sink.drives[1].state(), DriveState::OperationEnabled);
  EXPECT_EQ(bus.sink.drives[1].mode_display, 8);
  EXPECT_EQ(bus.sink.drives[1].position_actual, 777);
  EXPECT_EQ(bus.sink.drives[1].velocity_actual, -55);
}

TEST_F(Cia402Only, AFaultsErrorCodeIsReadWhenTheFaultComesAndGoes) {
  bus.sink.clear();
  node.set_drive_fault(0, 0x8611, 250);               // following error
  bus.send(od::CanFrame(0x185, {0x18, 0x02, 0x01}));  // 0x0218: Fault
  ASSERT_GE(bus.sink.drives.size(), 1u);              // (the SDO read may already be answered)
  EXPECT_EQ(bus.sink.drives[0].state(), DriveState::Fault);
  EXPECT_EQ(bus.sink.drives[0].error_code, 0) << "603Fh is in no TPDO: not known yet";
  bus.run_ms(20);
  ASSERT_EQ(bus.sink.drives.size(), 2u) << "603Fh read over SDO, then published";
  EXPECT_EQ(bus.sink.drives[1].error_code, 0x8611);
  EXPECT_EQ(bus.sink.drives[1].state(), DriveState::Fault);
  // Still in Fault: no new read.
  bus.send(od::CanFrame(0x185, {0x18, 0x02, 0x01}));
  bus.run_ms(20);
  EXPECT_EQ(bus.sink.drives.size(), 3u);
  // The master's fault reset: the drive clears 603Fh.
  node.set_drive_fault(0, 0, 0);
  bus.send(od::CanFrame(0x185, {0x50, 0x02, 0x01}));  // Switch on disabled
  bus.run_ms(20);
  ASSERT_EQ(bus.sink.drives.size(), 5u);
  EXPECT_EQ(bus.sink.drives[4].error_code, 0);
  EXPECT_EQ(bus.sink.drives[4].state(), DriveState::SwitchOnDisabled);
  EXPECT_EQ(count(uploads(bus), 0x603F), 3u) << "snapshot, fault, reset";
  EXPECT_EQ(bus.observer.node_health(5, bus.now_us).sdo_failures, 0u);
}

TEST_F(Cia402Only, TheErrorCodeReadWaitsForAnotherMastersSdo) {
  bus.sink.clear();
  bus.master_start(5);
  bus.master_upload(0x6041, 0);  // another master polls the statusword ...
  node.set_drive_fault(0, 0x9000, 0);
  bus.send(od::CanFrame(0x185, {0x18, 0x02, 0x01}));  // ... and the drive faults
  bus.run_ms(200);
  EXPECT_EQ(bus.sink.drives.size(), 1u) << "the default channel was busy a moment ago";
  bus.run_ms(150);
  ASSERT_EQ(bus.sink.drives.size(), 2u);
  EXPECT_EQ(bus.sink.drives[1].error_code, 0x9000);
}

TEST_F(Cia402Only, LostNodeDisposesItsDrives) {
  bus.run_ms(300);  // heartbeats seen: their interval is known
  bus.beat_of(node).beating = false;
  bus.run_ms(1500);
  ASSERT_FALSE(bus.sink.disposed.empty());
  EXPECT_EQ(bus.sink.disposed.back(), (std::pair<uint8_t, uint8_t>{5, 2}));
}

TEST(Cia402Mapping, ObjectsAtAnyAxisOffsetAndFollowingErrorAndErrorCodeMapped) {
  TestBus bus;
  FakeNode node(cia402_only(6, 3));
  // TPDO5 (axis 3's PDOs start invalid): axis 3's 60F4h + 0x1000 and 603Fh, axis 2's statusword.
  set_mapping(node, 4, 0x1A6, {0x70F40020, 0x703F0010, 0x68410010});
  bus.add(node);
  bus.boot(node);
  bus.run_ms(120);
  ASSERT_TRUE(bus.observer.node_health(6, bus.now_us).discovered);
  EXPECT_EQ(bus.observer.node_health(6, bus.now_us).axes, 3);
  bus.sink.clear();
  node.set_drive_fault(2, 0x8611, -70000);
  node.set_drive(1, 0x0218, 0);
  bus.send(node.tpdo(4));
  // One DriveStatus per axis the TPDO touched (then axis 2's, when its 603Fh read is answered).
  ASSERT_GE(bus.sink.drives.size(), 2u);
  EXPECT_EQ(bus.sink.drives[0].axis, 2);
  EXPECT_EQ(bus.sink.drives[0].state(), DriveState::Fault);
  EXPECT_EQ(bus.sink.drives[1].axis, 3);
  EXPECT_EQ(bus.sink.drives[1].following_error, -70000);
  EXPECT_EQ(bus.sink.drives[1].error_code, 0x8611);
  // Axis 2's fault: its 603Fh is in no TPDO, so it is read; axis 3's is mapped.
  bus.run_ms(20);
  EXPECT_EQ(count(uploads(bus), 0x683F), 2u) << "snapshot and the fault";
  EXPECT_EQ(count(uploads(bus), 0x703F), 1u) << "snapshot only";
}

TEST(Cia402Mapping, HornerAndCia402OnOneDevice) {
  TestBus bus;
  FakeNode node({.id = 7, .axes = 2, .cia402 = true});
  // The CiA 402 PDOs come after the register block (8 PDOs) and start invalid: TPDO9 is
  // axis 1's {6041h, 6061h}; a configuration tool gives it a COB-ID.
  node.dictionary().put<uint32_t>(0x1808, 1, 0x40000000u | 0x1B7);
  bus.add(node);
  bus.boot(node);
  bus.run_ms(150);
  const NodeHealthSample h = bus.observer.node_health(7, bus.now_us);
  ASSERT_TRUE(h.discovered);
  EXPECT_TRUE(h.is_stepnode);
  EXPECT_EQ(h.axes, 2);
  bus.sink.clear();
  node.set_status(0, 0x8100);
  bus.send(node.tpdo(0));  // Horner status
  node.set_drive(0, 0x0227, 3);
  bus.send(node.tpdo(8));
  ASSERT_EQ(bus.sink.statuses.size(), 1u);
  EXPECT_EQ(bus.sink.statuses[0].status_bits, 0x8100);
  ASSERT_EQ(bus.sink.drives.size(), 1u);
  EXPECT_EQ(bus.sink.drives[0].state(), DriveState::OperationEnabled);
  EXPECT_EQ(bus.sink.drives[0].mode_display, 3);
}

TEST(Cia402Mapping, AnotherVendorsDriveIsDecodedToo) {
  TestBus bus;
  FakeNode drive({.id = 9,
                  .axes = 1,
                  .horner = false,
                  .hp = false,
                  .user = false,
                  .cia402 = true,
                  .stepnode_product_code = 0x00C0FFEE});
  bus.add(drive);
  bus.boot(drive);
  bus.run_ms(100);
  const NodeHealthSample h = bus.observer.node_health(9, bus.now_us);
  ASSERT_TRUE(h.discovered);
  EXPECT_FALSE(h.is_stepnode);
  EXPECT_EQ(h.axes, 1);
  for (uint16_t i : uploads(bus))
    EXPECT_FALSE(i >= 0x2000 && i < 0x2800) << std::hex << i << ": not a stepnode";
  bus.sink.clear();
  bus.send(od::CanFrame(0x189, {0x37, 0x06, 0x01}));
  ASSERT_EQ(bus.sink.drives.size(), 1u);
  EXPECT_EQ(bus.sink.drives[0].state(), DriveState::OperationEnabled);
}

// The plan alone: device types and 67FFh as another vendor's drive may answer them.
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
template <class F>
std::vector<SdoRead> run(DiscoveryPlan& p, F answer) {
  std::vector<SdoRead> reads;
  while (!p.finished() && reads.size() < 1000) {
    reads.push_back(p.next());
    p.on_result(answer(reads.back()));
  }
  return reads;
}

TEST(Cia402Plan, ASingleAxisDriveWithout67FFhIsOneAxis) {
  DiscoveryPlan p;
  const auto reads = run(p, [](SdoRead r) -> od::SdoResult {
    if (r.index == 0x1000) return value(od::encode<uint32_t>(0x00020192));  // a servo drive
    if (r.index == 0x1018) return value(od::encode<uint32_t>(0x77));
    if (r.index == 0x1800) return value(od::encode<uint32_t>(0x181));
    if (r.index == 0x1A00) return r.sub == 0 ? value({1}) : value(od::encode<uint32_t>(0x60410010));
    if (r.index == 0x6041) return value(od::encode<uint16_t>(0x0250));
    return none();
  });
  EXPECT_EQ(p.info().drive_axes, 1);
  EXPECT_EQ(p.info().axes, 0);
  EXPECT_FALSE(p.info().is_stepnode());
  ASSERT_EQ(p.info().tpdos.size(), 1u);
  EXPECT_TRUE(p.info().drive_snapshot[0].statusword_read);
  EXPECT_EQ(p.info().drive_snapshot[0].statusword, 0x0250);
  EXPECT_FALSE(p.info().drive_snapshot[0].error_code_read);
  for (const SdoRead& r : reads) EXPECT_NE(r.index, 0x2001);
}

TEST(Cia402Plan, AnotherProfileIsNotProbedFor67FFh) {
  DiscoveryPlan p;
  const auto reads = run(p, [](SdoRead r) -> od::SdoResult {
    if (r.index == 0x1000) return value(od::encode<uint32_t>(0x000F0191));  // CiA 401 I/O
    if (r.index == 0x1018) return value(od::encode<uint32_t>(0x77));
    if (r.index == 0x67FF) return value(od::encode<uint32_t>(0x12345678));  // means something else
    return none();
  });
  EXPECT_FALSE(p.info().has_axes());
  for (const SdoRead& r : reads) EXPECT_TRUE(r.index < 0x1800) << std::hex << r.index;
}

}  // namespace
}  // namespace stepnode::bridge::test
