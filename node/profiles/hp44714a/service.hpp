// The HP 44714A profile in the node: connects the channels (node/motion/hp_channel.*) to
// their objects (node/profiles/hp44714a/objects.*): a write is the manual's command, acted on at
// once; a refused command is answered with an SDO abort (settings conflict 0x06040043, HP error
// 0x08000022), its number stays in 0x2n19 / 0x2n1A and an error number also goes out as EMCY 0xFF00
// + n. DONE?, the error number and the interrupt event word are published after every advance (TPDO
// 4n+4 carries them); a SYNC is TRIG SYS; channel 0's trigger is TRIG CHAN0's.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "node/axis_bank.hpp"
#include "node/emcy.hpp"
#include "node/motion/hp_channel.hpp"
#include "node/profile.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class HpService final : public Profile {
 public:
  HpService(od::Dictionary& dictionary, AxisBank& axes, EmcyProducer& emcy);

  // The channels' timed work (DELAY, triggers, the end of a move) up to `now_us`.
  void advance(uint64_t now_us) override;
  void publish() override;
  // A channel's own timed work (a DELAY, a pulse train, reaching a SUSTAIN velocity,
  // STANDBY AUTO's power-off after the motion) is kept inside the channel, so while any
  // of it may be due this is the conservative poll; an idle channel needs nothing.
  uint64_t next_advance_us(uint64_t now_us) override;
  // Power-up / NMT reset node, after the axes: the channels' power-on state, then their
  // stored settings.
  void power_up(uint64_t now_us) override;
  // A SYNC was received (or produced) at `frame_us` (<= now_us; its arrival on the bus):
  // TRIG SYS. The armed channels are idle, so a start a little in the past is exact.
  void sync(uint64_t now_us, uint64_t frame_us) override;

  motion::hp::Channel& channel(unsigned a) { return *channels_.at(a); }

 private:
  void install_hooks(unsigned a);
  void install_command_hooks(unsigned a);
  void install_output_hooks(unsigned a);
  void install_counter_hooks(unsigned a);
  // A reaction on axis a's object `offset`, sub `sub`, publishing the channel after it.
  void hook(unsigned a, uint16_t offset, uint8_t sub,
            std::function<od::SdoAbort(std::span<const uint8_t>)> f);
  // The hook of a command that only sets a parameter: error 89 while a MOVE or SUSTAIN
  // without NOWAIT runs (hp::Channel::setting_command), else `apply` and accepted.
  void setting_hook(unsigned a, uint16_t offset, uint8_t sub,
                    std::function<void(std::span<const uint8_t>)> apply);
  void apply_stored(unsigned a, motion::Tick t);
  void publish(unsigned a);
  od::SdoAbort result(unsigned a, motion::hp::Error e);
  motion::Tick now() const { return axes_.now(); }

  od::Dictionary& dictionary_;
  AxisBank& axes_;
  EmcyProducer& emcy_;
  std::vector<std::unique_ptr<motion::hp::Channel>> channels_;
};

}  // namespace stepnode::node
