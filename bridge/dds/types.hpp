// TypeSupport for each topic. Plain naming registers the generated types as they are
// (keyed by node and axis). ROS 2 naming registers the same serialization under the ROS 2
// type name and without a key: rmw_fastrtps types have none, and Fast DDS refuses to match
// a keyed writer with an unkeyed reader (topic kinds differ), silently for the user.
#pragma once
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "bridge/dds/naming.hpp"

namespace stepnode::bridge::dds {

// The generated type under another name, without a key (one topic-wide history).
template <class Generated>
class UnkeyedType : public Generated {
 public:
  explicit UnkeyedType(const std::string& name) {
    this->setName(name.c_str());
    this->m_isGetKeyDefined = false;
  }
};

eprosima::fastdds::dds::TypeSupport make_type_support(TopicKind kind, const Naming& naming);

}  // namespace stepnode::bridge::dds
