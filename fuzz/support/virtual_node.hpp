// A Device as node/main.cpp builds it, in virtual time, for the fuzz targets: the same
// constructor, start, on_frame and the 1 ms timer tick, without a socket or a clock.
// Its state directory is private to the process and emptied before every Device, so a
// 0x1010 "save" from one input never becomes the power-on state of the next one (an input
// that crashes must crash again when replayed alone).
#pragma once
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "node/device.hpp"
#include "od/can_frame.hpp"
#include "od/sdo_client.hpp"

namespace stepnode::fuzz {

class VirtualNode {
 public:
  static constexpr uint64_t kTickUs = 1000;  // main.cpp's default timer period

  // Builds the device (may throw what the Device constructor throws: a UsageError for a
  // configured default that is wrong on its face). `options.state_dir` is replaced.
  VirtualNode(node::NodeOptions options, const node::Device::ObjectDefaults& defaults = {});

  // Power-on (boot-up, pre-operational), then NMT start as a master sends it.
  void start_operational();
  void frame(const od::CanFrame& f) { device_->on_frame(f, now_us, now_us); }
  // Virtual time moves on by `us`, with the timer tick every kTickUs as in main.cpp.
  void advance_us(uint64_t us);
  // One SDO transfer through the device's own server (the node answers each request at
  // once), as a master's od client runs it. Gives up after a bounded number of rounds.
  od::SdoResult transfer(bool download, uint16_t index, uint8_t sub, od::Bytes data = {});

  node::Device& device() { return *device_; }
  uint8_t id() const { return id_; }

  uint64_t now_us = 1'000'000;
  std::vector<od::CanFrame> sent;  // what the node sent since the last clear

 private:
  uint8_t id_;
  std::unique_ptr<node::Device> device_;
};

// The process's state directory (created once, under /dev/shm when it exists: the store
// fsyncs), emptied on every call.
const std::filesystem::path& fresh_state_dir();

// Logging off: spdlog's output would cost more than the node's work.
void quiet_logs();

}  // namespace stepnode::fuzz
