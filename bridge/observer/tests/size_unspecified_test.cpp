// Another vendor's drive that answers expedited uploads without the size (e = 1, s = 0):
// CiA 301 7.2.4.3.6 leaves the size to the object's data type, so the bridge reads each
// value by its type (found in review: 1A00h:0, an UNSIGNED8 sent as four bytes, was taken
// as no mapping at all, and 6041h as absent).
#include <gtest/gtest.h>

#include <map>
#include <optional>
#include <utility>

#include "test_bus.hpp"

namespace stepnode::bridge::test {
namespace {

// A CiA 402 drive (1000h 0x00020192) of another vendor, its objects answered by hand.
struct OtherVendorsDrive {
  uint8_t id = 9;
  bool size_indicated = false;
  struct Value {
    uint32_t v;
    uint8_t size;
  };
  std::map<std::pair<uint16_t, uint8_t>, Value> objects{
      {{0x1017, 0}, {100, 2}},         {{0x1000, 0}, {0x00020192, 4}},
      {{0x1018, 1}, {0xAB, 4}},        {{0x1018, 2}, {0x1234, 4}},
      {{0x1018, 3}, {1, 4}},           {{0x1018, 4}, {77, 4}},
      {{0x1800, 1}, {0x40000189u, 4}}, {{0x1A00, 0}, {2, 1}},
      {{0x1A00, 1}, {0x60410010, 4}},  // statusword
      {{0x1A00, 2}, {0x60610008, 4}},  // modes of operation display
      {{0x6041, 0}, {0x0250, 2}},      // switch on disabled
      {{0x6061, 0}, {1, 1}},           {{0x6064, 0}, {1000, 4}},
      {{0x606C, 0}, {0, 4}},           {{0x60F4, 0}, {0, 4}},
      {{0x603F, 0}, {0, 2}},
  };
  std::optional<od::CanFrame> answer(const od::CanFrame& req) const {
    if (req.id != 0x600u + id || req.dlc != 8 || req.data[0] != 0x40) return std::nullopt;
    const uint8_t sub = req.data[3];
    od::CanFrame r(0x580 + id, {0, req.data[1], req.data[2], sub, 0, 0, 0, 0});
    const auto it = objects.find({od::get_u16(&req.data[1]), sub});
    if (it == objects.end()) {  // abort 0x06020000: no object
      r.data[0] = 0x80;
      r.data[6] = 0x02;
      r.data[7] = 0x06;
      return r;
    }
    const Value& val = it->second;
    // e = 1 with s = 1 and n = 4 - size, or s = 0 and the unused bytes left as they are.
    r.data[0] = size_indicated ? static_cast<uint8_t>(0x43 | ((4 - val.size) << 2)) : 0x42;
    for (unsigned i = 0; i < 4; ++i) r.data[4 + i] = 0xEE;
    for (unsigned i = 0; i < val.size; ++i) r.data[4 + i] = static_cast<uint8_t>(val.v >> (8 * i));
    return r;
  }
};

void discover(TestBus& bus, const OtherVendorsDrive& drive) {
  bus.send(od::CanFrame(0x700u + drive.id, {0x00}));  // boot-up
  size_t served = 0;
  for (int round = 0; round < 2000 && served < bus.observer_sent.size(); ++round) {
    const od::CanFrame req = bus.observer_sent[served++];
    if (auto a = drive.answer(req)) bus.send(*a);
  }
}

void decodes_the_drive(bool size_indicated) {
  TestBus bus;
  OtherVendorsDrive drive;
  drive.size_indicated = size_indicated;
  discover(bus, drive);
  const NodeHealthSample h = bus.observer.node_health(9, bus.now_us);
  ASSERT_TRUE(h.discovered);
  EXPECT_EQ(h.vendor_id, 0xABu);
  EXPECT_EQ(h.serial, 77u);
  // The snapshot read 6041h (UNSIGNED16) and 6061h (INTEGER8).
  ASSERT_FALSE(bus.sink.drives.empty());
  EXPECT_TRUE(bus.sink.drives.back().statusword_known);
  EXPECT_EQ(bus.sink.drives.back().statusword, 0x0250);
  // TPDO 1 by its mapping: 1A00h:0 = 2 entries.
  bus.send(od::CanFrame(0x709, {0x05}));
  bus.sink.drives.clear();
  bus.send(od::CanFrame(0x189, {0x37, 0x02, 0x01}));  // 6041h = 0x0237, 6061h = 1
  ASSERT_FALSE(bus.sink.drives.empty());
  EXPECT_EQ(bus.sink.drives.back().statusword, 0x0237);
  EXPECT_EQ(bus.sink.drives.back().mode_display, 1);
}

TEST(SizeUnspecified, ADriveAnsweringWithoutTheSizeIsDecodedByTheObjectsTypes) {
  decodes_the_drive(false);
}

TEST(SizeUnspecified, TheSameDriveAnsweringWithTheSize) { decodes_the_drive(true); }

}  // namespace
}  // namespace stepnode::bridge::test
