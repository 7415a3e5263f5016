#include "bridge/dds/types.hpp"

#include <stepnodePubSubTypes.h>

namespace stepnode::bridge::dds {
namespace {

template <class Generated>
eprosima::fastdds::dds::TypeSupport support(TopicKind kind, const Naming& naming) {
  if (naming.ros2)
    return eprosima::fastdds::dds::TypeSupport(new UnkeyedType<Generated>(type_name(kind, naming)));
  return eprosima::fastdds::dds::TypeSupport(new Generated());
}

}  // namespace

eprosima::fastdds::dds::TypeSupport make_type_support(TopicKind kind, const Naming& naming) {
  switch (kind) {
    case TopicKind::AxisStatus: return support<::stepnode::AxisStatusPubSubType>(kind, naming);
    case TopicKind::AxisPosition: return support<::stepnode::AxisPositionPubSubType>(kind, naming);
    case TopicKind::NodeHealth: return support<::stepnode::NodeHealthPubSubType>(kind, naming);
    case TopicKind::Emergency: return support<::stepnode::EmergencyPubSubType>(kind, naming);
    case TopicKind::DriveStatus: return support<::stepnode::DriveStatusPubSubType>(kind, naming);
  }
  return {};
}

}  // namespace stepnode::bridge::dds
