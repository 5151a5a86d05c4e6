// Frame encoders: one body writer per TYPE, framing and CRC in one place.
#include "omniloc/protocol.hpp"

namespace omniloc::protocol {

namespace {

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void put_window(std::vector<std::uint8_t>& out, const Window& w) {
  put_u32(out, w.seq);
  put_u32(out, w.timestamp_cycles);
  for (const std::int32_t c : w.count) put_u32(out, static_cast<std::uint32_t>(c));
  out.push_back(w.dir);
  out.push_back(w.status);
}

struct BodyWriter {
  std::vector<std::uint8_t>& out;
  std::uint8_t operator()(const ReadReq& f) const {
    out.push_back(f.addr);
    return regmap::kFrameReadReq;
  }
  std::uint8_t operator()(const WriteReq& f) const {
    out.push_back(f.addr);
    put_u32(out, f.data);
    return regmap::kFrameWriteReq;
  }
  std::uint8_t operator()(const SnapshotReq&) const { return regmap::kFrameSnapshotReq; }
  std::uint8_t operator()(const ReadResp& f) const {
    out.push_back(f.addr);
    put_u32(out, f.data);
    return regmap::kFrameReadResp;
  }
  std::uint8_t operator()(const WriteAck& f) const {
    out.push_back(f.addr);
    return regmap::kFrameWriteAck;
  }
  std::uint8_t operator()(const SnapshotResp& f) const {
    put_window(out, f.window);
    return regmap::kFrameSnapshotResp;
  }
  std::uint8_t operator()(const Telemetry& f) const {
    put_window(out, f.window);
    return regmap::kFrameTelemetry;
  }
  std::uint8_t operator()(const ErrorResp& f) const {
    out.push_back(f.code);
    out.push_back(f.detail);
    return regmap::kFrameError;
  }
};

}  // namespace

void encode_into(const Frame& frame, std::vector<std::uint8_t>& out) {
  const std::size_t start = out.size();
  out.push_back(regmap::kFrameSync);
  out.push_back(0);  // LEN, patched below once the body size is known
  out.push_back(0);  // TYPE, likewise
  const std::uint8_t type = std::visit(BodyWriter{out}, frame);
  out[start + 1] = static_cast<std::uint8_t>(out.size() - start - 2);
  out[start + 2] = type;
  const std::uint16_t crc = crc16_ccitt(std::span(out).subspan(start + 1));
  out.push_back(static_cast<std::uint8_t>(crc >> 8));
  out.push_back(static_cast<std::uint8_t>(crc & 0xFF));
}

std::vector<std::uint8_t> encode(const Frame& frame) {
  std::vector<std::uint8_t> out;
  out.reserve(frame_bytes(regmap::kFrameTelemetryBodyBytes));
  encode_into(frame, out);
  return out;
}

}  // namespace omniloc::protocol
