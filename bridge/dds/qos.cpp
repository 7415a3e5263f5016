#include "bridge/dds/qos.hpp"

#include <algorithm>

namespace stepnode::bridge::dds {
namespace efd = eprosima::fastdds::dds;

namespace {

bool transient_local(TopicKind kind) { return kind != TopicKind::AxisPosition; }

int32_t writer_depth(TopicKind kind, bool ros2) {
  if (kind == TopicKind::Emergency) return ros2 ? kRos2Depth : kEmergencyDepth;
  if (ros2 && transient_local(kind)) return kRos2Depth;
  return 1;
}

// History and resource limits consistent with each other: per instance when keyed, the
// whole topic when unkeyed (ROS 2 mode).
template <class Qos>
void history(Qos& qos, int32_t depth, bool ros2) {
  qos.history().kind = efd::KEEP_LAST_HISTORY_QOS;
  qos.history().depth = depth;
  auto& limits = qos.resource_limits();
  limits.max_instances = ros2 ? 1 : kMaxInstances;
  limits.max_samples_per_instance = depth;
  limits.max_samples = limits.max_instances * depth;
  limits.allocated_samples = std::min<int32_t>(limits.max_samples, 64);
}

}  // namespace

efd::DataWriterQos builtin_writer_qos(TopicKind kind, bool ros2) {
  efd::DataWriterQos qos = efd::DATAWRITER_QOS_DEFAULT;
  qos.reliability().kind = efd::RELIABLE_RELIABILITY_QOS;
  qos.reliability().max_blocking_time = eprosima::fastrtps::Duration_t(0, 1'000'000);  // 1 ms
  qos.durability().kind =
      transient_local(kind) ? efd::TRANSIENT_LOCAL_DURABILITY_QOS : efd::VOLATILE_DURABILITY_QOS;
  history(qos, writer_depth(kind, ros2), ros2);
  qos.data_sharing().off();
  qos.publish_mode().kind = efd::SYNCHRONOUS_PUBLISH_MODE;
  // A late joiner of another vendor (Cyclone) may drop the first push of the history when
  // it has not discovered the writer yet; it recovers on the next heartbeat (3 s default).
  qos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 500'000'000);
  if (kind == TopicKind::AxisPosition || kind == TopicKind::DriveStatus) {
    // One sample per TPDO, up to ~80,000/s. With Fast DDS's default nack suppression of 0,
    // every write restarts a timer that fires at once, so each sample also wakes the
    // event thread (and contends for the writer's mutex): half the publishing CPU per
    // sample (bridge/bench/pipeline_bench: 20 -> 11 us at 20,000/s, 10 -> 5.5 us at
    // 60,000/s). With 1 ms the timer is re-armed at most once per ms; a NACK for a sample
    // sent less than 1 ms ago is ignored (it is still in flight), which only matters for
    // the repair of a lost sample.
    qos.reliable_writer_qos().times.nackSupressionDuration =
        eprosima::fastrtps::Duration_t(0, 1'000'000);
  }
  return qos;
}

efd::DataReaderQos builtin_reader_qos(TopicKind kind, bool ros2, int32_t depth) {
  efd::DataReaderQos qos = efd::DATAREADER_QOS_DEFAULT;
  qos.reliability().kind = efd::RELIABLE_RELIABILITY_QOS;
  qos.durability().kind =
      transient_local(kind) ? efd::TRANSIENT_LOCAL_DURABILITY_QOS : efd::VOLATILE_DURABILITY_QOS;
  history(qos, depth > 0 ? depth : writer_depth(kind, ros2), ros2);
  qos.data_sharing().off();
  return qos;
}

efd::DataWriterQos writer_qos(TopicKind kind, bool ros2, const efd::Publisher& publisher,
                              bool* from_profile) {
  efd::DataWriterQos qos;
  bool found = publisher.get_datawriter_qos_from_profile(profile_name(kind), qos) ==
               eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  if (from_profile) *from_profile = found;
  return found ? qos : builtin_writer_qos(kind, ros2);
}

efd::DataReaderQos reader_qos(TopicKind kind, bool ros2, const efd::Subscriber& subscriber,
                              int32_t depth, bool* from_profile) {
  efd::DataReaderQos qos;
  bool found = subscriber.get_datareader_qos_from_profile(profile_name(kind), qos) ==
               eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  if (from_profile) *from_profile = found;
  return found ? qos : builtin_reader_qos(kind, ros2, depth);
}

}  // namespace stepnode::bridge::dds
