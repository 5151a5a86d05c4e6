// A byte-level fault injector between a UART side and the host, in both directions: corrupts, drops
// and truncates (drops a run of bytes, as when a frame is cut short). Seeded and logged, so a test
// can tell exactly which frames were damaged and check that the host saw every loss.
#pragma once

#include <cstdint>
#include <random>
#include <span>
#include <vector>

#include "omniloc_sim/uart_side.hpp"

namespace omniloc::sim {

struct FaultRates {
  double corrupt_per_byte = 0.0;   ///< xor with a random non-zero mask
  double drop_per_byte = 0.0;      ///< the byte vanishes
  double truncate_per_byte = 0.0;  ///< this byte and up to truncate_max_bytes - 1 following vanish
  int truncate_max_bytes = 24;
};

/// Every fault injected in one direction, by byte offset in the undisturbed stream.
struct FaultLog {
  std::uint64_t corrupted = 0;
  std::uint64_t dropped = 0;  ///< single drops plus every byte of each truncation
  std::uint64_t truncations = 0;
  std::vector<std::uint64_t>
      damaged_offsets;  ///< sorted: offsets of every corrupted or removed byte
  std::uint64_t bytes_seen = 0;
};

/// Applies faults to a byte stream; keeps state across chunks (a truncation may span chunks).
class FaultChannel {
 public:
  FaultChannel(FaultRates rates, std::uint64_t seed) : rates_(rates), rng_(seed) {}

  /// Appends the disturbed version of in to out.
  void apply(std::span<const std::uint8_t> in, std::vector<std::uint8_t>& out) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (const std::uint8_t b : in) {
      const std::uint64_t at = log_.bytes_seen++;
      if (truncating_ > 0) {  // a truncation under way completes even after faults are disabled
        --truncating_;
        ++log_.dropped;
        log_.damaged_offsets.push_back(at);
        continue;
      }
      if (!enabled_) {
        out.push_back(b);
        continue;
      }
      const double x = u(rng_);
      if (x < rates_.truncate_per_byte) {
        ++log_.truncations;
        truncating_ = std::uniform_int_distribution<int>(0, rates_.truncate_max_bytes - 1)(rng_);
        ++log_.dropped;
        log_.damaged_offsets.push_back(at);
      } else if (x < rates_.truncate_per_byte + rates_.drop_per_byte) {
        ++log_.dropped;
        log_.damaged_offsets.push_back(at);
      } else if (x < rates_.truncate_per_byte + rates_.drop_per_byte + rates_.corrupt_per_byte) {
        ++log_.corrupted;
        log_.damaged_offsets.push_back(at);
        out.push_back(
            static_cast<std::uint8_t>(b ^ std::uniform_int_distribution<int>(1, 255)(rng_)));
      } else {
        out.push_back(b);
      }
    }
  }

  /// Faults stop (a running truncation still completes): lets a test end on a clean stream.
  void set_enabled(bool on) { enabled_ = on; }
  [[nodiscard]] const FaultLog& log() const { return log_; }

 private:
  FaultRates rates_;
  std::mt19937_64 rng_;
  FaultLog log_;
  int truncating_ = 0;
  bool enabled_ = true;
};

/// A UartSide that disturbs the bytes going to and coming from another UartSide.
class FaultyUart final : public UartSide {
 public:
  FaultyUart(UartSide& inner, FaultRates to_board, FaultRates from_board, std::uint64_t seed)
      : inner_(inner),
        to_board_(to_board, seed),
        from_board_(from_board, seed ^ 0x9E3779B97F4A7C15ull) {}

  void to_board(std::span<const std::uint8_t> bytes) override {
    scratch_.clear();
    to_board_.apply(bytes, scratch_);
    if (!scratch_.empty()) inner_.to_board(scratch_);
  }

  std::size_t from_board(std::span<std::uint8_t> out) override {
    while (pending_.size() < out.size()) {
      std::uint8_t buf[256];
      const std::size_t n = inner_.from_board(std::span<std::uint8_t>(buf, sizeof buf));
      if (n == 0) break;
      from_board_.apply(std::span<const std::uint8_t>(buf, n), pending_);
    }
    const std::size_t n = std::min(out.size(), pending_.size());
    std::copy_n(pending_.begin(), n, out.begin());
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n));
    return n;
  }

  void set_enabled(bool on) {
    to_board_.set_enabled(on);
    from_board_.set_enabled(on);
  }
  [[nodiscard]] const FaultLog& to_board_log() const { return to_board_.log(); }
  [[nodiscard]] const FaultLog& from_board_log() const { return from_board_.log(); }

 private:
  UartSide& inner_;
  FaultChannel to_board_;
  FaultChannel from_board_;
  std::vector<std::uint8_t> scratch_;
  std::vector<std::uint8_t> pending_;
};

}  // namespace omniloc::sim
