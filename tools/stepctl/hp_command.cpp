#include "tools/stepctl/hp_command.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <thread>

#include "node/profiles/hp44714a/objects.hpp"
#include "od/sdo_abort.hpp"
#include "tools/stepctl/hp_words.hpp"

namespace stepnode::tools {
namespace {

// An INTEGER8 (CiA 301 7.1.4.5: two's complement) from its one data byte: DONE? codes are
// -3..1.
int integer8(uint8_t byte) { return byte >= 0x80 ? int{byte} - 0x100 : int{byte}; }

}  // namespace

int run_hp_command(MasterBus& bus, int node, unsigned channel, const std::string& words,
                   int wait_timeout_s) {
  const auto plan = plan_hp_words(words, channel);  // bad words: nothing is sent
  return run_hp_plan(bus, node, channel, plan, wait_timeout_s, {});
}

int run_hp_plan(MasterBus& bus, int node, unsigned channel, const std::vector<HpAccess>& plan,
                int wait_timeout_s, const std::function<void()>& idle) {
  const uint8_t id = static_cast<uint8_t>(node);
  auto refused = [&](const HpAccess& a, const od::SdoResult& r) {
    std::fprintf(stderr, "stepctl: node %d channel %u: 0x%04X:%02X refused: 0x%08X %s\n", node,
                 channel, a.index, a.sub, static_cast<uint32_t>(r.abort),
                 std::string(od::abort_text(r.abort)).c_str());
    // Why, in the manual's words.
    if (r.abort == od::SdoAbort::DeviceState) {
      od::SdoResult e = bus.upload(id, hp44714a::obj::index(channel, hp44714a::obj::kError), 0);
      if (e.ok())
        std::fprintf(stderr, "stepctl: ERROR %u \"%s\"\n", e.data.at(0),
                     hp_error_text(e.data.at(0)).c_str());
    } else if (r.abort == od::SdoAbort::ParameterIncompatible) {
      od::SdoResult e = bus.upload(id, hp44714a::obj::index(channel, hp44714a::obj::kConflict), 0);
      if (e.ok())
        std::fprintf(stderr, "stepctl: settings conflict: %s\n",
                     hp_conflict_text(e.data.at(0)).c_str());
    }
    return 1;
  };
  for (const HpAccess& a : plan) {
    if (a.kind == HpAccess::Write) {
      od::SdoResult r = bus.download(id, a.index, a.sub, a.data);
      if (!r.ok()) return refused(a, r);
    } else if (a.kind == HpAccess::Read) {
      od::SdoResult r = bus.upload(id, a.index, a.sub);
      if (!r.ok()) return refused(a, r);
      if (a.type == od::DataType::Real64) {
        std::printf("%s %.10g\n", a.label.c_str(), od::decode<double>(r.data));
      } else if (a.type == od::DataType::Integer8) {
        int code = integer8(r.data.at(0));
        std::printf("%s %d (%s)\n", a.label.c_str(), code, hp_done_text(code).c_str());
      } else if (a.label == "TEST") {
        unsigned n = r.data.at(0);
        std::printf("TEST %u (%s)\n", n, n == 0 ? "passed" : "failed");
      } else {
        unsigned n = r.data.at(0);
        std::printf("%s %u (%s)\n", a.label.c_str(), n, hp_error_text(n).c_str());
      }
    } else {
      // Without NOWAIT: the command has completed when DONE? is no longer "running".
      auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(wait_timeout_s);
      for (;;) {
        od::SdoResult r = bus.upload(id, a.index, 0);
        if (!r.ok()) return refused(a, r);
        int code = integer8(r.data.at(0));
        if (code == -3) {
          // A command without NOWAIT under a trigger other than AUTO: locked in its wait state.
          std::fprintf(
              stderr,
              "stepctl: waiting for a trigger it cannot get without NOWAIT (HP 3-13 note 1); "
              "TRIG HOLD cancels it\n");
          return 1;
        }
        if (code != -2) break;
        if (std::chrono::steady_clock::now() > deadline) {
          std::fprintf(stderr, "stepctl: still running after %d s\n", wait_timeout_s);
          return 1;
        }
        if (idle) idle();
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    }
    if (idle) idle();
  }
  return 0;
}

}  // namespace stepnode::tools
