#include "node/profiles/user/objects.hpp"

#include <cstdio>
#include <string>

namespace stepnode::user {

void add_objects(od::Dictionary& od) {
  using DT = od::DataType;
  using AC = od::Access;
  od::Object& regs = od.record(kRegisters, "User registers", od::ObjectCode::Array);
  for (unsigned i = 1; i <= 8; ++i)
    regs.add(static_cast<uint8_t>(i), "User register " + std::to_string(i), DT::Unsigned32,
             AC::ReadWrite, od::encode<uint32_t>(0), true);
  od::Entry& data = od.var(kData, "User data", DT::Domain, AC::ReadWrite, {});
  data.max_length = kDataMaxLength;
  data.persistent = true;
}

}  // namespace stepnode::user
