// EMCY producer (CiA 301 7.2.7): active errors, the error register 0x1001, the history in
// 0x1003 and the inhibit time 0x1015.
#pragma once
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <utility>

#include "node/deadline.hpp"
#include "od/can_frame.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

// Error register bits (CiA 301 7.5.2.2).
namespace error_bits {
constexpr uint8_t kGeneric = 0x01;
constexpr uint8_t kCurrent = 0x02;
constexpr uint8_t kVoltage = 0x04;
constexpr uint8_t kTemperature = 0x08;
constexpr uint8_t kCommunication = 0x10;
constexpr uint8_t kProfile = 0x20;
constexpr uint8_t kManufacturer = 0x80;
}  // namespace error_bits

// Emergency error codes this device raises (CiA 301 table 21).
namespace emcy_code {
constexpr uint16_t kNoError = 0x0000;
constexpr uint16_t kDataStorage = 0x5530;  // stored parameters damaged or refused
constexpr uint16_t kSoftware = 0x6100;     // internal software: a configured value refused
constexpr uint16_t kCommunication =
    0x8100;  // communication, generic: another device has our node-ID
constexpr uint16_t kCanOverrun = 0x8110;
constexpr uint16_t kCanErrorPassive = 0x8120;
constexpr uint16_t kHeartbeatError = 0x8130;
constexpr uint16_t kRecoveredFromBusOff = 0x8140;
constexpr uint16_t kPdoLength = 0x8210;  // PDO not processed: length error
constexpr uint16_t kPdoLengthExceeded = 0x8220;
constexpr uint16_t kRpdoTimeout = 0x8250;
constexpr uint16_t kSyncLength = 0x8240;  // unexpected SYNC data length
}  // namespace emcy_code

// Who raised a condition. One code may stand for errors of several sources (0x8130: a lost
// heartbeat, and the fault 6007h makes of it in each CiA 402 drive), each ended by its own;
// EMCY 0x0000 goes out when none is left (found in review: the heartbeat's return reset the
// error of a drive still in Fault).
namespace emcy_source {
constexpr uint16_t kCommunication = 0;  // the CiA 301 services: they end at reset communication
constexpr uint16_t kBus = 1;            // the CAN controller's state: it outlives that reset
constexpr uint16_t kAxis = 0x100;       // + the axis index: the application's, which does too
}  // namespace emcy_source

class EmcyProducer {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  EmcyProducer(od::Dictionary& dictionary, Send send);

  // Raises an error condition (and sends the EMCY). A condition already active is not
  // sent again. `register_bits` are OR-ed into 0x1001 while it is active.
  void raise(uint16_t code, uint8_t register_bits, std::array<uint8_t, 5> manufacturer = {},
             uint64_t now_us = 0, uint16_t source = emcy_source::kCommunication);
  // An event that is reported but leaves nothing active (e.g. PDO length error).
  void report(uint16_t code, uint8_t register_bits, std::array<uint8_t, 5> manufacturer = {},
              uint64_t now_us = 0);
  // Clears a condition; when none is left active, EMCY 0x0000 ("error reset") goes out.
  void clear(uint16_t code, uint64_t now_us = 0, uint16_t source = emcy_source::kCommunication);
  // Whether the code is active, from any source.
  bool active(uint16_t code) const;
  uint8_t error_register() const;

  // Sending is allowed only in pre-operational and operational; queued messages wait.
  void set_enabled(bool enabled) { enabled_ = enabled; }
  // Sends queued messages whose inhibit time has passed.
  void on_tick(uint64_t now_us);
  // A queued message waits for the inhibit time 0x1015 (x 100 us) after the last one sent;
  // kNoDeadline with nothing queued or while sending is not allowed (enabling is a state
  // change, after which the node runs its services).
  uint64_t next_deadline_us(uint64_t now_us) const;
  // Reset node: forget everything (history included).
  void reset();
  // Reset communication: the CiA 301 services' conditions end with their services (no EMCY);
  // the bus's and the application's are still there and are announced again once EMCY may
  // be sent (0x1003 was put back with the other communication objects). They were forgotten,
  // 0x1001 reading 0 with an axis still in error: found in review.
  void reset_communication(uint64_t now_us);

 private:
  void enqueue(uint16_t code, std::array<uint8_t, 5> manufacturer, uint64_t now_us);
  void push_history(uint16_t code, std::array<uint8_t, 5> manufacturer);
  void update_register();

  od::Dictionary& dictionary_;
  Send send_;
  struct Condition {
    uint8_t register_bits = 0;
    std::array<uint8_t, 5> manufacturer{};
  };
  std::map<std::pair<uint16_t, uint16_t>, Condition> active_;  // (code, source)
  std::deque<od::CanFrame> pending_;
  uint64_t last_sent_us_ = 0;
  bool sent_any_ = false;
  bool enabled_ = false;
};

}  // namespace stepnode::node
