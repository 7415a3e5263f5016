// Test harness for the node in virtual time: the whole device as node/device.* assembles
// it (the CiA 301 slave, the axes on the simulated machine, the HP channels) with a fresh
// state directory, a recorder of every frame it sends, and a master's view of the bus (NMT
// commands, SYNC, hand-built SDO expedited transfers, the PDO mapping procedure).
#pragma once
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "node/canopen_node.hpp"
#include "node/device.hpp"
#include "od/sdo_client.hpp"
#include "od/value_codec.hpp"

namespace stepnode::node::test {

using od::CanFrame;

constexpr uint32_t kNoAnswer = 0xFFFFFFFF;

// A fresh, empty directory; removed by the destructor.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "stepnode-nt-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::permissions(path, std::filesystem::perms::owner_all,
                                 std::filesystem::perm_options::add, ec);
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

class NodeHarness : public ::testing::Test {
 protected:
  static constexpr uint8_t kId = 5;
  static constexpr uint32_t kSdoRx = 0x600 + kId;
  static constexpr uint32_t kSdoTx = 0x580 + kId;
  static constexpr uint32_t kHeartbeatId = 0x700 + kId;
  static constexpr uint32_t kEmcyId = 0x80 + kId;

  void SetUp() override { make(); }
  void TearDown() override { stop(); }

  // A new node (a new process) on the same state directory, started at `t`.
  void make(unsigned axes = 1, const Device::ObjectDefaults& defaults = {}) {
    NodeOptions o;
    o.device.node_id = kId;
    o.layout.axes = axes;
    o.state_dir = dir.path;
    make(o, defaults);  // all profiles
  }
  // A device with the profiles and axes of `layout`.
  void make(const DeviceLayout& layout) {
    NodeOptions o;
    o.device.node_id = kId;
    o.layout = layout;
    o.state_dir = dir.path;
    make(o);
  }
  void make(const NodeOptions& o, const Device::ObjectDefaults& defaults = {}) {
    stop();
    device = std::make_unique<Device>(o, defaults, [this](const CanFrame& f) {
      sent.push_back(f);
      sent_at.push_back(t);
    });
    node = &device->canopen();
    sent.clear();
    sent_at.clear();
    device->start(t);
  }
  // The process ends.
  void stop() {
    node = nullptr;
    device.reset();
  }

  od::Dictionary& od() { return node->dictionary(); }

  void frame(const CanFrame& f) { device->on_frame(f, t); }
  void nmt(uint8_t cs, uint8_t target = kId) { frame(CanFrame(0, {cs, target})); }
  void sync() { frame(CanFrame(0x80, {})); }
  void sync(uint8_t counter) { frame(CanFrame(0x80, {counter})); }

  // Advances virtual time by `us` in ticks of `step_us`.
  void advance_us(uint64_t us, uint64_t step_us = 1000) {
    uint64_t end = t + us;
    while (t < end) {
      t = std::min(end, t + step_us);
      device->on_tick(t);
    }
  }
  void advance_ms(uint64_t ms, uint64_t step_us = 1000) { advance_us(ms * 1000, step_us); }

