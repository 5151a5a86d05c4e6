// Frame encoders: the body of each TYPE is packed by its generated layout (frame_bodies.hpp);
// framing and CRC in one place.
#include "omniloc/protocol.hpp"

namespace omniloc::protocol {

namespace {

/// Appends the N body bytes of a frame TYPE and packs the body into them with its layout's pack();
/// a body whose layout is not N bytes long matches no pack() and does not compile.
template <std::size_t N, class Body>
void put_body(std::vector<std::uint8_t>& out, const Body& body) {
  const std::size_t at = out.size();
  out.resize(at + N);
  regmap::pack(body, std::span<std::uint8_t, N>(out.data() + at, N));
}

struct BodyWriter {
  std::vector<std::uint8_t>& out;
  std::uint8_t operator()(const ReadReq& f) const {
    put_body<regmap::kFrameReadReqBodyBytes>(out, f);
    return regmap::kFrameReadReq;
  }
  std::uint8_t operator()(const WriteReq& f) const {
    put_body<regmap::kFrameWriteReqBodyBytes>(out, f);
    return regmap::kFrameWriteReq;
  }
  std::uint8_t operator()(const SnapshotReq&) const { return regmap::kFrameSnapshotReq; }
  std::uint8_t operator()(const ReadResp& f) const {
    put_body<regmap::kFrameReadRespBodyBytes>(out, f);
    return regmap::kFrameReadResp;
  }
  std::uint8_t operator()(const WriteAck& f) const {
    put_body<regmap::kFrameWriteAckBodyBytes>(out, f);
    return regmap::kFrameWriteAck;
  }
  std::uint8_t operator()(const SnapshotResp& f) const {
    put_body<regmap::kFrameSnapshotRespBodyBytes>(out, f.window);
    return regmap::kFrameSnapshotResp;
  }
  std::uint8_t operator()(const Telemetry& f) const {
    put_body<regmap::kFrameTelemetryBodyBytes>(out, f.window);
    return regmap::kFrameTelemetry;
  }
  std::uint8_t operator()(const ErrorResp& f) const {
    put_body<regmap::kFrameErrorBodyBytes>(out, f);
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
