// Golden frame encoding for the link testbenches, written from the frame description in
// common/regmap.json: SYNC, LEN = 1 + body bytes, TYPE, body, CRC-16/CCITT-FALSE over LEN, TYPE
// and body, high byte first.
#pragma once

#include <cstdint>
#include <vector>

#include "omniloc/regmap.hpp"

namespace omniloc::tb {

inline std::uint16_t golden_crc(const std::uint8_t* data, std::size_t n) {
  std::uint16_t crc = 0xFFFF;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= static_cast<std::uint16_t>(data[i] << 8);
    for (int b = 0; b < 8; ++b)
      crc = (crc & 0x8000u) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021u)
                            : static_cast<std::uint16_t>(crc << 1);
  }
  return crc;
}

inline std::vector<std::uint8_t> golden_frame(std::uint8_t type,
                                              const std::vector<std::uint8_t>& body) {
  std::vector<std::uint8_t> f;
  f.reserve(body.size() + 5);
  f.push_back(regmap::kFrameSync);
  f.push_back(static_cast<std::uint8_t>(body.size() + 1));
  f.push_back(type);
  for (const auto b : body) f.push_back(b);
  const std::uint16_t crc = golden_crc(f.data() + 1, f.size() - 1);
  f.push_back(static_cast<std::uint8_t>(crc >> 8));
  f.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  return f;
}

inline void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

}  // namespace omniloc::tb
