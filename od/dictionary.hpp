// The object dictionary model: objects (VAR/ARRAY/RECORD) with typed sub-entries, the
// CiA 301 access and range rules enforced on every write, and hooks through which the
// services validate writes, react to them, or compute a value when it is read.
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "od/data_type.hpp"
#include "od/sdo_abort.hpp"
#include "od/value_codec.hpp"

namespace stepnode::od {

enum class ObjectCode : uint8_t { Var = 0x07, Array = 0x08, Record = 0x09 };

// Who is writing: a master over SDO, or a received PDO (its entries were checked when
// mapped). Same rules; for a PDO the reactions are run by unpack_pdo after the whole PDO
// is stored.
enum class WriteOrigin : uint8_t { Sdo, Pdo };

struct Entry {
  uint16_t index = 0;
  uint8_t sub = 0;
  std::string name;
  DataType type = DataType::Unsigned8;
  Access access = Access::ReadOnly;
  bool pdo_mappable = false;
  // A sampled value (a position while moving) does not by itself make an event-driven
  // TPDO go out when the TPDO also carries values that are events (status bits).
  bool pdo_sampled = false;
  bool persistent = false;  // saved by 0x1010, brought back by 0x1011 / restart
  Bytes default_value;
  std::string eds_default;         // EDS DefaultValue when it is an expression ("$NODEID+0x180")
  std::optional<Bytes> low, high;  // inclusive limits, in the entry's type
  size_t max_length = 0;           // strings and domains: largest accepted length
  Bytes value;

  // Returns an abort code to refuse the write (value range, state, consistency). A check
  // only: it never acts (the reactions do).
  std::function<SdoAbort(std::span<const uint8_t>)> validate;
  // What the objects' owners do with a value once it is stored (a command is a write), in
  // the order they were added (listen(), react()); over SDO at once, for a PDO after the
  // whole PDO is stored. A reaction may refuse: the entry gets its previous value back and,
  // over SDO, that abort is the answer; the later reactions do not run.
  std::vector<std::function<SdoAbort()>> reactions;
  // A received PDO carried a value this entry refused (range, validate hook). A PDO has no
  // answer (CiA 301 7.2.2), so the owner of the object decides what the refusal means; it
  // runs before the PDO's on_written reactions.
  std::function<void(std::span<const uint8_t> value, SdoAbort abort)> on_pdo_refused;
  // Refreshes `value` just before a read (positions, counters, generated text).
  std::function<void(Bytes&)> on_read;

  size_t size() const { return value.size(); }
  size_t bit_length() const { return fixed_size(type) * 8; }
  uint32_t mapping_word() const;  // index<<16 | sub<<8 | bits, as in 0x1600/0x1A00
};

// Adds a reaction that never refuses (a listener: a service noting a changed setting).
void listen(Entry& entry, std::function<void()> listener);
// Adds a reaction that may refuse the value (a command the device cannot carry out now).
void react(Entry& entry, std::function<SdoAbort()> reaction);
// Runs the entry's reactions on its stored value; on a refusal puts `previous` back and
// returns the abort.
SdoAbort run_reactions(Entry& entry, const Bytes& previous);

// Sets an entry's inclusive range, in its own type (a write outside gets 0x0609003x).
template <class T>
Entry& limits(Entry& e, T low, T high) {
  e.low = encode<T>(low);
  e.high = encode<T>(high);
  return e;
}

struct Object {
  uint16_t index = 0;
  std::string name;
  ObjectCode code = ObjectCode::Var;
  std::map<uint8_t, Entry> entries;

  // Adds sub-entry `sub`. For ARRAY/RECORD, sub 0 (highest sub-index) is kept up to date.
  Entry& add(uint8_t sub, std::string name, DataType type, Access access, Bytes default_value,
             bool pdo_mappable = false);
};

struct ReadResult {
  SdoAbort abort = SdoAbort::None;
  Bytes data;
  bool ok() const { return abort == SdoAbort::None; }
};

class Dictionary {
 public:
  Dictionary() = default;
  Dictionary(const Dictionary&) = delete;  // hooks capture addresses of entries
  Dictionary& operator=(const Dictionary&) = delete;

  // Builders. A VAR has its value at sub 0; ARRAY/RECORD start with sub 0 only.
  Entry& var(uint16_t index, std::string name, DataType type, Access access, Bytes default_value,
             bool pdo_mappable = false);
  Object& record(uint16_t index, std::string name, ObjectCode code = ObjectCode::Record);

  Object* object(uint16_t index);
  const Object* object(uint16_t index) const;
  Entry* find(uint16_t index, uint8_t sub);
  const Entry* find(uint16_t index, uint8_t sub) const;
  Entry& at(uint16_t index, uint8_t sub);  // throws std::out_of_range naming the object
  const std::map<uint16_t, Object>& objects() const { return objects_; }

  // Locating an entry: NoObject / NoSubindex, else None.
  SdoAbort locate(uint16_t index, uint8_t sub) const;
  // The checks a download must pass before any data moves (existence, access).
  SdoAbort check_write_access(uint16_t index, uint8_t sub) const;
  ReadResult read(uint16_t index, uint8_t sub);
  // Full CiA 301 write: access, length, range, then the validate hook; stores the value and
  // (SDO) runs the reactions. Returns the abort code, or None.
  SdoAbort write(uint16_t index, uint8_t sub, std::span<const uint8_t> data,
                 WriteOrigin origin = WriteOrigin::Sdo);

  // The device's own view (no access checks, no hooks).
  const Bytes& value(uint16_t index, uint8_t sub) const;
  void set(uint16_t index, uint8_t sub, Bytes value);
  template <class T>
  T get(uint16_t index, uint8_t sub) const {
    return decode<T>(value(index, sub));
  }
  template <class T>
  void put(uint16_t index, uint8_t sub, T v) {
    set(index, sub, encode<T>(v));
  }

  // Every value back to its default (for the given index range).
  void reset_to_defaults(uint16_t first, uint16_t last);

 private:
  std::map<uint16_t, Object> objects_;
};

// Checks data against an entry's type, length and limits (no access or hook checks).
SdoAbort check_value(const Entry& entry, std::span<const uint8_t> data);

}  // namespace stepnode::od
