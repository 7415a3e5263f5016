#include "node/profiles/sim/objects.hpp"

#include <string>

namespace stepnode::sim {
namespace {

using DT = od::DataType;
using AC = od::Access;
using od::encode;
using od::Entry;
using od::limits;
using od::Object;

void add_machine(od::Dictionary& od, unsigned a) {
  using namespace obj;
  auto name = [a](const char* what) {
    return "Simulated axis " + std::to_string(a + 1) + " " + what;
  };
  Object& sw = od.record(index(a, kSwitches), name("switches"));
  sw.add(switches_sub::kHomePosition, "Home switch position", DT::Integer32, AC::ReadWrite,
         encode<int32_t>(1000));
  sw.add(switches_sub::kHomeWidth, "Home switch width (0 = none)", DT::Integer32, AC::ReadWrite,
         encode<int32_t>(50));
  sw.add(switches_sub::kLowerLimitEnabled, "Lower limit present", DT::Boolean, AC::ReadWrite, {1});
  sw.add(switches_sub::kLowerLimit, "Lower limit position", DT::Integer32, AC::ReadWrite,
         encode<int32_t>(-100000));
  sw.add(switches_sub::kUpperLimitEnabled, "Upper limit present", DT::Boolean, AC::ReadWrite, {1});
  sw.add(switches_sub::kUpperLimit, "Upper limit position", DT::Integer32, AC::ReadWrite,
         encode<int32_t>(100000));
  sw.add(switches_sub::kIndexPosition, "Index input position", DT::Integer32, AC::ReadWrite,
         encode<int32_t>(0));
  sw.add(switches_sub::kIndexWidth, "Index input width (0 = none)", DT::Integer32, AC::ReadWrite,
         encode<int32_t>(0));
  Object& enc = od.record(index(a, kEncoder), name("encoder"));
  limits<int32_t>(enc.add(encoder_sub::kStepsPerRev, "Steps per revolution", DT::Integer32,
                          AC::ReadWrite, encode<int32_t>(2000)),
                  1, 1'000'000);
  limits<int32_t>(enc.add(encoder_sub::kLines, "Encoder lines per revolution", DT::Integer32,
                          AC::ReadWrite, encode<int32_t>(500)),
                  1, 1'000'000);
  enc.add(encoder_sub::kMarkerOffset, "Marker offset", DT::Integer32, AC::ReadWrite,
          encode<int32_t>(0));
  limits<int32_t>(enc.add(encoder_sub::kMarkerWidth, "Marker width", DT::Integer32, AC::ReadWrite,
                          encode<int32_t>(4)),
                  1, 1'000'000);
  Object& f = od.record(index(a, kFaults), name("faults"));
  f.add(faults_sub::kStallBelowEnabled, "Jam below a position", DT::Boolean, AC::ReadWrite, {0});
  f.add(faults_sub::kStallBelow, "Jam position (low)", DT::Integer32, AC::ReadWrite,
        encode<int32_t>(0));
  f.add(faults_sub::kStallAboveEnabled, "Jam above a position", DT::Boolean, AC::ReadWrite, {0});
  f.add(faults_sub::kStallAbove, "Jam position (high)", DT::Integer32, AC::ReadWrite,
        encode<int32_t>(0));
  f.add(faults_sub::kMissEvery, "Lose every n-th step (0 = none)", DT::Unsigned32, AC::ReadWrite,
        encode<uint32_t>(0));
  Entry& push = f.add(faults_sub::kDisplace, "Displace the load by steps", DT::Integer32,
                      AC::WriteOnly, encode<int32_t>(0));
  push.persistent = false;
  f.add(faults_sub::kMoveEvery, "Slipping: only every n-th step moves the load (0 = off)",
        DT::Unsigned32, AC::ReadWrite, encode<uint32_t>(0));
  od.var(index(a, kMechanicalPosition), name("mechanical position"), DT::Integer32, AC::ReadOnly,
         encode<int32_t>(0), true);
  od.var(index(a, kInputs), name("inputs"), DT::Unsigned8, AC::ReadOnly, {0}, true);
}

}  // namespace

void add_objects(od::Dictionary& od, unsigned motors) {
  for (unsigned m = 0; m < motors; ++m) add_machine(od, m);
  od.var(obj::kEmergencyStop, "Simulated emergency stop input", DT::Boolean, AC::ReadWrite, {0})
      .persistent = false;
}

}  // namespace stepnode::sim
