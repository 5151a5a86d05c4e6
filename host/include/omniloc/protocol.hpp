// The board link's frame protocol (docs/PROTOCOL.md), exactly as common/regmap.json "frames"
// defines it:
//   SYNC, LEN (bytes of TYPE + body), TYPE, body (little-endian), CRC-16/CCITT-FALSE over LEN, TYPE
//   and body, sent high byte first.
// Encoders for every frame type, a streaming decoder that survives garbage, and the host's
// wrap-safe reconstruction of the board's 32-bit position accumulators and clock-cycle timestamp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include "omniloc/frame_bodies.hpp"
#include "omniloc/regmap.hpp"

namespace omniloc::protocol {

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor).
[[nodiscard]] std::uint16_t crc16_ccitt(std::span<const std::uint8_t> bytes,
                                        std::uint16_t crc = regmap::kCrcInit);

// ---- Frame bodies (one struct per TYPE of regmap.json) ----
// Each is the generated layout of its TYPE's body (frame_bodies.hpp: fields, offsets, pack and
// unpack), as its own type so that the variant below tells the frames apart: READ_REQ and WRITE_ACK
// share the REG_ADDR layout, READ_RESP and WRITE_REQ REG_VALUE, SNAPSHOT_RESP and TELEMETRY WINDOW.
struct ReadReq : regmap::FrameReadReqBody {
  friend bool operator==(const ReadReq&, const ReadReq&) = default;
};
struct WriteReq : regmap::FrameWriteReqBody {
  friend bool operator==(const WriteReq&, const WriteReq&) = default;
};
struct SnapshotReq : regmap::FrameSnapshotReqBody {
  friend bool operator==(const SnapshotReq&, const SnapshotReq&) = default;
};
struct ReadResp : regmap::FrameReadRespBody {
  friend bool operator==(const ReadResp&, const ReadResp&) = default;
};
struct WriteAck : regmap::FrameWriteAckBody {
  friend bool operator==(const WriteAck&, const WriteAck&) = default;
};
/// One captured window: the body of SNAPSHOT_RESP and TELEMETRY (seq, timestamp_cycles, count[],
/// dir: bit n = channel n counting down at the end of the window, status: low byte of STATUS at
/// capture).
using Window = regmap::FrameTelemetryBody;
static_assert(std::is_same_v<regmap::FrameSnapshotRespBody, Window>,
              "SNAPSHOT_RESP and TELEMETRY carry one window");
struct SnapshotResp {
  Window window;
  friend bool operator==(const SnapshotResp&, const SnapshotResp&) = default;
};
struct Telemetry {
  Window window;
  friend bool operator==(const Telemetry&, const Telemetry&) = default;
};
/// code: regmap::kErr*; detail: the offending address (BAD_ADDRESS, READ_ONLY, BAD_VALUE), TYPE
/// (BAD_CRC, MALFORMED), LEN (MALFORMED) or 0xFF (a request cut short).
struct ErrorResp : regmap::FrameErrorBody {
  friend bool operator==(const ErrorResp&, const ErrorResp&) = default;
};

using Frame = std::variant<ReadReq, WriteReq, SnapshotReq, ReadResp, WriteAck, SnapshotResp,
                           Telemetry, ErrorResp>;

/// Bytes on the wire for a frame with body of n bytes: SYNC + LEN + TYPE + body + 2 CRC.
[[nodiscard]] constexpr std::size_t frame_bytes(std::size_t body_bytes) {
  return body_bytes + 5;
}

/// Body size of a frame TYPE, or nullopt for a code regmap.json does not define.
[[nodiscard]] std::optional<std::size_t> body_bytes(std::uint8_t type);

/// Name of a frame TYPE ("READ_RESP"), or "UNKNOWN".
[[nodiscard]] std::string_view type_name(std::uint8_t type);

/// Name of an error code ("BAD_ADDRESS"), or "UNKNOWN".
[[nodiscard]] std::string_view error_name(std::uint8_t code);

/// Name of a register from regmap::kRegisters ("CONTROL"), or "0x1F (unmapped)".
[[nodiscard]] std::string register_name(std::uint8_t addr);

/// Encodes any frame into its wire bytes.
[[nodiscard]] std::vector<std::uint8_t> encode(const Frame& frame);

/// Appends the wire bytes of a frame to out (no allocation when out has capacity).
void encode_into(const Frame& frame, std::vector<std::uint8_t>& out);

// ---- Streaming decoder ----

