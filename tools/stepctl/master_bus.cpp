#include "tools/stepctl/master_bus.hpp"

#include <poll.h>

#include <chrono>
#include <ctime>
#include <thread>

#include "od/cob_id.hpp"

namespace stepnode::tools {
namespace {

// Aborts a second client on the channel provokes (the server saw a request out of its
// sequence, or waited for a segment the other client never sent), and our own timeout.
bool protocol_failure(od::SdoAbort a) {
  return a == od::SdoAbort::Timeout || a == od::SdoAbort::BadCommand ||
         a == od::SdoAbort::ToggleBit || a == od::SdoAbort::General;
}

uint32_t parse_cob_id(const std::string& text) {
  if (auto id = od::parse_can_id(text)) return *id;
  throw std::invalid_argument("--sdo-cob-ids: '" + text + "' is not an 11-bit CAN-ID (1..0x7FF)");
}

}  // namespace

uint64_t monotonic_us() {
  timespec ts;
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<uint64_t>(ts.tv_sec) * 1'000'000u + static_cast<uint64_t>(ts.tv_nsec) / 1000;
}

SdoCobIds parse_sdo_cob_ids(const std::string& text) {
  const size_t comma = text.find(',');
  if (comma == std::string::npos)
    throw std::invalid_argument("--sdo-cob-ids: '" + text +
                                "': give CLIENT_TO_SERVER,SERVER_TO_CLIENT (e.g. 0x695,0x6D5)");
  SdoCobIds ids{parse_cob_id(text.substr(0, comma)), parse_cob_id(text.substr(comma + 1))};
  if (ids.client_to_server == ids.server_to_client)
    throw std::invalid_argument("--sdo-cob-ids: the two COB-IDs must differ");
  return ids;
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

// `disturbed`: another client used the channel during the transfer: its requests on our
// request COB-ID (the socket does not hand us our own frames), or answers to them.
template <class Start>
od::SdoResult MasterBus::run(uint8_t node, Start start, bool& disturbed) {
  const SdoCobIds ids =
      cob_ids_.value_or(SdoCobIds{od::cob::kSdoRx + node, od::cob::kSdoTx + node});
  od::SdoClient client(ids.client_to_server, ids.server_to_client);
  client.set_timeout_us(static_cast<uint64_t>(sdo_timeout_ms_) * 1000);
  // Frames that queued up before this transfer are not its answers (and a socket left
  // unread for long may have filled its buffer): start from an empty queue.
  while (can_.receive()) {
  }
  std::vector<od::CanFrame> out;
  start(client, out);
  for (const auto& f : out) can_.send(f);
  bool foreign_request = false;
  while (!client.done()) {
    out.clear();
    if (auto r = receive(5)) {
      foreign_request |= r->frame.id == ids.client_to_server;
      client.on_frame(r->frame, monotonic_us(), out);
    }
    client.on_tick(monotonic_us(), out);
    for (const auto& f : out) can_.send(f);
  }
  can_.flush();
  const od::SdoResult& r = client.result();
  disturbed = !r.ok() && protocol_failure(r.abort) && (foreign_request || r.foreign_replies > 0);
  return r;
}

od::SdoResult MasterBus::upload(uint8_t node, uint16_t index, uint8_t sub,
                                od::SdoClient::Mode mode) {
  for (int attempt = 1;; ++attempt) {
    bool disturbed = false;
    od::SdoResult r = run(
        node,
        [&](od::SdoClient& c, std::vector<od::CanFrame>& out) {
          c.start_upload(index, sub, mode, monotonic_us(), out);
        },
        disturbed);
    if (!disturbed) return r;
    if (attempt == kReadAttempts) throw SdoChannelBusy(node);
    // A read changes nothing, so it may go again; a pause that differs per attempt keeps
    // two clients from meeting again in step.
    std::this_thread::sleep_for(
        std::chrono::milliseconds(uint64_t{20} * attempt + monotonic_us() % 30));
  }
}

od::SdoResult MasterBus::download(uint8_t node, uint16_t index, uint8_t sub, od::Bytes data,
                                  od::SdoClient::Mode mode) {
  bool disturbed = false;
  od::SdoResult r = run(
      node,
      [&](od::SdoClient& c, std::vector<od::CanFrame>& out) {
        c.start_download(index, sub, std::move(data), mode, monotonic_us(), out);
      },
      disturbed);
  if (disturbed) throw SdoChannelBusy(node);
  return r;
}

}  // namespace stepnode::tools
