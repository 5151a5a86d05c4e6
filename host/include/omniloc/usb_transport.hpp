// The board's USB bridge on the robot: FT2232H channel B as a UART, driven with libusb-1.0 directly
// (docs/PROTOCOL.md explains why not libftdi1). Finds the board by VID/PID and product string (and
// serial), configures the channel like libftdi would (reset, purge, H-series baud divisor, 8N1, no
// flow control, 1 ms latency timer), writes with bulk OUT and reads with asynchronous bulk IN,
// removing the two status bytes at the start of every packet and counting the line errors they
// report. An unplug (LIBUSB_ERROR_NO_DEVICE) surfaces as TransportError kDeviceGone so the caller
// can reconnect.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "omniloc/regmap.hpp"
#include "omniloc/transport.hpp"

namespace omniloc {

namespace ftdi {
inline constexpr std::uint16_t kVid = 0x0403;
inline constexpr std::uint16_t kPidFt2232h = 0x6010;
inline constexpr int kInterfaceB = 1;       ///< USB interface number of channel B
inline constexpr std::uint16_t kPortB = 2;  ///< channel B's index in wIndex of vendor requests
inline constexpr std::uint8_t kEpOutB = 0x04;
inline constexpr std::uint8_t kEpInB = 0x83;
// Vendor requests (bmRequestType 0x40: vendor, device, host to device).
inline constexpr std::uint8_t kRequestTypeOut = 0x40;
inline constexpr std::uint8_t kReqReset = 0;
inline constexpr std::uint8_t kReqSetModemCtrl = 1;
inline constexpr std::uint8_t kReqSetFlowCtrl = 2;
inline constexpr std::uint8_t kReqSetBaudRate = 3;
inline constexpr std::uint8_t kReqSetData = 4;
inline constexpr std::uint8_t kReqSetLatencyTimer = 9;
inline constexpr std::uint8_t kReqSetBitmode = 11;
inline constexpr std::uint16_t kResetSio = 0;
inline constexpr std::uint16_t kResetPurgeRx = 1;
inline constexpr std::uint16_t kResetPurgeTx = 2;
inline constexpr std::uint16_t kData8N1 = 0x0008;  ///< 8 bits | parity none << 8 | 1 stop << 11
// Second status byte of every bulk-IN packet.
inline constexpr std::uint8_t kLineOverrun = 0x02;
inline constexpr std::uint8_t kLineParity = 0x04;
inline constexpr std::uint8_t kLineFraming = 0x08;
inline constexpr std::uint8_t kLineBreak = 0x10;

/// wValue/wIndex of SET_BAUD_RATE for an H-series chip (FT2232H/FT4232H/FT232H), and the rate the
/// chip will really run at.
struct BaudSetting {
  std::uint16_t value = 0;
  std::uint16_t index = 0;
  std::uint32_t actual_baud = 0;
};

/// The H-series divisor encoding: 120 MHz / 10 base clock with bit 0x20000 set, a divisor in 1/8
/// steps whose fraction is coded {0,3,2,4,1,5,6,7}; below ~733 baud the 3 MHz/16 clock of the older
/// chips. Throws std::invalid_argument when the rate is out of range or the closest achievable rate
/// is more than 3 % off (a UART would not lock).
[[nodiscard]] BaudSetting h_series_baud(std::uint32_t baud, std::uint16_t port_index);
}  // namespace ftdi

/// A 0403:6010 device seen on the bus.
struct UsbBoardInfo {
  int bus = 0;
  int address = 0;
  std::string manufacturer;
  std::string product;
  std::string serial;
  /// product string matches the one the EEPROM of an omniloc board carries
  bool is_omniloc = false;
  std::string error;  ///< why its strings could not be read (e.g. LIBUSB_ERROR_ACCESS), else empty
};

struct UsbTransportOptions {
  std::string product = "omniloc encoder board";
  std::string serial;                      ///< empty: the first board found
  std::uint32_t baud = regmap::kUartBaud;  ///< the board's UART rate (common/regmap.json "link")
  std::uint8_t latency_ms = 1;
  std::chrono::milliseconds io_timeout{500};  ///< control and bulk-OUT transfers
  int in_transfers = 4;                       ///< bulk-IN transfers kept in flight
  int in_transfer_bytes = 4096;               ///< several 512-byte packets per transfer
  /// host-side buffer; beyond it bytes are dropped and counted
  std::size_t rx_buffer_bytes = 1 << 20;
};

/// Lists every FT2232H (0403:6010) on the bus, omniloc boards flagged.
[[nodiscard]] std::vector<UsbBoardInfo> find_usb_boards(
    const std::string& product = UsbTransportOptions{}.product);

class UsbTransport final : public Transport {
 public:
  /// Opens and configures the board; throws TransportError (kNotFound, kConfig, kDeviceGone).
  explicit UsbTransport(UsbTransportOptions options = {});
  ~UsbTransport() override;

  void write(std::span<const std::uint8_t> bytes) override;
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds timeout) override;
  [[nodiscard]] TransportStatus status() const override;
  [[nodiscard]] const UsbBoardInfo& board() const;
  [[nodiscard]] std::uint32_t actual_baud() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace omniloc
