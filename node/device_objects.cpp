#include "node/device_objects.hpp"

#include "node/diagnostic_objects.hpp"
#include "node/profiles/horner/objects.hpp"
#include "node/profiles/hp44714a/objects.hpp"
#include "node/profiles/sim/objects.hpp"
#include "node/profiles/user/objects.hpp"

namespace stepnode::node {

unsigned DeviceLayout::pdos() const { return horner::kPdosPerAxis * axes; }

std::string DeviceLayout::description() const {
  std::string out;
  auto add = [&out](const char* what) { out += (out.empty() ? "" : ", ") + std::string(what); };
  if (horner) add(spm30_multiplexed ? "Horner (SPM30 multiplexed)" : "Horner");
  if (hp) add("HP 44714A");
  if (user) add("user objects");
  if (out.empty()) out = "no profile";
  return out + "; " + std::to_string(axes) + (axes == 1 ? " axis" : " axes") + " on the simulated machine";
}

void add_node_objects(od::Dictionary& dictionary, const od::DeviceInfo& info, const DeviceLayout& layout) {
  od::build_communication_objects(dictionary, info, layout.pdos());
  add_diagnostic_objects(dictionary);
}

void add_profile_objects(od::Dictionary& dictionary, const DeviceLayout& layout) {
  if (layout.user) user::add_objects(dictionary);
  if (layout.horner) horner::add_objects(dictionary, layout.axes);
  if (layout.hp) hp44714a::add_objects(dictionary, layout.axes);
  // The simulated machine is the back end of every axis.
  sim::add_objects(dictionary, layout.motors());
}

void build_device_objects(od::Dictionary& dictionary, const od::DeviceInfo& info, const DeviceLayout& layout) {
  add_node_objects(dictionary, info, layout);
  add_profile_objects(dictionary, layout);
}

}  // namespace stepnode::node
