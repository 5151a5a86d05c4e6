// Golden model of the omniloc encoder board as the host sees it through its UART: the registers of
// common/regmap.json, the request/response protocol and streamed telemetry, with window counts
// taken from a script instead of encoder waveforms. Time advances only when the test says so
// (run_windows), so every run is deterministic. Thread-safe: the emulated USB bridge calls it from
// umockdev's worker thread while the test thread advances time.
//
// The request parser follows rtl/frame_rx.v byte for byte (tests/link/tb_reference_board_vs_rtl.cpp
// feeds both the same byte streams and compares the answers): hunt for SYNC; a LEN of 0 or above
// 1 + WRITE_REQ body is answered ERROR MALFORMED (detail = LEN) at once; otherwise LEN bytes and
// the CRC are collected, and a wrong CRC is answered BAD_CRC (detail = TYPE), a right CRC on
// anything but a well-formed request MALFORMED (detail = TYPE). The parser does not rescan the
// bytes of a rejected frame (the host's decoder does). frame_rx aborts a frame after an inter-byte
// gap (MALFORMED, detail 0xFF); the model has no byte timing, so it treats the end of each
// to_board() chunk as such a gap when a frame is left incomplete -- the host writes every request
// whole and writes again only after an answer or a timeout, both longer than the gap. Register
// errors name the address in the detail: BAD_ADDRESS, READ_ONLY, BAD_VALUE (a refused value also
// sets STATUS.BAD_WRITE). A bad frame never writes a register.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc_sim/uart_side.hpp"

namespace omniloc::sim {

struct ReferenceBoardConfig {
  /// the iCEBreaker's clock, as the Verilated board (sim::BoardSim)
  std::uint32_t clk_hz = regmap::kBoardClockHz;
  std::uint32_t tick_hz = regmap::kTickHz;
  std::uint32_t initial_timestamp_cycles = 0;
  std::array<std::uint32_t, regmap::kChannels> initial_position{};  ///< to exercise wrap-around
  /// CONFIG.CHANNELS: a board built for 3 wheels counts nothing on channel 3 (rtl/encoder_core.v).
  int channels = regmap::kChannels;
  /// Keep every emitted frame, window and applied write for windows() / emitted() /
  /// applied_writes(); false keeps only the last window (a soak of hours, tests/soak/soak_daemon).
  bool keep_history = true;
};

/// Counts of one window for a window sequence number.
using CountScript = std::function<std::array<std::int32_t, regmap::kChannels>(std::uint32_t seq)>;

/// The gyro's window as the board latches it (regmap WINDOW gyro_sum, gyro_count, gyro_flags).
struct GyroWindowScript {
  std::int32_t sum = 0;
  std::uint8_t count = 0;
  std::uint8_t flags = 0;
};
/// The gyro's window for a window sequence number; without one, a working gyro at rest (ten 1 kHz
/// samples of 0 per 10 ms window, no flag).
using GyroScript = std::function<GyroWindowScript(std::uint32_t seq)>;

class ReferenceBoard final : public UartSide {
 public:
  /// Where one emitted frame lies in the board's output byte stream (for fault-injection
  /// bookkeeping).
  struct EmittedFrame {
    std::uint64_t offset = 0;  ///< index of its SYNC byte in everything the board ever sent
    std::size_t bytes = 0;
    protocol::Frame frame;
  };
  struct AppliedWrite {
    std::uint8_t addr;
    std::uint32_t value;
  };

  explicit ReferenceBoard(ReferenceBoardConfig cfg = {}, CountScript script = nullptr,
                          GyroScript gyro = nullptr)
      : cfg_(cfg), script_(std::move(script)), gyro_(std::move(gyro)) {
    period_cycles_ = cfg_.clk_hz / cfg_.tick_hz;
    timestamp_ = cfg_.initial_timestamp_cycles;
    position_ = cfg_.initial_position;
  }

  // ---- UartSide ----
  void to_board(std::span<const std::uint8_t> bytes) override {
    std::lock_guard lock(mu_);
    if (rx_state_ != Rx::kHunt) rx_error(regmap::kErrMalformed, 0xFF);  // the gap before this chunk
    for (const std::uint8_t b : bytes) rx_byte(b);
  }

