// SDO client state machine (CiA 301 7.2.4), the master's side of every transfer type.
// Used by stepctl, the bridge and tests. Pure: frames in, frames out, time passed in.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "od/can_frame.hpp"
#include "od/sdo_abort.hpp"
#include "od/value_codec.hpp"

namespace stepnode::od {

struct SdoResult {
  SdoAbort abort = SdoAbort::None;  // from the server, or detected by the client
  bool aborted_by_server = false;
  // Responses on our COB-ID that were not answers to this transfer (another object, a
  // command specifier or toggle this transfer does not expect): another client shares the
  // server's channel. With a Timeout it means the channel was busy, not the node absent.
  unsigned foreign_replies = 0;
  Bytes data;  // uploaded data
  // An expedited upload answered without the size (e = 1, s = 0, CiA 301 7.2.4.3.6):
  // `data` holds all four bytes, and the object's data type says how many are its value.
  bool size_unspecified = false;
  bool ok() const { return abort == SdoAbort::None; }
  // The uploaded value of an object whose type is `type_size` bytes long: an answer
  // without the size cut to it, any other as it came (a wrong size stays visible).
  Bytes value_of_size(size_t type_size) const {
    if (!size_unspecified || type_size == 0 || data.size() <= type_size) return data;
    return Bytes(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(type_size));
  }
};

class SdoClient {
 public:
  enum class Mode {
    Auto,       // expedited when it fits in 4 bytes, else segmented
    Segmented,  // never expedited for downloads (uploads: the server decides)
    Block,      // block transfer with CRC
  };

  // request_cob_id: 0x600 + node id; response_cob_id: 0x580 + node id.
  SdoClient(uint32_t request_cob_id, uint32_t response_cob_id);
  ~SdoClient();
  SdoClient(const SdoClient&) = delete;
  SdoClient& operator=(const SdoClient&) = delete;

  void start_upload(uint16_t index, uint8_t sub, Mode mode, uint64_t now_us,
                    std::vector<CanFrame>& out);
  void start_download(uint16_t index, uint8_t sub, Bytes data, Mode mode, uint64_t now_us,
                      std::vector<CanFrame>& out);
  // Feeds a frame from the bus; frames not on the response COB-ID are ignored, and so are
  // responses that do not belong to the transfer in progress (counted in foreign_replies).
  void on_frame(const CanFrame& frame, uint64_t now_us, std::vector<CanFrame>& out);
  // Times the transfer out (sends abort 0x05040000 to the server, ends with Timeout).
  void on_tick(uint64_t now_us, std::vector<CanFrame>& out);

  bool done() const;
  const SdoResult& result() const;

  uint32_t request_cob_id() const { return request_cob_id_; }
  uint32_t response_cob_id() const { return response_cob_id_; }
  void set_timeout_us(uint64_t timeout_us) { timeout_us_ = timeout_us; }
  void set_block_size(uint8_t blksize) { block_size_ = blksize; }  // 1..127, uploads

 private:
  uint32_t request_cob_id_;
  uint32_t response_cob_id_;
  uint64_t timeout_us_ = 1'000'000;
  uint8_t block_size_ = 127;
  struct State;  // the transfer in progress and the last result; see sdo_client.cpp
  std::unique_ptr<State> state_;
};

}  // namespace stepnode::od
