// The od library's tests against the stepnode device's real tables: its dictionary as the
// node builds it (node/device_objects.*: communication objects, diagnostics, profiles).
#pragma once
#include "node/device_objects.hpp"
#include "od/communication_objects.hpp"
#include "od/dictionary.hpp"

namespace stepnode::od {

inline void build_stepnode_device(Dictionary& od, const DeviceInfo& info,
                                  const node::DeviceLayout& layout = {}) {
  node::build_device_objects(od, info, layout);
}
inline unsigned pdo_count(const node::DeviceLayout& layout = {}) { return layout.pdos(); }

}  // namespace stepnode::od
