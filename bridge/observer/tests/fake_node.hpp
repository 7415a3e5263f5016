// A CANopen node for the observer's tests: a real stepnode dictionary (or a third-party
// device's small one) behind od's SDO server, plus builders for the frames a node sends
// (boot-up, heartbeat, TPDO packed by its current mapping, EMCY). Knobs make its SDO
// server misbehave (silent, aborting) for the retry tests.
#pragma once
#include <cstdint>
#include <vector>

#include "node/profiles/horner/objects.hpp"
#include "od/can_frame.hpp"
#include "od/communication_objects.hpp"
#include "od/dictionary.hpp"
#include "od/pdo_mapping.hpp"
#include "od/sdo_server.hpp"

namespace stepnode::bridge::test {

struct FakeNodeOptions {
  uint8_t id = 5;
  unsigned axes = 3;
  bool stepnode = true;     // false: a third-party device (identity, name, no axes)
  double pscale = 0;        // >0: 0x2n11 PSCALE present with this value (all axes)
  bool hp_objects = false;  // 0x2n18 DONE? I8 and 0x2n19 HP error U8, mappable
  // The stepnode's profiles (node/device_objects.hpp DeviceLayout). {.horner = false,
  // .hp = false, .user = false, .cia402 = true} is a CiA 402 only device: no 0x2n00
  // objects, TPDO1/2 {6041h, 6061h} / {6064h, 606Ch} of axis 1 at 0x180/0x280 + id.
  bool horner = true, hp = true, user = true, cia402 = false;
  uint32_t stepnode_product_code = 0x53544550;  // another: a CiA 402 drive of another vendor
  std::string name = "stepnode";
  // Third-party device only:
  uint32_t product_code = 0x00001234;
  bool has_2001 = true;  // its own (non-axis) object at 0x2001
  // A second SDO server channel (as 0x1201 configured): client->server, server->client.
  uint32_t channel_rx = 0, channel_tx = 0;
};

class FakeNode {
 public:
  explicit FakeNode(FakeNodeOptions options = {});

  uint8_t id() const { return options_.id; }
  od::Dictionary& dictionary() { return od_; }

  // A request frame from the bus (only 0x600+id and channel_rx are looked at); responses
  // go to `out`.
  void on_frame(const od::CanFrame& frame, uint64_t now_us, std::vector<od::CanFrame>& out);

  od::CanFrame boot_up() const { return od::CanFrame(0x700 + id(), {0x00}); }
  od::CanFrame heartbeat(uint8_t state = 0x05) const { return od::CanFrame(0x700 + id(), {state}); }
  // TPDO k (0-based) as the node would send it now, by its current COB-ID and mapping.
  od::CanFrame tpdo(unsigned k);
  od::CanFrame emcy(uint16_t code, uint8_t reg, std::array<uint8_t, 5> m) const;

  // Axis values (axis 0-based) the next TPDOs carry.
  void set_status(unsigned axis, uint16_t bits);
  void set_position(unsigned axis, int32_t motor, int32_t encoder);
  void set_velocity(unsigned axis, int32_t velocity, uint8_t phase);
  // CiA 402 values (axis 0-based: objects at index + 0x800 * axis).
  void set_drive(unsigned axis, uint16_t statusword, int8_t mode_display);
  void set_drive_position(unsigned axis, int32_t position, int32_t velocity);
  void set_drive_fault(unsigned axis, uint16_t error_code, int32_t following_error);

  // Misbehaviour of the SDO server.
  bool silent = false;         // requests are not answered (the client times out)
  unsigned abort_next = 0;     // the next N requests get abort 0x08000000 (general error)
  unsigned requests_seen = 0;  // SDO requests received
  bool hold = false;           // responses are kept in `held` until the test releases them
  std::vector<od::CanFrame> held;

 private:
  FakeNodeOptions options_;
  od::Dictionary od_;
  od::SdoServer server_;
  od::SdoServer channel_server_;  // its own transfer state, as on a real node
};

}  // namespace stepnode::bridge::test
