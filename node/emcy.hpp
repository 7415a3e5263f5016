// EMCY producer (CiA 301 7.2.7): active errors, the error register 0x1001, the history in
// 0x1003 and the inhibit time 0x1015.
#pragma once
#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>

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

class EmcyProducer {
 public:
  using Send = std::function<void(const od::CanFrame&)>;
  EmcyProducer(od::Dictionary& dictionary, Send send);

  // Raises an error condition (and sends the EMCY). A condition already active is not
  // sent again. `register_bits` are OR-ed into 0x1001 while it is active.
  void raise(uint16_t code, uint8_t register_bits, std::array<uint8_t, 5> manufacturer = {},
             uint64_t now_us = 0);
  // An event that is reported but leaves nothing active (e.g. PDO length error).
  void report(uint16_t code, uint8_t register_bits, std::array<uint8_t, 5> manufacturer = {},
              uint64_t now_us = 0);
  // Clears a condition; when none is left active, EMCY 0x0000 ("error reset") goes out.
  void clear(uint16_t code, uint64_t now_us = 0);
  bool active(uint16_t code) const { return active_.contains(code); }
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

 private:
  void enqueue(uint16_t code, std::array<uint8_t, 5> manufacturer, uint64_t now_us);
  void push_history(uint16_t code, std::array<uint8_t, 5> manufacturer);
  void update_register();

  od::Dictionary& dictionary_;
  Send send_;
  std::map<uint16_t, uint8_t> active_;  // code -> register bits
  std::deque<od::CanFrame> pending_;
  uint64_t last_sent_us_ = 0;
  bool sent_any_ = false;
  bool enabled_ = false;
};

}  // namespace stepnode::node
