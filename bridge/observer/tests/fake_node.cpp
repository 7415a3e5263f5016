#include "fake_node.hpp"

#include "node/device_objects.hpp"
#include "node/profiles/cia402/objects.hpp"
#include "od/sdo_protocol.hpp"

namespace stepnode::bridge::test {

using od::Access;
using od::DataType;

namespace {

void build_third_party(od::Dictionary& d, const FakeNodeOptions& o) {
  // Another vendor's I/O module: identity and name, one TPDO of its own, and a 0x2001 that
  // means something else (it must not be taken for an axis block).
  d.var(0x1000, "Device type", DataType::Unsigned32, Access::ReadOnly, od::encode<uint32_t>(0x191));
  d.var(0x1008, "Manufacturer device name", DataType::VisibleString, Access::Const,
        od::encode_string(o.name));
  d.var(0x1017, "Producer heartbeat time", DataType::Unsigned16, Access::ReadWrite,
        od::encode<uint16_t>(100));
  od::Object& id = d.record(0x1018, "Identity object");
  id.add(1, "Vendor-ID", DataType::Unsigned32, Access::ReadOnly, od::encode<uint32_t>(0x000000AB));
  id.add(2, "Product code", DataType::Unsigned32, Access::ReadOnly,
         od::encode<uint32_t>(o.product_code));
  id.add(3, "Revision", DataType::Unsigned32, Access::ReadOnly, od::encode<uint32_t>(7));
  id.add(4, "Serial", DataType::Unsigned32, Access::ReadOnly, od::encode<uint32_t>(99));
  if (o.has_2001)
    d.var(0x2001, "Digital inputs", DataType::Unsigned16, Access::ReadOnly, od::encode<uint16_t>(0),
          true);
}

}  // namespace

FakeNode::FakeNode(FakeNodeOptions options)
    : options_(std::move(options)),
      server_(od_, od::cob::kSdoTx + options_.id),
      channel_server_(od_, options_.channel_tx) {
  if (!options_.stepnode) {
    build_third_party(od_, options_);
    return;
  }
  od::DeviceInfo info;
  info.node_id = options_.id;
  info.device_name = options_.name;
  info.serial_number = 4242;
  info.product_code = options_.stepnode_product_code;
  node::build_device_objects(od_, info,
                             node::DeviceLayout{.axes = options_.axes,
                                                .horner = options_.horner,
                                                .hp = options_.hp,
                                                .user = options_.user,
                                                .cia402 = options_.cia402});
  for (unsigned a = 0; a < options_.axes; ++a) {
    // The device dictionary may have the HP objects already (node/profiles/hp44714a); the
    // values asked for here are set either way.
    if (!options_.horner && !options_.hp) continue;  // no 0x2n00 objects at all
    if (options_.pscale > 0 && od_.find(horner::obj::index(a, 0x11), 0))
      od_.put<double>(horner::obj::index(a, 0x11), 0, options_.pscale);
    else if (options_.pscale > 0)
      od_.var(horner::obj::index(a, 0x11), "PSCALE", DataType::Real64, Access::ReadWrite,
              od::encode<double>(options_.pscale));
    if (options_.hp_objects && !od_.find(horner::obj::index(a, 0x18), 0)) {
      od_.var(horner::obj::index(a, 0x18), "DONE?", DataType::Integer8, Access::ReadOnly,
              od::encode<int8_t>(0), true);
      od_.var(horner::obj::index(a, 0x19), "HP error", DataType::Unsigned8, Access::ReadOnly,
              od::encode<uint8_t>(0), true);
    }
  }
}

void FakeNode::on_frame(const od::CanFrame& f, uint64_t now_us, std::vector<od::CanFrame>& out) {
  if (options_.channel_rx && f.id == options_.channel_rx) {
    ++requests_seen;
    return channel_server_.on_request(f, now_us, out);
  }
  if (f.id != od::cob::kSdoRx + id()) return;
  ++requests_seen;
  if (silent) return;
  if (abort_next > 0 && f.data[0] != od::sdo::kAbortByte) {
    --abort_next;
    out.push_back(od::sdo::abort_frame(od::cob::kSdoTx + id(), od::get_u16(&f.data[1]), f.data[3],
                                       od::SdoAbort::General));
    return;
  }
  if (hold) {
    server_.on_request(f, now_us, held);
    return;
  }
  server_.on_request(f, now_us, out);
}

od::CanFrame FakeNode::tpdo(unsigned k) {
  const auto comm = static_cast<uint16_t>(0x1800 + k), map = static_cast<uint16_t>(0x1A00 + k);
  od::PdoMapping mapping;
  const uint8_t n = od_.get<uint8_t>(map, 0);
  for (uint8_t i = 1; i <= n; ++i)
    mapping.push_back(od::MappedEntry::from_word(od_.get<uint32_t>(map, i)));
  const std::vector<uint8_t> data = od::pack_pdo(od_, mapping);
  return od::CanFrame(od_.get<uint32_t>(comm, 1) & 0x7FF, std::span<const uint8_t>(data));
}

od::CanFrame FakeNode::emcy(uint16_t code, uint8_t reg, std::array<uint8_t, 5> m) const {
  return od::CanFrame(0x080 + id(), {static_cast<uint8_t>(code), static_cast<uint8_t>(code >> 8),
                                     reg, m[0], m[1], m[2], m[3], m[4]});
}

void FakeNode::set_status(unsigned axis, uint16_t bits) {
  od_.put<uint16_t>(horner::obj::index(axis, horner::obj::kStatusBits), 0, bits);
}

void FakeNode::set_position(unsigned axis, int32_t motor, int32_t encoder) {
  od_.put<int32_t>(horner::obj::index(axis, horner::obj::kMotorPosition), 0, motor);
  od_.put<int32_t>(horner::obj::index(axis, horner::obj::kEncoderPosition), 0, encoder);
}

void FakeNode::set_drive(unsigned axis, uint16_t statusword, int8_t mode_display) {
  using namespace cia402::obj;
  od_.put<uint16_t>(index(axis, kStatusword), 0, statusword);
  od_.put<int8_t>(index(axis, kModesOfOperationDisplay), 0, mode_display);
}

void FakeNode::set_drive_position(unsigned axis, int32_t position, int32_t velocity) {
  using namespace cia402::obj;
  od_.put<int32_t>(index(axis, kPositionActual), 0, position);
  od_.put<int32_t>(index(axis, kVelocityActual), 0, velocity);
}

void FakeNode::set_drive_fault(unsigned axis, uint16_t error_code, int32_t following_error) {
  using namespace cia402::obj;
  od_.put<uint16_t>(index(axis, kErrorCode), 0, error_code);
  od_.put<int32_t>(index(axis, kFollowingErrorActual), 0, following_error);
}

void FakeNode::set_velocity(unsigned axis, int32_t velocity, uint8_t phase) {
  od_.put<int32_t>(horner::obj::index(axis, horner::obj::kVelocity), 0, velocity);
  od_.put<uint8_t>(horner::obj::index(axis, horner::obj::kMotionPhase), 0, phase);
}

}  // namespace stepnode::bridge::test
