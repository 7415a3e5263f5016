// The CiA 402 profile in the node: one cia402::Drive per axis on the axis' motion core,
// connected to its objects (node/profiles/cia402/objects.*). 6040h acts at once (after the
// whole RPDO is stored, so a target mapped with it is current); 6060h, the targets, the
// profile, the option codes and the factor group are taken when written. The statusword,
// mode display, positions, velocity, digital inputs and error code are published after
// every advance; a fault goes out as EMCY with its 603Fh code and is cleared (EMCY 0000h
// when nothing else is active) by the fault reset. A lost master is 6007h's reaction.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "node/axis_bank.hpp"
#include "node/emcy.hpp"
#include "node/profile.hpp"
#include "node/profiles/cia402/drive.hpp"
#include "node/profiles/cia402/user_units.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

class Cia402Service final : public Profile {
 public:
  Cia402Service(od::Dictionary& dictionary, AxisBank& axes, EmcyProducer& emcy);

  void configure(uint64_t now_us) override;
  void power_up(uint64_t now_us) override;
  void publish() override;
  // A drive that may move (operation enabled, a quick stop or fault reaction running) has
  // timed work inside the drive (cyclic interpolation, following error time-out): the
  // conservative poll; any other state waits for a write.
  uint64_t next_advance_us(uint64_t now_us) override;
  void master_lost(uint64_t now_us) override;
  void master_back(uint64_t now_us) override;
  // CSP, CSV, IP: the set-points of this cycle take effect (the SYNC's arrival times the cycle).
  void sync(uint64_t now_us, uint64_t frame_us) override;

  cia402::Drive& drive(unsigned a) { return *drives_.at(a); }

 private:
  void install_hooks(unsigned a);
  void load_parameters(unsigned a);
  void load_options(unsigned a);
  void load_targets(unsigned a);
  void publish(unsigned a);
  void report_fault(unsigned a);

  od::Dictionary& dictionary_;
  AxisBank& axes_;
  EmcyProducer& emcy_;
  std::vector<std::unique_ptr<cia402::Drive>> drives_;
  std::vector<cia402::UserUnits> units_;
  std::vector<uint16_t> reported_;  // the 603Fh code sent as EMCY, per axis (0: none)
};

}  // namespace stepnode::node