  // Expedited SDO download built by hand (0x23/0x27/0x2B/0x2F idx_lo idx_hi sub data).
  // Returns 0 for a 0x60 confirmation, the abort code for 0x80, kNoAnswer for silence.
  uint32_t sdo_write(uint16_t index, uint8_t sub, uint32_t value, uint8_t size = 4) {
    size_t before = sent.size();
    uint8_t cs = static_cast<uint8_t>(0x23 | ((4 - size) << 2));
    frame(CanFrame(kSdoRx, {cs, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), sub,
                            static_cast<uint8_t>(value), static_cast<uint8_t>(value >> 8),
                            static_cast<uint8_t>(value >> 16), static_cast<uint8_t>(value >> 24)}));
    return sdo_answer(before, index, sub, 0x60).first;
  }
  // Expedited SDO upload. Returns the value, or nullopt (then *abort is set).
  std::optional<uint32_t> sdo_read(uint16_t index, uint8_t sub, uint32_t* abort = nullptr) {
    size_t before = sent.size();
    frame(CanFrame(kSdoRx, {0x40, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8),
                            sub, 0, 0, 0, 0}));
    auto [code, value] = sdo_answer(before, index, sub, 0x40);
    if (abort) *abort = code;
    if (code != 0) return std::nullopt;
    return value;
  }

  // One SDO transfer of any size through the od client (expedited, or segmented for the
  // REAL64 and longer values), the node answering each request at once.
  od::SdoResult transfer(bool download, uint16_t index, uint8_t sub, od::Bytes data = {}) {
    od::SdoClient client(kSdoRx, kSdoTx);
    std::vector<CanFrame> out;
    if (download)
      client.start_download(index, sub, std::move(data), od::SdoClient::Mode::Auto, t, out);
    else client.start_upload(index, sub, od::SdoClient::Mode::Auto, t, out);
    for (int guard = 0; guard < 100000 && !client.done();
         ++guard) {  // the EDS: thousands of segments
      std::vector<CanFrame> requests;
      requests.swap(out);
      for (const CanFrame& f : requests) {
        size_t before = sent.size();
        frame(f);
        for (size_t i = before; i < sent.size(); ++i) client.on_frame(sent[i], t, out);
      }
    }
    EXPECT_TRUE(client.done());
    return client.result();
  }
  // A REAL64 download (the HP objects' values); the abort code, 0 for success.
  uint32_t put(uint16_t index, uint8_t sub, double v) {
    return static_cast<uint32_t>(transfer(true, index, sub, od::encode<double>(v)).abort);
  }
  template <class T>
  uint32_t put_int(uint16_t index, uint8_t sub, T v) {
    return static_cast<uint32_t>(transfer(true, index, sub, od::encode<T>(v)).abort);
  }
  double get(uint16_t index, uint8_t sub = 0) {
    od::SdoResult r = transfer(false, index, sub);
    EXPECT_TRUE(r.ok());
    return od::decode<double>(r.data);
  }

  // The CiA 301 dynamic mapping procedure (7.5.2.36), over SDO: make the PDO invalid,
  // set the count to 0, write the entries, set the count, set the communication
  // parameters, make the PDO valid again.
  void map_pdo(bool transmit, unsigned n, std::initializer_list<uint32_t> words, uint8_t type,
               uint16_t inhibit_100us = 0, uint16_t event_ms = 0) {
    uint16_t comm = static_cast<uint16_t>((transmit ? 0x1800 : 0x1400) + n);
    uint16_t map = static_cast<uint16_t>(comm + 0x200);
    uint32_t can_id = (transmit ? 0x180 : 0x200) + 0x100 * n + kId;
    uint32_t no_rtr = transmit ? 0x40000000u : 0;
    ASSERT_EQ(sdo_write(comm, 1, 0x80000000u | no_rtr | can_id), 0u) << "destroy PDO";
    ASSERT_EQ(sdo_write(map, 0, 0, 1), 0u) << "disable mapping";
    uint8_t count = 0;
    for (uint32_t w : words) {
      ++count;
      ASSERT_EQ(sdo_write(map, count, w), 0u) << "mapping entry " << int(count);
    }
    ASSERT_EQ(sdo_write(map, 0, count, 1), 0u) << "enable mapping";
    ASSERT_EQ(sdo_write(comm, 2, type, 1), 0u) << "transmission type";
    if (transmit) {
      ASSERT_EQ(sdo_write(comm, 3, inhibit_100us, 2), 0u) << "inhibit time";
    }
    ASSERT_EQ(sdo_write(comm, 5, event_ms, 2), 0u) << "event timer";
    ASSERT_EQ(sdo_write(comm, 1, no_rtr | can_id), 0u) << "create PDO";
  }
  void map_tpdo(unsigned n, std::initializer_list<uint32_t> words, uint8_t type,
                uint16_t inhibit_100us = 0, uint16_t event_ms = 0) {
    map_pdo(true, n, words, type, inhibit_100us, event_ms);
  }
  void map_rpdo(unsigned n, std::initializer_list<uint32_t> words, uint8_t type,
                uint16_t event_ms = 0) {
    map_pdo(false, n, words, type, 0, event_ms);
  }

  std::vector<CanFrame> with_id(uint32_t id, size_t from = 0) const {
    std::vector<CanFrame> out;
    for (size_t i = from; i < sent.size(); ++i)
      if (sent[i].id == id) out.push_back(sent[i]);
    return out;
  }
  // When each frame with this id was sent (virtual us).
  std::vector<uint64_t> times_of(uint32_t id, size_t from = 0) const {
    std::vector<uint64_t> out;
    for (size_t i = from; i < sent.size(); ++i)
      if (sent[i].id == id) out.push_back(sent_at[i]);
    return out;
  }
  void clear_sent() {
    sent.clear();
    sent_at.clear();
  }
  std::vector<CanFrame> emcys(size_t from = 0) const { return with_id(kEmcyId, from); }
  static uint16_t emcy_code(const CanFrame& f) { return od::get_u16(f.data.data()); }

  TempDir dir;
  uint64_t t = 1'000'000;
  std::vector<CanFrame> sent;
  std::vector<uint64_t> sent_at;  // virtual time of each frame in `sent`
  std::unique_ptr<Device> device;
  CanopenNode* node = nullptr;  // the device's CiA 301 slave

 private:
  // Finds the server's answer to (index, sub) among the frames sent since `before`.
  std::pair<uint32_t, uint32_t> sdo_answer(size_t before, uint16_t index, uint8_t sub,
                                           uint8_t ok_scs) {
    for (size_t i = before; i < sent.size(); ++i) {
      const CanFrame& f = sent[i];
      if (f.id != kSdoTx) continue;
      EXPECT_EQ(f.dlc, 8) << "SDO response DLC";
      EXPECT_EQ(od::get_u16(&f.data[1]), index);
      EXPECT_EQ(f.data[3], sub);
      if (f.data[0] == 0x80) return {od::get_u32(&f.data[4]), 0};
      if ((f.data[0] & 0xE0) == ok_scs) {
        uint32_t v = od::get_u32(&f.data[4]);
        if (ok_scs == 0x40 && (f.data[0] & 0x03) == 0x03) {  // expedited, size indicated
          unsigned n = 4 - ((f.data[0] >> 2) & 3);
          if (n < 4) v &= (1u << (8 * n)) - 1;
        }
        return {0, v};
      }
      ADD_FAILURE() << "unexpected SDO response 0x" << std::hex << int(f.data[0]);
      return {kNoAnswer, 0};
    }
    return {kNoAnswer, 0};
  }
};

// With the axis's default TPDOs made invalid, so only what a test maps is on the bus.
class PdoHarness : public NodeHarness {
 protected:
  static constexpr uint32_t kReg1 = 0x2F000120, kReg2 = 0x2F000220, kReg3 = 0x2F000320;
  static constexpr uint32_t kTpdo1 = 0x185, kTpdo2 = 0x285, kRpdo1 = 0x205;
  void SetUp() override {
    NodeHarness::SetUp();
    for (unsigned n = 0; n < 4; ++n) {
      uint16_t tc = static_cast<uint16_t>(0x1800 + n);
      ASSERT_EQ(sdo_write(tc, 1, od().get<uint32_t>(tc, 1) | 0x80000000u), 0u);
    }
  }
  static CanFrame u32_frame(uint32_t id, uint32_t v) {
    return CanFrame(id, {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8),
                         static_cast<uint8_t>(v >> 16), static_cast<uint8_t>(v >> 24)});
  }
};

}  // namespace stepnode::node::test