  std::size_t from_board(std::span<std::uint8_t> out) override {
    std::lock_guard lock(mu_);
    const std::size_t n = std::min(out.size(), tx_.size() - tx_head_);
    std::copy_n(tx_.begin() + static_cast<std::ptrdiff_t>(tx_head_), n, out.begin());
    tx_head_ += n;
    if (tx_head_ == tx_.size()) {
      tx_.clear();
      tx_head_ = 0;
    }
    return n;
  }

  // ---- Test control ----
  /// Advances time by n windows of PERIOD cycles; each captured window is streamed when STREAM is
  /// set.
  void run_windows(int n) {
    std::lock_guard lock(mu_);
    for (int i = 0; i < n; ++i) capture();
  }

  [[nodiscard]] std::uint32_t reg(std::uint8_t addr) const {
    std::lock_guard lock(mu_);
    return read_reg(addr).value_or(0);
  }
  [[nodiscard]] std::vector<protocol::Window> windows() const {
    std::lock_guard lock(mu_);
    return windows_;
  }
  [[nodiscard]] std::vector<EmittedFrame> emitted() const {
    std::lock_guard lock(mu_);
    return emitted_;
  }
  [[nodiscard]] std::vector<AppliedWrite> applied_writes() const {
    std::lock_guard lock(mu_);
    return writes_;
  }
  /// Requests the board's parser rejected, by the error it answered with.
  struct RxCounters {
    std::uint64_t requests = 0;
    std::uint64_t bad_crc = 0;
    std::uint64_t malformed = 0;
    std::uint64_t aborted = 0;  ///< incomplete at a gap (MALFORMED 0xFF), counted in malformed too
  };
  [[nodiscard]] RxCounters rx_counters() const {
    std::lock_guard lock(mu_);
    return rx_counters_;
  }
  [[nodiscard]] std::uint64_t tx_bytes_total() const {
    std::lock_guard lock(mu_);
    return tx_total_;
  }
  [[nodiscard]] std::uint32_t period_cycles() const {
    std::lock_guard lock(mu_);
    return period_cycles_;
  }

 private:
  enum class Rx { kHunt, kLen, kType, kBody, kCrcHi, kCrcLo };
  static constexpr std::uint8_t kMaxLen = 1 + regmap::kFrameWriteReqBodyBytes;

  void rx_error(std::uint8_t code, std::uint8_t detail) {
    ++(code == regmap::kErrBadCrc ? rx_counters_.bad_crc : rx_counters_.malformed);
    if (detail == 0xFF && code == regmap::kErrMalformed) ++rx_counters_.aborted;
    emit(protocol::ErrorResp{code, detail});
    rx_state_ = Rx::kHunt;
  }

  void rx_byte(std::uint8_t b) {
    switch (rx_state_) {
      case Rx::kHunt:
        if (b == regmap::kFrameSync) {
          rx_frame_.clear();
          rx_state_ = Rx::kLen;
        }
        return;
      case Rx::kLen:
        if (b == 0 || b > kMaxLen) return rx_error(regmap::kErrMalformed, b);
        rx_frame_.push_back(b);
        rx_state_ = Rx::kType;
        return;
      case Rx::kType:
        rx_frame_.push_back(b);
        rx_state_ = rx_frame_[0] == 1 ? Rx::kCrcHi : Rx::kBody;
        return;
      case Rx::kBody:
        rx_frame_.push_back(b);
        if (rx_frame_.size() == static_cast<std::size_t>(rx_frame_[0]) + 1) rx_state_ = Rx::kCrcHi;
        return;
      case Rx::kCrcHi:
        rx_crc_hi_ = b;
        rx_state_ = Rx::kCrcLo;
        return;
      case Rx::kCrcLo: {
        rx_state_ = Rx::kHunt;
        const std::uint8_t type = rx_frame_[1];
        const auto crc = static_cast<std::uint16_t>((rx_crc_hi_ << 8) | b);
        if (crc != protocol::crc16_ccitt(rx_frame_)) return rx_error(regmap::kErrBadCrc, type);
        const std::size_t body = rx_frame_.size() - 2;
        const bool request =
            (type == regmap::kFrameReadReq && body == regmap::kFrameReadReqBodyBytes) ||
            (type == regmap::kFrameWriteReq && body == regmap::kFrameWriteReqBodyBytes) ||
            (type == regmap::kFrameSnapshotReq && body == regmap::kFrameSnapshotReqBodyBytes);
        if (!request) return rx_error(regmap::kErrMalformed, type);
        ++rx_counters_.requests;
        handle(protocol::decode_body(type, std::span<const std::uint8_t>(rx_frame_).subspan(2)));
        return;
      }
    }
  }

