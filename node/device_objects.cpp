#include "node/device_objects.hpp"

#include <cstdio>

#include "node/diagnostic_objects.hpp"
#include "node/profiles/cia402/objects.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/hp44714a/objects.hpp"
#include "node/profiles/sim/objects.hpp"
#include "node/profiles/user/objects.hpp"
#include "od/cob_id.hpp"

namespace stepnode::node {

unsigned DeviceLayout::register_pdos() const {
  return horner || hp || !cia402 ? horner::kPdosPerAxis * axes : 0;
}

unsigned DeviceLayout::pdos() const { return register_pdos() + (cia402 ? 2 * axes : 0); }

std::string DeviceLayout::description() const {
  std::string out;
  auto add = [&out](const char* what) { out += (out.empty() ? "" : ", ") + std::string(what); };
  if (horner) add(spm30_multiplexed ? "Horner (SPM30 multiplexed)" : "Horner");
  if (hp) add("HP 44714A");
  if (cia402) add("CiA 402");
  if (user) add("user objects");
  if (out.empty()) out = "no profile";
  return out + "; " + std::to_string(axes) + (axes == 1 ? " axis" : " axes") +
         " on the simulated machine";
}

void add_node_objects(od::Dictionary& dictionary, const od::DeviceInfo& info,
                      const DeviceLayout& layout) {
  od::build_communication_objects(dictionary, info, layout.pdos());
  add_diagnostic_objects(dictionary);
}

void add_profile_objects(od::Dictionary& dictionary, const DeviceLayout& layout) {
  if (layout.user) user::add_objects(dictionary);
  if (layout.horner) horner::add_objects(dictionary, layout.axes);
  if (layout.hp) hp44714a::add_objects(dictionary, layout.axes);
  if (layout.cia402) {
    cia402::add_objects(dictionary, layout.axes);
    for (unsigned a = 0; a < layout.axes; ++a)
      cia402::set_default_pdos(dictionary, a, layout.cia402_first_pdo(a),
                               layout.cia402_first_pdo(a));
    // 1000h: a CiA 402 stepper drive (each axis' 67FFh says the same).
    od::Entry& type = dictionary.at(0x1000, 0);
    type.default_value = type.value = od::encode<uint32_t>(cia402::kDeviceTypeStepper);
  }
  // The simulated machine is the back end of every axis.
  sim::add_objects(dictionary, layout.motors());
  // A PDO no profile of this device maps starts invalid (COB-ID bit 31), as the PDOs of
  // axes 2-8 do: a master maps and enables it if it wants it.
  for (unsigned n = 0; n < layout.pdos(); ++n)
    for (unsigned comm : {0x1400u, 0x1800u}) {
      const auto map = static_cast<uint16_t>(comm + 0x200 + n);
      if (dictionary.get<uint8_t>(map, 0) != 0) continue;
      od::Entry& cob = dictionary.at(static_cast<uint16_t>(comm + n), 1);
      const uint32_t invalid = od::decode<uint32_t>(cob.default_value) | od::kCobInvalid;
      cob.default_value = cob.value = od::encode<uint32_t>(invalid);
      if (!cob.eds_default
               .empty()) {  // "$NODEID+0x180" (a pre-defined ID): the node id stays symbolic
        char text[32];
        std::snprintf(text, sizeof text, "$NODEID+0x%X", static_cast<unsigned>(invalid & ~0x7Fu));
        cob.eds_default = text;
      }
    }
}

void build_device_objects(od::Dictionary& dictionary, const od::DeviceInfo& info,
                          const DeviceLayout& layout) {
  add_node_objects(dictionary, info, layout);
  add_profile_objects(dictionary, layout);
}

}  // namespace stepnode::node
