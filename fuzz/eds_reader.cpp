// Fuzz target: the EDS reader (od/eds_reader.cpp, CiA 306), which stepctl runs on files it
// is given and on what a node serves over 0x1021. The input is the file's text. A malformed
// file is a std::runtime_error naming the line; anything else escaping (another exception,
// a crash, undefined behaviour) is a bug.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "od/eds.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const stepnode::od::EdsFile eds = stepnode::od::parse_eds(text);
    // What stepctl does next with it: look entries up.
    for (const auto& [key, entry] : eds.entries)
      if (eds.find(key.first, key.second) != &entry) __builtin_trap();
  } catch (const std::runtime_error&) {
    // a malformed file, refused with its line number: the expected outcome
  }
  return 0;
}