  void emit(const protocol::Frame& f) {
    const std::size_t before = tx_.size();
    protocol::encode_into(f, tx_);
    const std::size_t n = tx_.size() - before;
    if (cfg_.keep_history) emitted_.push_back(EmittedFrame{tx_total_, n, f});
    tx_total_ += n;
  }

  void capture() {
    timestamp_ += period_cycles_;
    if (!regmap::kControlEnable.get(control_)) return;
    protocol::Window w;
    w.seq = ++seq_;
    w.timestamp_cycles = timestamp_;
    if (script_) w.count = script_(w.seq);
    for (int ch = cfg_.channels; ch < regmap::kChannels; ++ch)
      w.count[static_cast<std::size_t>(ch)] = 0;
    const GyroWindowScript g =
        gyro_
            ? gyro_(w.seq)
            : GyroWindowScript{0, static_cast<std::uint8_t>(regmap::kGyroOdrHz / cfg_.tick_hz), 0};
    w.gyro_sum = g.sum;
    w.gyro_count = g.count;
    w.gyro_flags = g.flags;
    gyro_faults_ += g.flags != 0 && gyro_faults_ < 255 ? 1u : 0u;
    gyro_running_ = (g.flags >> regmap::kGyroFlagNotRunning & 1u) == 0;
    gyro_absent_ = (g.flags >> regmap::kGyroFlagAbsent & 1u) != 0;
    for (int ch = 0; ch < regmap::kChannels; ++ch) {
      const auto c = static_cast<std::size_t>(ch);
      position_[c] += static_cast<std::uint32_t>(w.count[c]);
      if (w.count[c] < 0) dir_ |= static_cast<std::uint8_t>(1u << ch);
      if (w.count[c] > 0) dir_ &= static_cast<std::uint8_t>(~(1u << ch));
    }
    w.dir = dir_;
    if (!consumed_ && !windows_.empty()) status_ = regmap::kStatusOverrun.put(status_, 1);
    w.status = static_cast<std::uint8_t>(status_ & 0xFF);
    // The RTL sets GYRO_FAULT in the cycle after the capture: it shows from the next window on.
    if (g.flags != 0) status_ = regmap::kStatusGyroFault.put(status_, 1);
    if (!cfg_.keep_history) windows_.clear();
    windows_.push_back(w);
    last_positions_ = position_;
    consumed_ = false;
    if (regmap::kControlStream.get(control_)) {
      emit(protocol::Telemetry{w});
      consumed_ = true;
    }
  }

  void latch() {
    if (windows_.empty()) return;
    latched_ = windows_.back();
    latched_positions_ = last_positions_;
    consumed_ = true;
  }

  [[nodiscard]] std::optional<std::uint32_t> read_reg(std::uint8_t addr) const {
    namespace r = regmap;
    if (addr >= r::kRegSnapCount0 && addr <= r::kRegSnapCount3) {
      return static_cast<std::uint32_t>(latched_.count[addr - r::kRegSnapCount0]);
    }
    if (addr >= r::kRegSnapPosition0 && addr <= r::kRegSnapPosition3) {
      return latched_positions_[addr - r::kRegSnapPosition0];
    }
    if (addr >= r::kRegErrorCount0 && addr <= r::kRegErrorCount3)
      return 0u;  // the script makes no illegal edges
    switch (addr) {
      case r::kRegId:
        return r::kIdValue;
      case r::kRegVersion:
        return r::kVersionValue;
      case r::kRegConfig:
        return r::kConfigChannels.put(0, static_cast<std::uint32_t>(cfg_.channels));
      case r::kRegControl:
        return control_;
      case r::kRegFilter:
        return filter_;
      case r::kRegPeriod:
        return period_cycles_;
      case r::kRegStatus:
        return status_;
      case r::kRegTimestamp:
        return timestamp_;
      case r::kRegLinkErrors:
        return 0u;  // bytes arrive whole here: no stop-bit or overrun errors
      case r::kRegSnapSeq:
        return latched_.seq;
      case r::kRegSnapTimestamp:
        return latched_.timestamp_cycles;
      case r::kRegSnapDir:
        return latched_.dir;
      case r::kRegSnapStatus:
        return latched_.status;
      case r::kRegSnapGyroSum:
        return static_cast<std::uint32_t>(latched_.gyro_sum);
      case r::kRegSnapGyro:
        return r::kSnapGyroFlags.put(r::kSnapGyroCount.put(0, latched_.gyro_count),
                                     latched_.gyro_flags);
      case r::kRegGyroState:  // the live reader: faults counted per flagged window (the RTL counts
                              // each fault)
        return r::kGyroStateFaults.put(
            r::kGyroStateAbsent.put(r::kGyroStateRunning.put(0, gyro_running_ ? 1 : 0),
                                    gyro_absent_ ? 1 : 0),
            gyro_faults_);
      default:
        return std::nullopt;
    }
  }

