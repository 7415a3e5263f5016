// `stepctl watch`: the bus in words, PDOs decoded by the mapping each node really has.
#pragma once
#include <string>

#include "tools/stepctl/object_catalog.hpp"

namespace stepnode::tools {

// Prints every frame until `seconds` passed (0 = forever). Unless passive, reads each
// node's PDO mapping over SDO when the node appears, reboots, or a master remapped it.
int run_watch(const std::string& iface, const ObjectCatalog& catalog, bool passive, int seconds);

}  // namespace stepnode::tools
