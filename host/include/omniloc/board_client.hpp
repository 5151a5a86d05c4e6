// Talks to the omniloc encoder board through any Transport: register reads and writes, snapshots
// and streamed telemetry, with timeouts and retries. One request is outstanding at a time.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <stdexcept>
#include <string>

#include "omniloc/protocol.hpp"
#include "omniloc/transport.hpp"

namespace omniloc {

/// The board answered a request with an ERROR frame that retrying cannot fix (BAD_ADDRESS,
/// READ_ONLY, BAD_VALUE), or it never answered within all retries.
class BoardError : public std::runtime_error {
 public:
  BoardError(std::string what, std::uint8_t error_code, std::uint8_t addr)
      : std::runtime_error(std::move(what)), error_code_(error_code), addr_(addr) {}
  /// regmap::kErr* code, or 0 when the board never answered.
  [[nodiscard]] std::uint8_t error_code() const { return error_code_; }
  [[nodiscard]] std::uint8_t addr() const { return addr_; }

 private:
  std::uint8_t error_code_;
  std::uint8_t addr_;
};

struct BoardClientOptions {
  /// Time to wait for a response before resending. A request and its response take < 0.5 ms on the
  /// wire at 1 Mbaud; the bridge's latency timer (1 ms) and USB scheduling dominate.
  std::chrono::milliseconds response_timeout{50};
  int attempts = 4;  ///< sends per request before giving up
  /// telemetry frames kept while nobody polls (oldest dropped)
  std::size_t telemetry_queue = 1024;
};

struct BoardClientCounters {
  std::uint64_t requests = 0;
  std::uint64_t retries = 0;         ///< resends after a timeout or a BAD_CRC / MALFORMED answer
  std::uint64_t timeouts = 0;        ///< response timeouts (each followed by a retry or a failure)
  std::uint64_t board_rejected = 0;  ///< BAD_CRC / MALFORMED answers: our request arrived damaged
  std::uint64_t unexpected_frames = 0;  ///< well-formed frames that answer nothing outstanding
  std::uint64_t telemetry_dropped = 0;  ///< telemetry dropped because the queue was full
};

class BoardClient {
 public:
  explicit BoardClient(Transport& transport, BoardClientOptions options = {});

  [[nodiscard]] std::uint32_t read_register(std::uint8_t addr);
  void write_register(std::uint8_t addr, std::uint32_t value);
  /// SNAPSHOT_REQ: the last captured window, latched as one unit by the board.
  [[nodiscard]] protocol::Window snapshot();
  /// Sets or clears CONTROL.STREAM with a read-modify-write of CONTROL.
  void set_streaming(bool on);
  /// The next telemetry window, waiting up to timeout (0: only what has already arrived); nullopt
  /// on timeout.
  [[nodiscard]] std::optional<protocol::Window> poll_telemetry(std::chrono::milliseconds timeout);

  [[nodiscard]] const protocol::DecoderCounters& decoder_counters() const {
    return decoder_.counters();
  }
  [[nodiscard]] const BoardClientCounters& counters() const { return counters_; }
  [[nodiscard]] Transport& transport() { return transport_; }

 private:
  enum class Expect { kRead, kWrite, kSnapshot };
  /// Sends the request and waits for the frame that answers it; returns that frame.
  protocol::Frame transact(const protocol::Frame& request, Expect expect, std::uint8_t addr);
  /// Reads from the transport until a frame is decoded or the deadline passes.
  std::optional<protocol::Frame> next_frame(std::chrono::steady_clock::time_point deadline);
  void queue_telemetry(const protocol::Window& w);
  void drain_input();

  Transport& transport_;
  BoardClientOptions options_;
  protocol::FrameDecoder decoder_;
  std::deque<protocol::Window> telemetry_;
  BoardClientCounters counters_;
};

}  // namespace omniloc