  /// Applies a write; returns the error code to answer with, or 0.
  std::uint8_t write_reg(std::uint8_t addr, std::uint32_t v) {
    namespace r = regmap;
    const auto* reg = find(addr);
    if (!reg) return r::kErrBadAddress;
    switch (addr) {
      case r::kRegControl:
        // A bit above CONTROL's fields, or a DECODE value it does not define (they are 0..max).
        if (r::kControlDecode.get(v) > r::kControlDecodeMax || (v >> r::kControlBits) != 0) {
          status_ = r::kStatusBadWrite.put(status_, 1);
          return r::kErrBadValue;
        }
        control_ = v;
        break;
      case r::kRegFilter:
        if ((v >> r::kFilterBits) != 0) {
          status_ = r::kStatusBadWrite.put(status_, 1);
          return r::kErrBadValue;
        }
        filter_ = v;
        break;
      case r::kRegPeriod:
        if (v < r::kPeriodMinCycles) {
          status_ = r::kStatusBadWrite.put(status_, 1);
          return r::kErrBadValue;
        }
        period_cycles_ = v;
        break;
      case r::kRegStatus:
        status_ &= ~v;
        break;
      default:
        return r::kErrReadOnly;
    }
    if (cfg_.keep_history) writes_.push_back(AppliedWrite{addr, v});
    return 0;
  }

  static const regmap::Register* find(std::uint8_t addr) {
    for (const auto& r : regmap::kRegisters) {
      if (r.address == addr) return &r;
    }
    return nullptr;
  }

  void handle(const protocol::Frame& f) {
    using namespace protocol;
    if (const auto* rd = std::get_if<ReadReq>(&f)) {
      if (rd->addr == regmap::kRegSnapSeq) latch();
      const auto v = read_reg(rd->addr);
      if (v) {
        emit(ReadResp{rd->addr, *v});
      } else {
        emit(ErrorResp{regmap::kErrBadAddress, rd->addr});
      }
    } else if (const auto* wr = std::get_if<WriteReq>(&f)) {
      const std::uint8_t err = write_reg(wr->addr, wr->data);
      if (err) {
        emit(ErrorResp{err, wr->addr});
      } else {
        emit(WriteAck{wr->addr});
      }
    } else {    // SNAPSHOT_REQ: the parser lets nothing else through
      latch();  // the status byte is SNAP_STATUS: STATUS as it stood at that window's capture
      emit(SnapshotResp{latched_});
    }
  }

  mutable std::mutex mu_;
  ReferenceBoardConfig cfg_;
  CountScript script_;
  Rx rx_state_ = Rx::kHunt;
  std::vector<std::uint8_t> rx_frame_;  // LEN, TYPE, body: what the CRC covers
  std::uint8_t rx_crc_hi_ = 0;
  RxCounters rx_counters_;
  std::vector<std::uint8_t> tx_;
  std::size_t tx_head_ = 0;
  std::uint64_t tx_total_ = 0;
  std::vector<EmittedFrame> emitted_;
  std::vector<AppliedWrite> writes_;
  std::vector<protocol::Window> windows_;

  std::uint32_t control_ = 0;
  std::uint32_t filter_ = 0;
  std::uint32_t period_cycles_ = 0;
  std::uint32_t status_ = 0;
  std::uint32_t timestamp_ = 0;
  std::uint32_t seq_ = 0;
  std::uint8_t dir_ = 0;
  bool consumed_ = true;
  std::array<std::uint32_t, regmap::kChannels> position_{};
  std::array<std::uint32_t, regmap::kChannels> last_positions_{};
  std::array<std::uint32_t, regmap::kChannels> latched_positions_{};
  protocol::Window latched_;
  GyroScript gyro_;
  std::uint32_t gyro_faults_ = 0;
  bool gyro_running_ = true;
  bool gyro_absent_ = false;
};

}  // namespace omniloc::sim
