// Fuzz target: the HP 44714A command language. The input is what a user types after
// `stepctl hp` ("PROFILE FREQ 100 800 200 25E-6; MOVE 20 NOWAIT; POS?"), the first byte
// choosing the channel (0..2). tools/stepctl/hp_words.cpp plans it (words -> object
// accesses; bad words are std::invalid_argument); then the plan runs as stepctl runs it,
// SDO transfer by transfer, against the default node (Horner, HP, 3 axes; the
// channel's reactions in node/profiles/hp44714a and node/motion/hp_channel carry the
// commands out), virtual time moving on while a command without NOWAIT runs. A refused
// access ends the plan, as in stepctl.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz/support/byte_stream.hpp"
#include "fuzz/support/virtual_node.hpp"
#include "tools/stepctl/hp_words.hpp"

using namespace stepnode;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::quiet_logs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteStream in(data, size);
  const unsigned channel = in.u8() % 3;
  const std::string words = in.rest();
  std::vector<tools::HpAccess> plan;
  try {
    plan = tools::plan_hp_words(words, channel);
  } catch (const std::invalid_argument&) {
    return 0;  // refused words, nothing sent: the expected outcome
  }
  node::NodeOptions options;
  options.device.node_id = 5;
  options.layout = node::DeviceLayout{};  // the default device: Horner, HP and user objects, 3 axes
  fuzz::VirtualNode n(options);
  n.start_operational();
  for (const tools::HpAccess& a : plan) {
    if (a.kind == tools::HpAccess::WaitWhileRunning) {
      // stepctl polls DONE? until it is no longer -2 (running); here for at most 10 s.
      for (int polls = 0; polls < 500; ++polls) {
        od::SdoResult r = n.transfer(false, a.index, 0);
        if (!r.ok() || r.data.empty() || static_cast<int8_t>(r.data[0]) != -2) break;
        n.advance_us(20'000);
      }
      continue;
    }
    const od::SdoResult r = n.transfer(a.kind == tools::HpAccess::Write, a.index, a.sub, a.data);
    if (!r.ok()) break;
    n.advance_us(1000);
  }
  n.advance_us(10'000);
  return 0;
}
