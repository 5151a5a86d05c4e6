// A byte pipe to the board: the USB bridge on the robot (UsbTransport), a simulated board in tests.
// The protocol layer and BoardClient only ever see this interface.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

namespace omniloc {

/// Why a transport operation failed.
enum class TransportErrorKind {
  kDeviceGone,  ///< the device was unplugged (LIBUSB_ERROR_NO_DEVICE): reopen to continue
  kIo,          ///< any other failure of the underlying channel
  kConfig,      ///< opening or configuring the channel failed
  kNotFound,    ///< no matching device
};

[[nodiscard]] const char* to_string(TransportErrorKind kind);

class TransportError : public std::runtime_error {
 public:
  TransportError(TransportErrorKind kind, const std::string& what)
      : std::runtime_error(what), kind_(kind) {}
  [[nodiscard]] TransportErrorKind kind() const { return kind_; }

 private:
  TransportErrorKind kind_;
};

/// Counters every transport keeps. Line-status errors are those the bridge reports per USB packet.
struct TransportCounters {
  std::uint64_t bytes_written = 0;
  std::uint64_t bytes_read = 0;
  std::uint64_t packets_in = 0;        ///< bridge packets received (USB: 512-byte bulk packets)
  std::uint64_t line_overrun = 0;      ///< packets flagged OE (bridge's receive buffer overran)
  std::uint64_t line_parity = 0;       ///< packets flagged PE
  std::uint64_t line_framing = 0;      ///< packets flagged FE
  std::uint64_t line_break = 0;        ///< packets flagged BI
  std::uint64_t rx_dropped_bytes = 0;  ///< bytes dropped because the host's receive buffer was full
  std::uint64_t write_timeouts = 0;
};

struct TransportStatus {
  bool open = false;
  bool device_gone = false;
  std::string description;  ///< e.g. "FT2232H 001/004 serial OL000001, channel B at 1000000 baud"
  TransportCounters counters;
};

class Transport {
 public:
  virtual ~Transport() = default;
  Transport() = default;
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  /// Sends all bytes or throws TransportError.
  virtual void write(std::span<const std::uint8_t> bytes) = 0;
  /// Returns the bytes available, waiting up to timeout for at least one; 0 bytes means timeout.
  /// Throws TransportError (kind kDeviceGone after an unplug, once buffered bytes are drained).
  virtual std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) = 0;
  [[nodiscard]] virtual TransportStatus status() const = 0;

  /// The clock that read() timeouts are measured in, and that BoardClient's deadlines use: wall
  /// time for real hardware; a simulated board's own time for a simulated one (so that a board
  /// simulated slower than real time never makes the host time out).
  [[nodiscard]] virtual std::chrono::steady_clock::time_point now() const {
    return std::chrono::steady_clock::now();
  }
};

}  // namespace omniloc
