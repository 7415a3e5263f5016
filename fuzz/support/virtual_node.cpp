#include "fuzz/support/virtual_node.hpp"

#include <spdlog/spdlog.h>
#include <stdlib.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace stepnode::fuzz {

const std::filesystem::path& fresh_state_dir() {
  static const std::filesystem::path dir = [] {
    std::filesystem::path base = std::filesystem::is_directory("/dev/shm")
                                     ? std::filesystem::path("/dev/shm")
                                     : std::filesystem::temp_directory_path();
    std::string tmpl = (base / "stepnode-fuzz-XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    static std::filesystem::path made = tmpl;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(made, ec);
    });
    return made;
  }();
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    std::filesystem::remove_all(e.path(), ec);
  return dir;
}

void quiet_logs() { spdlog::set_level(spdlog::level::off); }

VirtualNode::VirtualNode(node::NodeOptions options, const node::Device::ObjectDefaults& defaults)
    : id_(options.device.node_id) {
  options.state_dir = fresh_state_dir();
  device_ = std::make_unique<node::Device>(options, defaults, [this](const od::CanFrame& f) {
    // Bounded: an input that makes the node talk a lot must not grow memory without end.
    if (sent.size() < 4096) sent.push_back(f);
  });
}

void VirtualNode::start_operational() {
  device_->start(now_us);
  frame(od::CanFrame(od::cob::kNmt, {0x01, id_}));
}

void VirtualNode::advance_us(uint64_t us) {
  const uint64_t end = now_us + us;
  while (now_us < end) {
    now_us = std::min(end, now_us + kTickUs);
    device_->on_tick(now_us);
  }
}

od::SdoResult VirtualNode::transfer(bool download, uint16_t index, uint8_t sub, od::Bytes data) {
  od::SdoClient client(od::cob::kSdoRx + id_, od::cob::kSdoTx + id_);
  std::vector<od::CanFrame> out;
  if (download)
    client.start_download(index, sub, std::move(data), od::SdoClient::Mode::Auto, now_us, out);
  else client.start_upload(index, sub, od::SdoClient::Mode::Auto, now_us, out);
  for (int round = 0; round < 64 && !client.done(); ++round) {
    if (out.empty()) {  // the node said nothing: let the client time out
      now_us += 2'000'000;
      client.on_tick(now_us, out);
      continue;
    }
    std::vector<od::CanFrame> requests;
    requests.swap(out);
    for (const od::CanFrame& f : requests) {
      sent.clear();
      frame(f);
      for (const od::CanFrame& r : sent) client.on_frame(r, now_us, out);
    }
  }
  sent.clear();
  return client.result();
}

}  // namespace stepnode::fuzz
