#include "od/dictionary.hpp"

#include <cstdio>
#include <stdexcept>

namespace stepnode::od {

uint32_t Entry::mapping_word() const {
  return (static_cast<uint32_t>(index) << 16) | (static_cast<uint32_t>(sub) << 8) |
         static_cast<uint32_t>(bit_length());
}

Entry& Object::add(uint8_t sub, std::string entry_name, DataType type, Access access,
                   Bytes default_value, bool pdo_mappable) {
  Entry& e = entries[sub];
  e.index = index;
  e.sub = sub;
  e.name = std::move(entry_name);
  e.type = type;
  e.access = access;
  e.pdo_mappable = pdo_mappable;
  e.persistent = writable(access);
  e.default_value = std::move(default_value);
  e.value = e.default_value;
  if (is_variable_length(type)) e.max_length = std::max<size_t>(e.value.size(), 255);
  // Sub 0 of an ARRAY/RECORD says the highest sub-index; a read-only one follows the
  // entries that exist (a writable one, like a PDO mapping count, is the owner's business).
  if (code != ObjectCode::Var && sub != 0) {
    Entry& count = entries.at(0);
    if (!writable(count.access) && sub > count.default_value.at(0)) {
      count.default_value = {sub};
      count.value = {sub};
    }
  }
  return e;
}

Entry& Dictionary::var(uint16_t index, std::string name, DataType type, Access access,
                       Bytes default_value, bool pdo_mappable) {
  Object& obj = objects_[index];
  obj.index = index;
  obj.name = name;
  obj.code = ObjectCode::Var;
  return obj.add(0, std::move(name), type, access, std::move(default_value), pdo_mappable);
}

Object& Dictionary::record(uint16_t index, std::string name, ObjectCode code) {
  Object& obj = objects_[index];
  obj.index = index;
  obj.name = std::move(name);
  obj.code = code;
  obj.add(0, "Highest sub-index supported", DataType::Unsigned8, Access::Const, {0});
  return obj;
}

Object* Dictionary::object(uint16_t index) {
  auto it = objects_.find(index);
  return it == objects_.end() ? nullptr : &it->second;
}

const Object* Dictionary::object(uint16_t index) const {
  auto it = objects_.find(index);
  return it == objects_.end() ? nullptr : &it->second;
}

Entry* Dictionary::find(uint16_t index, uint8_t sub) {
  Object* obj = object(index);
  if (!obj) return nullptr;
  auto it = obj->entries.find(sub);
  return it == obj->entries.end() ? nullptr : &it->second;
}

const Entry* Dictionary::find(uint16_t index, uint8_t sub) const {
  return const_cast<Dictionary*>(this)->find(index, sub);
}

Entry& Dictionary::at(uint16_t index, uint8_t sub) {
  Entry* e = find(index, sub);
  if (!e) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "object 0x%04X:%02X is not in the dictionary", index, sub);
    throw std::out_of_range(buf);
  }
  return *e;
}

SdoAbort Dictionary::locate(uint16_t index, uint8_t sub) const {
  const Object* obj = object(index);
  if (!obj) return SdoAbort::NoObject;
  if (!obj->entries.contains(sub)) return SdoAbort::NoSubindex;
  return SdoAbort::None;
}

SdoAbort Dictionary::check_write_access(uint16_t index, uint8_t sub) const {
  if (SdoAbort a = locate(index, sub); a != SdoAbort::None) return a;
  return writable(find(index, sub)->access) ? SdoAbort::None : SdoAbort::ReadOnly;
}

ReadResult Dictionary::read(uint16_t index, uint8_t sub) {
  if (SdoAbort a = locate(index, sub); a != SdoAbort::None) return {a, {}};
  Entry& e = *find(index, sub);
  if (!readable(e.access)) return {SdoAbort::WriteOnly, {}};
  if (e.on_read) e.on_read(e.value);
  return {SdoAbort::None, e.value};
}

SdoAbort check_value(const Entry& e, std::span<const uint8_t> data) {
  size_t size = fixed_size(e.type);
  if (size != 0) {
    if (data.size() > size) return SdoAbort::LengthTooHigh;
    if (data.size() < size) return SdoAbort::LengthTooLow;
    if (e.type == DataType::Boolean && data[0] > 1) return SdoAbort::InvalidValue;
    if (e.low && compare_values(e.type, data, *e.low) < 0) return SdoAbort::ValueTooLow;
    if (e.high && compare_values(e.type, data, *e.high) > 0) return SdoAbort::ValueTooHigh;
    return SdoAbort::None;
  }
  if (e.max_length != 0 && data.size() > e.max_length) return SdoAbort::LengthTooHigh;
  return SdoAbort::None;
}

SdoAbort Dictionary::write(uint16_t index, uint8_t sub, std::span<const uint8_t> data,
                           WriteOrigin origin) {
  if (SdoAbort a = locate(index, sub); a != SdoAbort::None) return a;
  Entry& e = *find(index, sub);
  if (!writable(e.access)) return SdoAbort::ReadOnly;
  if (SdoAbort a = check_value(e, data); a != SdoAbort::None) return a;
  if (e.validate) {
    if (SdoAbort a = e.validate(data); a != SdoAbort::None) return a;
  }
  Bytes previous = std::move(e.value);
  e.value.assign(data.begin(), data.end());
  // A PDO's reactions run once all its values are in (unpack_pdo), so a command bit in the
  // same PDO as its destination sees the new destination.
  if (origin == WriteOrigin::Pdo) return SdoAbort::None;
  return run_reactions(e, previous);
}

void listen(Entry& entry, std::function<void()> listener) {
  entry.reactions.push_back([listener = std::move(listener)] {
    listener();
    return SdoAbort::None;
  });
}

void react(Entry& entry, std::function<SdoAbort()> reaction) {
  entry.reactions.push_back(std::move(reaction));
}

SdoAbort run_reactions(Entry& entry, const Bytes& previous) {
  for (const auto& reaction : entry.reactions) {
    if (SdoAbort a = reaction(); a != SdoAbort::None) {
      entry.value = previous;
      return a;
    }
  }
  return SdoAbort::None;
}

const Bytes& Dictionary::value(uint16_t index, uint8_t sub) const {
  return const_cast<Dictionary*>(this)->at(index, sub).value;
}

void Dictionary::set(uint16_t index, uint8_t sub, Bytes v) { at(index, sub).value = std::move(v); }

void Dictionary::reset_to_defaults(uint16_t first, uint16_t last) {
  for (auto& [index, obj] : objects_) {
    if (index < first || index > last) continue;
    for (auto& [sub, e] : obj.entries) e.value = e.default_value;
  }
}

}  // namespace stepnode::od
