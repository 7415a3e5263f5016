// Another device with this node's node-ID. CiA 301 gives each node-ID to one device and
// defines no check; this is the product's. A CAN controller does not receive its own
// frames (the node's socket does not ask for them), so a frame on a COB-ID that only this
// node produces came from another device: a boot-up or heartbeat on 0x700+id (a remote
// frame there is a node guarding request, not a conflict), an SDO server answer on
// 0x580+id, or an EMCY on this node's EMCY COB-ID (0x1014).
//
// Who keeps the node-ID: the device that had it first. Within the claim period after its
// own boot-up a node that hears another yields (gives the node-ID up and waits for an LSS
// master, as a node without one); later it keeps it, reports the conflict, and answers a
// boot-up with its heartbeat at once, so that the newcomer hears it while it still yields.
//
// Optionally (NodeOptions::boot_listen_us, `boot_listen_ms` in the config) the node listens
// before its first boot-up: a device heard with its node-ID in that time is a refusal, and
// the node never sends a frame with the node-ID (no boot-up a master could take for the
// other device's reboot). CiA 301 sets no time limit on initialisation, so the delay is
// allowed; it only moves the boot-up later.
#pragma once
#include <cstdint>
#include <optional>

#include "od/can_frame.hpp"

namespace stepnode::node {

class NodeIdConflict {
 public:
  static constexpr uint64_t kClaimPeriodUs = 2'000'000;

  // Refuse: heard before this node's boot-up (it listened); Yield: within the claim period.
  enum class Action { Keep, Yield, Refuse };
  struct Finding {
    Action action = Action::Keep;
    uint32_t cob_id = 0;
    bool boot_up = false;  // the other device just booted
  };

  // Before the first boot-up: listen for `duration_us` from now; nothing is sent meanwhile.
  void listen(uint8_t node_id, uint64_t now_us, uint64_t duration_us);
  bool listening() const { return listen_end_us_ != 0; }
  uint64_t listen_end_us() const { return listen_end_us_; }  // valid while listening()
  // This node sent its boot-up: the listening (if any) ends, the claim period starts.
  void booted(uint8_t node_id, uint64_t now_us);
  // The node gave its node-ID up (or was refused it): no frame is a conflict until the next
  // boot-up.
  void forget();
  // A frame from the bus; `emcy_cob_id` is 0x1014 as it is now.
  std::optional<Finding> on_frame(const od::CanFrame& frame, uint32_t emcy_cob_id,
                                  uint64_t now_us) const;

 private:
  uint8_t node_id_ = 0;  // 0: not booted and not listening
  uint64_t booted_us_ = 0;
  uint64_t listen_end_us_ = 0;  // 0: not listening
};

}  // namespace stepnode::node
