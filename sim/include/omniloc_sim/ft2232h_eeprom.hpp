// The identity an FT2232H EEPROM configuration gives a board, read from the `ftdi_eeprom` file in
// firmware/ (the single source of that identity). The emulated bridge takes its strings from it, so
// the tests check that the host finds a board programmed with exactly that file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace omniloc::sim {

struct EepromIdentity {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string manufacturer;
  std::string product;
  std::string serial;
  std::string channel_b_type;  ///< `chb_type`: UART, FIFO, ...
};

/// Reads an ftdi_eeprom configuration (`key=value` lines, "quoted" strings, # comments). Throws
/// std::runtime_error naming the file (and line) for an unreadable file, a line that is not
/// `key=value`, a key given twice, a bad number, or a missing vendor_id / product_id / manufacturer
/// / product / serial / chb_type.
[[nodiscard]] EepromIdentity read_eeprom_identity(const std::filesystem::path& conf);

}  // namespace omniloc::sim
