// Reads a fuzz input front to back, one field after another, so that a seed written by
// fuzz/make_seeds (a layout byte, then events) means what it says, and a mutation of one
// byte changes one field. Past the end every read gives 0 and done() is true.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace stepnode::fuzz {

class ByteStream {
 public:
  ByteStream(const uint8_t* data, size_t size) : p_(data), end_(data + size) {}

  bool done() const { return p_ >= end_; }
  size_t left() const { return static_cast<size_t>(end_ - p_); }
  uint8_t u8() { return done() ? 0 : *p_++; }
  uint16_t u16() {  // little-endian, as on the bus
    uint16_t lo = u8();
    return static_cast<uint16_t>(lo | (u8() << 8));
  }
  // The rest of the input as text.
  std::string rest() {
    std::string s(reinterpret_cast<const char*>(p_), left());
    p_ = end_;
    return s;
  }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
};

}  // namespace stepnode::fuzz
