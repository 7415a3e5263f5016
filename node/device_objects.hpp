// The objects of a stepnode device as configured: the CiA 301 communication objects
// (od/communication_objects.*), the node's diagnostics, and the tables of the profiles
// the device has (node/profiles/*). Pure tables: the node builds its dictionary with it,
// and so do stepctl (names and types of every object) and the tests.
#pragma once
#include <cstdint>
#include <string>

#include "od/communication_objects.hpp"
#include "od/dictionary.hpp"

namespace stepnode::node {

constexpr unsigned kMaxAxes = 8;

// Which profiles a device has and how many axes they drive. A profile is the objects of
// one folder of node/profiles and, in the node, the service that reacts to them.
struct DeviceLayout {
  unsigned axes = 3;  // 1..kMaxAxes
  // SPM30 3-axis models: one register set (axis 1) multiplexes 3 motors, chosen with
  // %Q1..%Q3. Then axes = 1 and the simulated machine has 3 motors.
  bool spm30_multiplexed = false;
  bool horner = true;   // the Horner register set (0x2n00-0x2n0A)
  bool hp = true;       // the HP 44714A channels (0x2n10-0x2n1E)
  bool user = true;     // the user objects (0x2F00, 0x2F01)
  bool cia402 = false;  // the CiA 402 drive (0x6000 + 0x800 per axis)
  // How far ahead of its time a step is given to the back end's step port (0: as it falls
  // due). The simulated machine reproduces every step train at any horizon; a hardware
  // back end needs one longer than its worst scheduling delay.
  uint32_t step_horizon_us = 0;
  // Simulated motors (0x5000 blocks): one per axis, or 3 behind a multiplexed axis.
  unsigned motors() const { return spm30_multiplexed ? 3 : axes; }
  // RPDOs (and as many TPDOs). The register block: four per axis (Horner RPDO/TPDO
  // 4a+1..4a+3, the HP TPDO 4a+4), present unless the device is CiA 402 only; then two per
  // axis for CiA 402 (axis a: PDO first+2a+1, first+2a+2). A CiA 402 only device's axis 1
  // thus has RPDO1/2 and TPDO1/2 at the pre-defined COB-IDs a standard master expects.
  unsigned pdos() const;
  unsigned register_pdos() const;
  unsigned cia402_first_pdo(unsigned axis) const { return register_pdos() + 2 * axis; }
  // "Horner, HP 44714A, user objects; 3 axes on the simulated machine" (the EDS comment).
  std::string description() const;
};

// The communication objects and the node's diagnostics (what the CiA 301 slave needs).
void add_node_objects(od::Dictionary& dictionary, const od::DeviceInfo& info,
                      const DeviceLayout& layout);
// The tables of the profiles in `layout`, with their default PDO mappings.
void add_profile_objects(od::Dictionary& dictionary, const DeviceLayout& layout);
// Both: every object of the device.
void build_device_objects(od::Dictionary& dictionary, const od::DeviceInfo& info,
                          const DeviceLayout& layout);

}  // namespace stepnode::node
