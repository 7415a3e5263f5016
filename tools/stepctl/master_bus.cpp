#include "tools/stepctl/master_bus.hpp"

#include <poll.h>

#include <ctime>

namespace stepnode::tools {

uint64_t monotonic_us() {
  timespec ts;
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000u + static_cast<uint64_t>(ts.tv_nsec) / 1000;
}

MasterBus::MasterBus(const std::string& iface) : can_(iface) {}

void MasterBus::send(const od::CanFrame& frame) { can_.send(frame); }

std::optional<canio::ReceivedFrame> MasterBus::receive(int timeout_ms) {
  uint64_t deadline = monotonic_us() + static_cast<uint64_t>(timeout_ms) * 1000;
  for (;;) {
    can_.flush();
    while (auto r = can_.receive())
      if (!r->error_frame) return r;
    uint64_t now = monotonic_us();
    if (now >= deadline) return std::nullopt;
    pollfd p{can_.fd(), POLLIN, 0};
    int wait_ms = static_cast<int>((deadline - now + 999) / 1000);
    ::poll(&p, 1, can_.has_pending() ? std::min(wait_ms, 1) : wait_ms);
  }
}

template <class Start>
od::SdoResult MasterBus::run(uint8_t node, Start start) {
  od::SdoClient client(od::cob::kSdoRx + node, od::cob::kSdoTx + node);
  client.set_timeout_us(static_cast<uint64_t>(sdo_timeout_ms_) * 1000);
  // Frames that queued up before this transfer are not its answers (and a socket left
  // unread for long may have filled its buffer): start from an empty queue.
  while (can_.receive()) {
  }
  std::vector<od::CanFrame> out;
  start(client, out);
  for (const auto& f : out) can_.send(f);
  while (!client.done()) {
    out.clear();
    if (auto r = receive(5)) client.on_frame(r->frame, monotonic_us(), out);
    client.on_tick(monotonic_us(), out);
    for (const auto& f : out) can_.send(f);
  }
  can_.flush();
  return client.result();
}

od::SdoResult MasterBus::upload(uint8_t node, uint16_t index, uint8_t sub, od::SdoClient::Mode mode) {
  return run(node, [&](od::SdoClient& c, std::vector<od::CanFrame>& out) {
    c.start_upload(index, sub, mode, monotonic_us(), out);
  });
}

od::SdoResult MasterBus::download(uint8_t node, uint16_t index, uint8_t sub, od::Bytes data,
                                  od::SdoClient::Mode mode) {
  return run(node, [&](od::SdoClient& c, std::vector<od::CanFrame>& out) {
    c.start_download(index, sub, std::move(data), mode, monotonic_us(), out);
  });
}

}  // namespace stepnode::tools
