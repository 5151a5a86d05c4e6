// Harness: the board link's streaming frame decoder (protocol.hpp FrameDecoder) on any byte stream.
// The first byte chooses how the rest is cut into chunks (1..64 bytes, varying); the frames the
// decoder returns must be exactly those an independent whole-buffer reading of docs/PROTOCOL.md
// finds (below, with its own CRC), the byte accounting of DecoderCounters must add up, and every
// returned frame must re-encode to the bytes it was read from.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "fuzz_common.hpp"
#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"

namespace {

using omniloc::fuzz::fuzz_check;
namespace protocol = omniloc::protocol;
namespace regmap = omniloc::regmap;

std::uint16_t reference_crc(std::span<const std::uint8_t> bytes) {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t b : bytes) {
    crc ^= static_cast<std::uint16_t>(b << 8);
    for (int i = 0; i < 8; ++i)
      crc = static_cast<std::uint16_t>((crc & 0x8000) ? (crc << 1) ^ 0x1021 : crc << 1);
  }
  return crc;
}

/// The frames in `s` as the protocol defines them, read from the whole buffer at once: at a SYNC
/// with a known TYPE, the LEN of that TYPE and a good CRC, a frame; otherwise move one byte on.
/// Stops at a candidate cut off by the end (the streaming decoder waits for its remaining bytes).
/// Telemetry not newer than the last accepted one (32-bit modular order) is dropped.
struct Reference {
  std::vector<std::vector<std::uint8_t>> frames;  // wire bytes of each frame returned
  std::size_t consumed = 0;                       // bytes before the first undecided one
  std::uint64_t stale = 0;
};

Reference reference_decode(std::span<const std::uint8_t> s) {
  Reference r;
  std::optional<std::uint32_t> last_seq;
  std::size_t i = 0;
  while (i < s.size()) {
    if (s[i] != regmap::kFrameSync) {
      ++i;
      continue;
    }
    if (s.size() - i < 3) break;
    const auto body = protocol::body_bytes(s[i + 2]);
    if (!body || s[i + 1] != *body + 1) {
      ++i;
      continue;
    }
    const std::size_t total = *body + 5;
    if (s.size() - i < total) break;
    const std::uint16_t got =
        static_cast<std::uint16_t>((s[i + total - 2] << 8) | s[i + total - 1]);
    if (reference_crc(s.subspan(i + 1, total - 3)) != got) {
      ++i;
      continue;
    }
    const auto frame = s.subspan(i, total);
    i += total;
    if (frame[2] == regmap::kFrameTelemetry) {
      const std::uint32_t seq =
          static_cast<std::uint32_t>(frame[3]) | static_cast<std::uint32_t>(frame[4]) << 8 |
          static_cast<std::uint32_t>(frame[5]) << 16 | static_cast<std::uint32_t>(frame[6]) << 24;
      if (last_seq && static_cast<std::uint32_t>(seq - *last_seq) - 1u >= 0x7FFFFFFFu) {
        ++r.stale;
        continue;
      }
      last_seq = seq;
    }
    r.frames.emplace_back(frame.begin(), frame.end());
  }
  r.consumed = i;
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const unsigned chunk_seed = data[0];
  const std::span<const std::uint8_t> stream(data + 1, size - 1);

  protocol::FrameDecoder decoder;
  std::vector<std::vector<std::uint8_t>> got;
  std::size_t fed = 0;
  unsigned k = 0;
  while (fed < stream.size()) {
    const std::size_t chunk = 1 + (chunk_seed * 31u + k++ * 17u) % 64u;
    const std::size_t n = std::min(chunk, stream.size() - fed);
    decoder.feed(stream.subspan(fed, n));
    fed += n;
    while (const auto frame = decoder.next()) got.push_back(protocol::encode(*frame));
  }

  const Reference ref = reference_decode(stream);
  fuzz_check(got == ref.frames,
             "the decoder's frames differ from the reference reading of the stream");
  const auto& c = decoder.counters();
  fuzz_check(c.telemetry_stale == ref.stale, "telemetry_stale differs from the reference");
  fuzz_check(c.frames_ok == ref.frames.size() + ref.stale,
             "frames_ok is not returned + stale frames");
  std::uint64_t accepted_bytes =
      ref.stale * protocol::frame_bytes(regmap::kFrameTelemetryBodyBytes);
  for (const auto& f : ref.frames) accepted_bytes += f.size();
  fuzz_check(accepted_bytes + c.resync_bytes + decoder.pending_bytes() == stream.size(),
             "accepted + resync + pending bytes != bytes fed");
  fuzz_check(decoder.pending_bytes() == stream.size() - ref.consumed,
             "pending bytes differ from the reference");
  return 0;
}
