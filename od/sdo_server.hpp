// SDO server state machine (CiA 301 7.2.4): expedited, segmented and block transfers in
// both directions against a Dictionary. Pure: frames in, frames out, time passed in.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "od/can_frame.hpp"
#include "od/dictionary.hpp"

namespace stepnode::od {

class SdoServer {
 public:
  // tx_cob_id: the COB-ID responses go out on (0x580 + node id by default).
  SdoServer(Dictionary& dictionary, uint32_t tx_cob_id);

  // Handles one request frame (already filtered on the server's receive COB-ID) and appends
  // the response frames to `out` (block upload appends a whole sub-block at once).
  void on_request(const CanFrame& request, uint64_t now_us, std::vector<CanFrame>& out);
  // Aborts a transfer that waited longer than the timeout for the client (0x05040000).
  void on_tick(uint64_t now_us, std::vector<CanFrame>& out);
  // Drops any transfer in progress without a frame (NMT reset communication).
  void reset();

  bool busy() const;
  // When on_tick next has work (issue 13, event-driven timing): the transfer's timeout
  // instant (the client's last frame + the timeout) or, in a block download, the stalled
  // sub-block's acknowledgement before it. Nothing while idle.
  std::optional<uint64_t> next_deadline_us() const;
  void set_tx_cob_id(uint32_t cob_id) { tx_cob_id_ = cob_id; }
  void set_timeout_us(uint64_t timeout_us) { timeout_us_ = timeout_us; }
  // Largest block size (segments per sub-block, 1..127) offered in block download.
  void set_block_size(uint8_t blksize) { block_size_ = blksize; }

 private:
  Dictionary& dictionary_;
  uint32_t tx_cob_id_;
  uint64_t timeout_us_ = 1'000'000;
  uint8_t block_size_ = 127;
  // Transfer state lives in the .cpp; see sdo_server.cpp for the states.
  struct State;
  std::unique_ptr<State> state_;

 public:
  ~SdoServer();
  SdoServer(const SdoServer&) = delete;
  SdoServer& operator=(const SdoServer&) = delete;
};

}  // namespace stepnode::od
