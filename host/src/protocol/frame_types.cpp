// CRC and the per-TYPE tables of the frame protocol, all derived from the generated regmap.hpp.
#include <cstdio>

#include "omniloc/protocol.hpp"

namespace omniloc::protocol {

namespace {

// One table step per byte instead of eight shifts: the decoder checks the CRC of every candidate
// frame, so this is the hot loop of frame parsing (tests/bench/bench_protocol.cpp).
constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> t{};
  for (unsigned i = 0; i < 256; ++i) {
    auto crc = static_cast<std::uint16_t>(i << 8);
    for (int b = 0; b < 8; ++b) {
      crc = (crc & 0x8000u) ? static_cast<std::uint16_t>((crc << 1) ^ regmap::kCrcPoly)
                            : static_cast<std::uint16_t>(crc << 1);
    }
    t[i] = crc;
  }
  return t;
}
constexpr auto kCrcTable = make_crc_table();

}  // namespace

std::uint16_t crc16_ccitt(std::span<const std::uint8_t> bytes, std::uint16_t crc) {
  for (const std::uint8_t b : bytes) {
    crc = static_cast<std::uint16_t>((crc << 8) ^
                                     kCrcTable[static_cast<std::uint8_t>((crc >> 8) ^ b)]);
  }
  return crc;
}

std::optional<std::size_t> body_bytes(std::uint8_t type) {
  switch (type) {
    case regmap::kFrameReadReq:
      return regmap::kFrameReadReqBodyBytes;
    case regmap::kFrameWriteReq:
      return regmap::kFrameWriteReqBodyBytes;
    case regmap::kFrameSnapshotReq:
      return regmap::kFrameSnapshotReqBodyBytes;
    case regmap::kFrameReadResp:
      return regmap::kFrameReadRespBodyBytes;
    case regmap::kFrameWriteAck:
      return regmap::kFrameWriteAckBodyBytes;
    case regmap::kFrameSnapshotResp:
      return regmap::kFrameSnapshotRespBodyBytes;
    case regmap::kFrameTelemetry:
      return regmap::kFrameTelemetryBodyBytes;
    case regmap::kFrameError:
      return regmap::kFrameErrorBodyBytes;
    default:
      return std::nullopt;
  }
}

std::string_view type_name(std::uint8_t type) {
  switch (type) {
    case regmap::kFrameReadReq:
      return "READ_REQ";
    case regmap::kFrameWriteReq:
      return "WRITE_REQ";
    case regmap::kFrameSnapshotReq:
      return "SNAPSHOT_REQ";
    case regmap::kFrameReadResp:
      return "READ_RESP";
    case regmap::kFrameWriteAck:
      return "WRITE_ACK";
    case regmap::kFrameSnapshotResp:
      return "SNAPSHOT_RESP";
    case regmap::kFrameTelemetry:
      return "TELEMETRY";
    case regmap::kFrameError:
      return "ERROR";
    default:
      return "UNKNOWN";
  }
}

std::string_view error_name(std::uint8_t code) {
  switch (code) {
    case regmap::kErrBadCrc:
      return "BAD_CRC";
    case regmap::kErrBadAddress:
      return "BAD_ADDRESS";
    case regmap::kErrMalformed:
      return "MALFORMED";
    case regmap::kErrReadOnly:
      return "READ_ONLY";
    case regmap::kErrBadValue:
      return "BAD_VALUE";
    default:
      return "UNKNOWN";
  }
}

std::string register_name(std::uint8_t addr) {
  for (const auto& r : regmap::kRegisters) {
    if (r.address == addr) return std::string(r.name);
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "0x%02X (unmapped)", addr);
  return buf;
}

}  // namespace omniloc::protocol
