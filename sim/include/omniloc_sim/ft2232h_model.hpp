// The USB-bridge device model: an emulated FT2232H (0403:6010) on an emulated USB bus (umockdev,
// all in user space), so that libusb -- and UsbTransport, the exact code that runs on the robot --
// talks to it as to real hardware. Control requests are checked against what channel B as an 8N1
// UART needs; bulk OUT bytes on 0x04 go to a pluggable UartSide (the reference board model, later
// the Verilated board), bulk IN on 0x83 returns packets of [modem status, line status, data...], at
// most 512 bytes each, after data arrives or when the latency timer expires, as the chip does.
//
// Requires running under `umockdev-wrapper` (LD_PRELOAD of libumockdev-preload); built by
// tests/usb/CMakeLists.txt (library omniloc_usb_model) since it needs libumockdev.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "omniloc_sim/ft2232h_eeprom.hpp"
#include "omniloc_sim/uart_side.hpp"

namespace omniloc::sim {

/// An emulated USB bus: owns the umockdev testbed. Create it before any libusb context.
class EmulatedUsb {
 public:
  EmulatedUsb();  ///< throws std::runtime_error when not running under umockdev-wrapper
  ~EmulatedUsb();
  EmulatedUsb(const EmulatedUsb&) = delete;
  EmulatedUsb& operator=(const EmulatedUsb&) = delete;
  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

struct Ft2232hConfig {
  int bus = 1;
  int address = 2;
  // The strings of the chip's EEPROM. No defaults: an omniloc board gets them from
  // firmware/ft2232h_eeprom.conf (programmed_with), any other device from its test.
  std::string manufacturer;
  std::string product;
  std::string serial;
  bool kernel_driver_bound = true;   ///< ftdi_sio holds interface 1 until the host detaches it
  std::uint8_t modem_status = 0x31;  ///< first byte of every IN packet (CTS, DSR, low nibble 1)

  /// A chip whose EEPROM was written with this identity (read_eeprom_identity of the firmware
  /// file).
  [[nodiscard]] static Ft2232hConfig programmed_with(const EepromIdentity& eeprom) {
    Ft2232hConfig c;
    c.manufacturer = eeprom.manufacturer;
    c.product = eeprom.product;
    c.serial = eeprom.serial;
    return c;
  }
};

/// A vendor or standard control request the device received.
struct ControlRequest {
  std::uint8_t request_type = 0;
  std::uint8_t request = 0;
  std::uint16_t value = 0;
  std::uint16_t index = 0;
  std::uint16_t length = 0;
  bool accepted = true;  ///< false: the device stalled it (wrong channel, unknown request)
};

/// What the device saw and how it is configured now.
struct Ft2232hState {
  std::vector<ControlRequest> control;
  bool driver_detached = false;
  bool interface_claimed = false;
  int resets = 0;
  int purges_rx = 0;
  int purges_tx = 0;
  std::uint16_t baud_value = 0xFFFF;
  std::uint16_t baud_index = 0xFFFF;
  std::uint16_t data_characteristics = 0xFFFF;
  std::uint16_t flow_control = 0xFFFF;
  std::uint16_t latency_ms = 16;  ///< the chip's power-on value
  std::uint16_t bitmode = 0xFFFF;
  std::uint64_t bulk_out_bytes = 0;
  std::uint64_t bulk_in_packets = 0;
  std::uint64_t bulk_in_bytes = 0;  ///< payload bytes, status bytes excluded
  std::uint64_t status_only_packets = 0;
  std::vector<unsigned long> unhandled_ioctls;
  bool unplugged = false;
  /// True when the channel is set up as the host library must: channel B reset, purged both ways,
  /// UART bitmode, 8N1, no flow control.
  [[nodiscard]] bool configured_as_uart() const {
    return resets > 0 && purges_rx > 0 && purges_tx > 0 && bitmode == 0x0000 &&
           data_characteristics == 0x0008 && flow_control == 0x0000;
  }
};

class Ft2232hModel {
 public:
  /// Plugs the device into the bus; its UART side is uart (which must outlive the model).
  Ft2232hModel(EmulatedUsb& usb, UartSide& uart, Ft2232hConfig config = {});
  ~Ft2232hModel();
  Ft2232hModel(const Ft2232hModel&) = delete;
  Ft2232hModel& operator=(const Ft2232hModel&) = delete;

  /// Pulls the cable: URBs in flight complete with -ESHUTDOWN, every later request fails with
  /// ENODEV.
  void unplug();
  /// Sets line-status bits (OE 0x02, PE 0x04, FE 0x08, BI 0x10) on the next count IN packets.
  void inject_line_status(std::uint8_t bits, int count = 1);
  [[nodiscard]] Ft2232hState state() const;
  [[nodiscard]] std::string devnode() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace omniloc::sim