/// What the decoder rejected or noticed. Every rejected candidate frame is counted exactly once,
/// under the first reason it failed. Invariant: every byte fed is either part of an accepted frame
/// (frames_ok), counted in resync_bytes, or still pending.
struct DecoderCounters {
  std::uint64_t frames_ok = 0;     ///< frames accepted (CRC and length good)
  std::uint64_t bad_crc = 0;       ///< candidates whose CRC did not match
  std::uint64_t bad_length = 0;    ///< candidates whose LEN did not match their TYPE's body size
  std::uint64_t unknown_type = 0;  ///< candidates with a TYPE regmap.json does not define
  /// bytes discarded: garbage before a SYNC and the SYNC of each rejected candidate
  std::uint64_t resync_bytes = 0;
  std::uint64_t telemetry_gaps = 0;  ///< times the telemetry sequence skipped forward
  std::uint64_t telemetry_lost = 0;  ///< telemetry frames missing in those gaps
  /// telemetry frames older than or equal to the last one (dropped)
  std::uint64_t telemetry_stale = 0;
  friend bool operator==(const DecoderCounters&, const DecoderCounters&) = default;
};

/// Follows the 32-bit wrapping telemetry sequence number and counts gaps.
class SequenceTracker {
 public:
  /// Result of observing one sequence number.
  struct Step {
    bool accepted = true;       ///< false: a duplicate or older frame (the caller should drop it)
    std::uint32_t missing = 0;  ///< frames skipped just before this one
  };
  Step observe(std::uint32_t seq);
  void reset() { last_.reset(); }
  [[nodiscard]] std::optional<std::uint32_t> last() const { return last_; }

 private:
  std::optional<std::uint32_t> last_;
};

/// Turns a byte stream cut into arbitrary chunks into frames. Never accepts a frame whose CRC fails
/// or whose LEN differs from its TYPE's body size; after a rejected candidate it searches for the
/// next SYNC from the byte after the rejected SYNC, so a good frame that follows garbage or a
/// truncated frame is found. Telemetry frames go through a SequenceTracker: gaps are counted, stale
/// frames (sequence not newer than the last) are counted and dropped.
class FrameDecoder {
 public:
  void feed(std::span<const std::uint8_t> bytes);
  /// The next complete frame, or nullopt when more bytes are needed.
  [[nodiscard]] std::optional<Frame> next();
  [[nodiscard]] const DecoderCounters& counters() const { return counters_; }
  /// Bytes buffered that are not yet a complete frame.
  [[nodiscard]] std::size_t pending_bytes() const { return buf_.size() - head_; }
  /// Forgets the telemetry sequence, e.g. after streaming was switched off and on again.
  void reset_sequence() { seq_.reset(); }

 private:
  void compact();
  std::vector<std::uint8_t> buf_;
  std::size_t head_ = 0;
  DecoderCounters counters_;
  SequenceTracker seq_;
};

/// Decodes the body of a frame whose TYPE and body length are already checked.
[[nodiscard]] Frame decode_body(std::uint8_t type, std::span<const std::uint8_t> body);

// ---- Wrap-safe reconstruction ----

/// Reconstructs a 64-bit position from the board's 32-bit wrapping accumulator. Correct as long as
/// the position moves by less than 2^31 counts between two observations (at 10 ms windows that is
/// 2e11 counts/s, far beyond any encoder). The first observation is read as a signed 32-bit value,
/// so a board that started at 0 and moved backwards reads negative.
class PositionUnwrapper {
 public:
  std::int64_t update(std::uint32_t raw_counts);
  [[nodiscard]] std::optional<std::int64_t> value_counts() const;

 private:
  std::optional<std::uint32_t> last_raw_;
  std::int64_t value_ = 0;
};

/// Reconstructs a 64-bit clock-cycle count from the board's 32-bit free-running TIMESTAMP (wraps
/// every 358 s at the board's 12 MHz, regmap::kBoardClockHz). Correct as long as observations are
/// less than 2^32 cycles apart.
class TimestampUnwrapper {
 public:
  explicit TimestampUnwrapper(double clk_hz);
  std::uint64_t update(std::uint32_t raw_cycles);
  /// Milliseconds since the first observation.
  [[nodiscard]] double elapsed_ms() const;
  [[nodiscard]] double clk_hz() const { return clk_hz_; }

 private:
  double clk_hz_;
  std::optional<std::uint32_t> last_raw_;
  std::uint64_t first_ = 0;
  std::uint64_t value_ = 0;
};

}  // namespace omniloc::protocol
