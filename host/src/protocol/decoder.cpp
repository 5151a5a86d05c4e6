// The streaming frame decoder: SYNC hunt, LEN/TYPE check, CRC check, body decode, sequence
// tracking.
#include <algorithm>

#include "omniloc/protocol.hpp"

namespace omniloc::protocol {

namespace {

/// The first N bytes of a body whose length the caller has checked, as the layout's fixed-size
/// span.
template <std::size_t N>
std::span<const std::uint8_t, N> as_layout(std::span<const std::uint8_t> b) {
  return b.first<N>();
}

}  // namespace

Frame decode_body(std::uint8_t type, std::span<const std::uint8_t> b) {
  namespace r = regmap;
  switch (type) {
    case r::kFrameReadReq:
      return ReadReq{r::unpack_reg_addr(as_layout<r::kFrameReadReqBodyBytes>(b))};
    case r::kFrameWriteReq:
      return WriteReq{r::unpack_reg_value(as_layout<r::kFrameWriteReqBodyBytes>(b))};
    case r::kFrameSnapshotReq:
      return SnapshotReq{};
    case r::kFrameReadResp:
      return ReadResp{r::unpack_reg_value(as_layout<r::kFrameReadRespBodyBytes>(b))};
    case r::kFrameWriteAck:
      return WriteAck{r::unpack_reg_addr(as_layout<r::kFrameWriteAckBodyBytes>(b))};
    case r::kFrameSnapshotResp:
      return SnapshotResp{r::unpack_window(as_layout<r::kFrameSnapshotRespBodyBytes>(b))};
    case r::kFrameTelemetry:
      return Telemetry{r::unpack_window(as_layout<r::kFrameTelemetryBodyBytes>(b))};
    default:
      return ErrorResp{r::unpack_error(as_layout<r::kFrameErrorBodyBytes>(
          b))};  // the caller has checked type is one of the eight
  }
}

SequenceTracker::Step SequenceTracker::observe(std::uint32_t seq) {
  Step step;
  if (last_) {
    // Modular distance: forward steps below 2^31 are progress, the rest are stale or repeated.
    const std::uint32_t ahead = seq - *last_;
    if (ahead == 0 || ahead >= 0x80000000u) {
      step.accepted = false;
      return step;
    }
    step.missing = ahead - 1;
  }
  last_ = seq;
  return step;
}

void FrameDecoder::feed(std::span<const std::uint8_t> bytes) {
  compact();
  buf_.insert(buf_.end(), bytes.begin(), bytes.end());
}

void FrameDecoder::compact() {
  // Keep the buffer from growing without bound while avoiding a memmove per frame.
  if (head_ > 0 && (head_ == buf_.size() || head_ >= 4096)) {
    buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(head_));
    head_ = 0;
  }
}

std::optional<Frame> FrameDecoder::next() {
  while (true) {
    const auto begin = buf_.begin() + static_cast<std::ptrdiff_t>(head_);
    const auto sync = std::find(begin, buf_.end(), regmap::kFrameSync);
    const auto skipped = static_cast<std::size_t>(sync - begin);
    counters_.resync_bytes += skipped;
    head_ += skipped;
    const std::size_t avail = buf_.size() - head_;
    if (avail < 3) return std::nullopt;
    const std::uint8_t len = buf_[head_ + 1];
    const std::uint8_t type = buf_[head_ + 2];
    const auto body = body_bytes(type);
    if (!body) {
      ++counters_.unknown_type;
      ++counters_.resync_bytes;
      ++head_;  // drop this SYNC only: a real frame may start in the bytes that follow
      continue;
    }
    if (len != *body + 1) {
      ++counters_.bad_length;
      ++counters_.resync_bytes;
      ++head_;
      continue;
    }
    const std::size_t total = frame_bytes(*body);
    if (avail < total) return std::nullopt;
    const std::span<const std::uint8_t> frame(buf_.data() + head_, total);
    const std::uint16_t crc = crc16_ccitt(frame.subspan(1, total - 3));
    const std::uint16_t got =
        static_cast<std::uint16_t>((frame[total - 2] << 8) | frame[total - 1]);
    if (crc != got) {
      ++counters_.bad_crc;
      ++counters_.resync_bytes;
      ++head_;
      continue;
    }
    head_ += total;
    ++counters_.frames_ok;
    Frame f = decode_body(type, frame.subspan(3, *body));
    if (const auto* t = std::get_if<Telemetry>(&f)) {
      const auto step = seq_.observe(t->window.seq);
      if (!step.accepted) {
        ++counters_.telemetry_stale;
        continue;
      }
      if (step.missing > 0) {
        ++counters_.telemetry_gaps;
        counters_.telemetry_lost += step.missing;
      }
    }
    return f;
  }
}

}  // namespace omniloc::protocol
