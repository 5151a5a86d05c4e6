// Harness: BoardClient (board_client.hpp) talking to a board that answers anything: register
// reads and writes, snapshots, streaming on/off and telemetry polls against a scripted transport.
//
// Input: byte 0 and 1 choose the client's operations (below); the rest is the board's side, a
// script of what each Transport::read returns, one step per opcode byte:
//   0x00..0x3F  n = op + 1 raw bytes follow (garbage, cut frames, anything)
//   0x40..0xBF  a well-formed frame: TYPE = the (op & 7)-th type of regmap.json, the body bytes
//               follow, the CRC is computed here (so that mutations reach past the CRC check)
//   0xC0..0xFD  nothing arrives: the read times out (the transport's clock advances by the wait)
//   0xFE        the device is unplugged (TransportError kDeviceGone, as UsbTransport throws it)
//   0xFF        an I/O error (TransportError kIo)
// When the script ends, every read times out. The clock is the transport's own (Transport::now),
// so timeouts and retries cost no wall time. BoardError and TransportError are the expected
// errors; every request the client writes must be a well-formed frame of the operation asked.
#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <variant>
#include <vector>

#include "fuzz_common.hpp"
#include "omniloc/board_client.hpp"
#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"

namespace {

using omniloc::fuzz::fuzz_check;
namespace protocol = omniloc::protocol;
namespace regmap = omniloc::regmap;

constexpr std::uint8_t kTypes[] = {regmap::kFrameReadReq,     regmap::kFrameWriteReq,
                                   regmap::kFrameSnapshotReq, regmap::kFrameReadResp,
                                   regmap::kFrameWriteAck,    regmap::kFrameSnapshotResp,
                                   regmap::kFrameTelemetry,   regmap::kFrameError};

class ScriptedTransport : public omniloc::Transport {
 public:
  explicit ScriptedTransport(std::span<const std::uint8_t> script) : script_(script) {}

  void write(std::span<const std::uint8_t> bytes) override {
    written_.feed(bytes);
    ++writes_;
    now_ += std::chrono::microseconds(100);
  }

  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override {
    ++reads_;
    fuzz_check(reads_ < 1'000'000, "the client keeps reading without end");
    fuzz_check(timeout.count() >= 0, "a negative read timeout");
    if (!pending_.empty()) return give(out);
    if (at_ >= script_.size()) return time_out(timeout);
    const std::uint8_t op = script_[at_++];
    if (op < 0x40) {
      const std::size_t n = std::min<std::size_t>(op + 1u, script_.size() - at_);
      pending_.assign(script_.begin() + static_cast<std::ptrdiff_t>(at_),
                      script_.begin() + static_cast<std::ptrdiff_t>(at_ + n));
      at_ += n;
    } else if (op < 0xC0) {
      const std::uint8_t type = kTypes[op & 7];
      const std::size_t body = *protocol::body_bytes(type);
      pending_ = {regmap::kFrameSync, static_cast<std::uint8_t>(body + 1), type};
      for (std::size_t i = 0; i < body; ++i)
        pending_.push_back(at_ < script_.size() ? script_[at_++] : 0);
      const std::uint16_t crc = protocol::crc16_ccitt(std::span(pending_).subspan(1));
      pending_.push_back(static_cast<std::uint8_t>(crc >> 8));
      pending_.push_back(static_cast<std::uint8_t>(crc & 0xFF));
    } else if (op < 0xFE) {
      return time_out(timeout);
    } else {
      throw omniloc::TransportError(
          op == 0xFE ? omniloc::TransportErrorKind::kDeviceGone : omniloc::TransportErrorKind::kIo,
          "scripted transport: fault");
    }
    return give(out);
  }

  [[nodiscard]] omniloc::TransportStatus status() const override {
    return {true, false, "scripted", {}};
  }
  [[nodiscard]] std::chrono::steady_clock::time_point now() const override { return now_; }

  protocol::FrameDecoder written_;
  std::uint64_t writes_ = 0;

 private:
  std::size_t give(std::span<std::uint8_t> out) {
    const std::size_t n = std::min(out.size(), pending_.size());
    std::copy_n(pending_.begin(), n, out.begin());
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n));
    now_ += std::chrono::microseconds(50);
    return n;
  }
  std::size_t time_out(std::chrono::milliseconds timeout) {
    now_ += timeout;
    if (timeout.count() == 0) now_ += std::chrono::microseconds(10);
    return 0;
  }

  std::span<const std::uint8_t> script_;
  std::size_t at_ = 0;
  std::vector<std::uint8_t> pending_;
  std::uint64_t reads_ = 0;
  std::chrono::steady_clock::time_point now_{};
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::uint16_t ops = static_cast<std::uint16_t>(data[0] | data[1] << 8);
  ScriptedTransport transport(std::span<const std::uint8_t>(data + 2, size - 2));
  omniloc::BoardClient client(transport, {std::chrono::milliseconds(50), 4, 8});
  std::vector<protocol::Frame> expected_requests;
  // Up to five operations, 3 bits each: read ID, read CONTROL, write CONTROL, snapshot,
  // streaming on, streaming off, poll telemetry (0 ms), poll telemetry (30 ms).
  try {
    for (int k = 0; k < 5; ++k) {
      switch ((ops >> (3 * k)) & 7) {
        case 0:
          (void)client.read_register(regmap::kRegId);
          break;
        case 1:
          (void)client.read_register(regmap::kRegControl);
          break;
        case 2:
          client.write_register(regmap::kRegControl, 0);
          break;
        case 3:
          (void)client.snapshot();
          break;
        case 4:
          client.set_streaming(true);
          break;
        case 5:
          client.set_streaming(false);
          break;
        case 6:
          (void)client.poll_telemetry(std::chrono::milliseconds(0));
          break;
        default:
          (void)client.poll_telemetry(std::chrono::milliseconds(30));
          break;
      }
    }
  } catch (const omniloc::BoardError&) {
  } catch (const omniloc::TransportError&) {
  }
  // What the client sent: whole, well-formed request frames only, nothing else.
  std::uint64_t frames = 0;
  while (const auto f = transport.written_.next()) {
    ++frames;
    fuzz_check(std::holds_alternative<protocol::ReadReq>(*f) ||
                   std::holds_alternative<protocol::WriteReq>(*f) ||
                   std::holds_alternative<protocol::SnapshotReq>(*f),
               "the client sent a frame that is not a request");
  }
  fuzz_check(frames == transport.writes_ && transport.written_.pending_bytes() == 0 &&
                 transport.written_.counters().resync_bytes == 0,
             "the client wrote something that is not one whole request frame per write");
  const auto& c = client.counters();
  fuzz_check(c.retries <= c.requests * 3, "more retries than attempts allow");
  return 0;
}
