// Differential test: the C++ reference board (sim/include/omniloc_sim/reference_board.hpp), which
// the host tests and the emulated-USB test use as "the board", against the Verilated
// rtl/omniloc_top.v (sim::BoardSim) on the same byte streams: valid requests to every address,
// corrupted CRCs, truncated frames, bad lengths, unknown types, responses sent to the board, and
// random garbage dense in SYNC bytes. Seeded (printed; OMNILOC_SEED repeats another). Both must
// answer every item with the same bytes.
//
// Where timing legitimately differs, and how the test deals with it:
// - The reference board has no byte timing: it ends a frame left incomplete at the end of a
//   to_board() chunk (MALFORMED, detail 0xFF), where frame_rx ends it after an inter-byte gap of
//   FRAME_GAP_TIMEOUT_US. Each item is one chunk for the reference board, followed by an empty
//   chunk (the gap); the Verilated board gets the same bytes and then more than the gap of idle
//   line.
// - The reference board answers at once, the RTL at line rate: a garbage item can make the RTL send
//   error frames (70 us each) faster than 10 us bytes arrive, and frame_rx takes no byte while its
//   event waits, so back-to-back bytes would be dropped as UART overruns (as on the real board: the
//   host writes one request and waits). The Verilated board is therefore given one byte at a time,
//   each after the previous answer has left (gaps stay far below the 1 ms timeout).
// - TIMESTAMP is the RTL's free-running cycle counter; the reference board's advances only with
//   run_windows(). A READ_RESP of TIMESTAMP is compared with its data masked, and so are the gyro's
//   (GYRO_STATE, SNAP_GYRO_SUM, SNAP_GYRO, and a SNAPSHOT_RESP's gyro fields): the RTL's gyro
//   reader retries its start-up every 100 ms with nothing on its pins and its window rolls at every
//   tick, the reference board's gyro is scripted per window; everything else byte for byte. ENABLE
//   is never written (no window is captured: the reference board takes its counts from a script,
//   the RTL from its pins).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "omniloc_sim/reference_board.hpp"
#include "tb_support.hpp"

namespace {

namespace rm = omniloc::regmap;
namespace protocol = omniloc::protocol;
using omniloc::sim::BoardSim;
using Bytes = std::vector<std::uint8_t>;

constexpr std::int64_t kCyclesPerByte = 10 * BoardSim::kClockHz / BoardSim::kBaud;
constexpr std::int64_t kGapCycles =
    BoardSim::kClockHz / 1000 * static_cast<std::int64_t>(rm::kFrameGapTimeoutUs) / 1000;

/// Runs the Verilated board until its TX line has been quiet for three byte times (an answer starts
/// within a few dozen cycles of the byte that completes a request, so that is after the last
/// answer).
void run_until_quiet(BoardSim& board) {
  int quiet = 0;
  std::size_t pending = board.pending_from_board();
  while (quiet < 3) {
    board.run_cycles(kCyclesPerByte);
    const std::size_t now = board.pending_from_board();
    quiet = (now == pending) ? quiet + 1 : 0;
    pending = now;
  }
}

Bytes drain(omniloc::sim::UartSide& side) {
  Bytes out(4096);
  std::size_t n = 0;
  while (true) {
    const std::size_t got = side.from_board(std::span(out).subspan(n));
    if (got == 0) break;
    n += got;
    if (n == out.size()) out.resize(2 * n);
  }
  out.resize(n);
  return out;
}

/// The frames of an answer stream; the timing-dependent data (a READ_RESP of TIMESTAMP or of the
/// gyro's registers, a SNAPSHOT_RESP's gyro fields) zeroed.
struct Answer {
  std::vector<protocol::Frame> frames;
  bool masked = false;
  protocol::DecoderCounters counters;
};
Answer decode(const Bytes& bytes) {
  protocol::FrameDecoder d;
  d.feed(bytes);
  Answer a;
  while (auto f = d.next()) {
    if (auto* r = std::get_if<protocol::ReadResp>(&*f);
        r && (r->addr == rm::kRegTimestamp || r->addr == rm::kRegGyroState ||
              r->addr == rm::kRegSnapGyroSum || r->addr == rm::kRegSnapGyro)) {
      r->data = 0;
      a.masked = true;
    }
    if (auto* s = std::get_if<protocol::SnapshotResp>(&*f)) {
      s->window.gyro_sum = 0;
      s->window.gyro_count = 0;
      s->window.gyro_flags = 0;
      a.masked = true;
    }
    a.frames.push_back(*f);
  }
  a.counters = d.counters();
  return a;
}

std::string hex(const Bytes& b) {
  std::string s;
  char buf[4];
  for (const std::uint8_t x : b) {
    std::snprintf(buf, sizeof buf, "%02x ", x);
    s += buf;
  }
  return s;
}

/// Random items of the kinds the test covers, and the name of each kind.
class ItemGen {
 public:
  explicit ItemGen(std::uint64_t seed) : rng_(seed) {}

  std::pair<std::string, Bytes> next() {
    switch (pick(10)) {
      case 0:
        return {"read", protocol::encode(protocol::ReadReq{{addr()}})};
      case 1:
        return {"write", protocol::encode(write_req())};
      case 2:
        return {"snapshot", protocol::encode(protocol::SnapshotReq{})};
      case 3: {  // one byte after SYNC flipped: a bad CRC, or a LEN/TYPE that is no longer right
        Bytes f = valid_request();
        f[1 + pick(f.size() - 1)] ^= static_cast<std::uint8_t>(1 + pick(255));
        return {"corrupted", f};
      }
      case 4: {  // cut short: the board sees the gap
        Bytes f = valid_request();
        f.resize(1 + pick(f.size() - 1));
        return {"truncated", f};
      }
      case 5:
        return {"bad_len", bad_length()};
      case 6: {  // a well-formed frame of a type the board does not serve (a response, or unknown)
        const protocol::Frame frames[] = {protocol::ReadResp{{addr(), word()}},
                                          protocol::WriteAck{{addr()}}, protocol::ErrorResp{{1, 2}},
                                          protocol::Telemetry{}};
        Bytes f = protocol::encode(frames[pick(4)]);
        if (pick(2) == 0) f = with_type(f, static_cast<std::uint8_t>(pick(256)));
        return {"not_request", f};
      }
      case 7: {  // two requests in one chunk, back to back
        Bytes f = valid_request();
        const Bytes g = valid_request();
        f.insert(f.end(), g.begin(), g.end());
        return {"two_requests", f};
      }
      default:
        return {"garbage", garbage()};
    }
  }

 private:
  std::uint64_t pick(std::uint64_t n) {
    return std::uniform_int_distribution<std::uint64_t>(0, n - 1)(rng_);
  }

  /// Mostly mapped registers and the first unmapped ones, sometimes anything.
  std::uint8_t addr() {
    return static_cast<std::uint8_t>(pick(4) == 0 ? pick(256) : pick(rm::kRegisters.size() + 4));
  }

  /// Values at and around every register's limits, and random words.
  std::uint32_t word() {
    static constexpr std::uint32_t kEdges[] = {
        0,  1,  2,  3,   4,   6,       7,           8,           0xF,        0x10,
        63, 64, 65, 255, 256, 120'000, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu};
    return pick(3) == 0 ? static_cast<std::uint32_t>(rng_()) : kEdges[pick(std::size(kEdges))];
  }

  protocol::WriteReq write_req() {
    // Half of the writes go to the writable registers, where values are checked.
    static constexpr std::uint8_t kWritable[] = {rm::kRegControl, rm::kRegFilter, rm::kRegPeriod,
                                                 rm::kRegStatus};
    protocol::WriteReq w{{pick(2) == 0 ? kWritable[pick(4)] : addr(), word()}};
    // Never ENABLE: a captured window would come from the RTL's pins but from the reference
    // board's script. Every other bit of CONTROL, reserved ones included, is fair game.
    if (w.addr == rm::kRegControl) w.data = rm::kControlEnable.put(w.data, 0);
    return w;
  }

  Bytes valid_request() {
    switch (pick(3)) {
      case 0:
        return protocol::encode(protocol::ReadReq{{addr()}});
      case 1:
        return protocol::encode(write_req());
      default:
        return protocol::encode(protocol::SnapshotReq{});
    }
  }

  /// A frame with a new TYPE and a CRC that is right for it.
  static Bytes with_type(Bytes f, std::uint8_t type) {
    f[2] = type;
    return reframe(std::move(f));
  }
  /// Recomputes the CRC of SYNC, LEN, TYPE, body (+ 2 CRC bytes at the end).
  static Bytes reframe(Bytes f) {
    const std::uint16_t crc = protocol::crc16_ccitt(std::span(f).subspan(1, f.size() - 3));
    f[f.size() - 2] = static_cast<std::uint8_t>(crc >> 8);
    f[f.size() - 1] = static_cast<std::uint8_t>(crc & 0xFF);
    return f;
  }

  /// A request TYPE with a body of the wrong size and a right CRC, or a LEN of 0 or above the
  /// largest.
  Bytes bad_length() {
    if (pick(3) == 0) {
      const std::uint8_t len =
          pick(2) == 0 ? 0 : static_cast<std::uint8_t>(rm::kFrameWriteReqBodyBytes + 2 + pick(250));
      Bytes f{rm::kFrameSync, len};
      for (std::uint64_t i = 0, n = pick(8); i < n; ++i)
        f.push_back(static_cast<std::uint8_t>(pick(256)));
      return f;
    }
    static constexpr std::uint8_t kTypes[] = {rm::kFrameReadReq, rm::kFrameWriteReq,
                                              rm::kFrameSnapshotReq};
    const std::uint8_t type = kTypes[pick(3)];
    const auto right = *protocol::body_bytes(type);
    std::size_t body = pick(rm::kFrameWriteReqBodyBytes + 1);
    if (body == right) body = (body + 1) % (rm::kFrameWriteReqBodyBytes + 1);
    Bytes f{rm::kFrameSync, static_cast<std::uint8_t>(body + 1), type};
    for (std::size_t i = 0; i < body; ++i) f.push_back(addr());
    f.push_back(0);
    f.push_back(0);
    return reframe(std::move(f));
  }

  /// Random bytes, one in four a SYNC; sometimes with a valid request inside.
  Bytes garbage() {
    Bytes f;
    for (std::uint64_t i = 0, n = 1 + pick(40); i < n; ++i) {
      f.push_back(pick(4) == 0 ? rm::kFrameSync : static_cast<std::uint8_t>(pick(256)));
    }
    if (pick(3) == 0) {
      const Bytes r = valid_request();
      f.insert(f.begin() + static_cast<std::ptrdiff_t>(pick(f.size() + 1)), r.begin(), r.end());
    }
    return f;
  }

  std::mt19937_64 rng_;
};

TEST(ReferenceBoardVsRtl, SameAnswersToTheSameByteStreams) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 12);
  constexpr int kItems = 1500;
  ItemGen gen(seed);
  omniloc::sim::ReferenceBoard reference;
  BoardSim rtl;

  std::map<std::string, int> kinds;
  std::map<std::string, int> answers;  // by frame type, and ERROR by code
  std::uint64_t masked = 0;
  for (int i = 0; i < kItems; ++i) {
    const auto [kind, bytes] = gen.next();
    ++kinds[kind];

    reference.to_board(bytes);
    reference.to_board({});  // the gap after the chunk
    for (const std::uint8_t b : bytes) {
      rtl.to_board(std::span(&b, 1));
      run_until_quiet(rtl);
    }
    rtl.run_cycles(kGapCycles + 2 * kCyclesPerByte);
    run_until_quiet(rtl);

    const Bytes want = drain(reference);
    const Bytes got = drain(rtl);
    const Answer a = decode(want);
    const Answer b = decode(got);
    ASSERT_EQ(a.counters.resync_bytes, 0u) << "reference board sent something that is not a frame";
    ASSERT_EQ(b.counters.resync_bytes, 0u)
        << "RTL sent something that is not a frame: " << hex(got);
    if (!a.masked && !b.masked) {
      ASSERT_EQ(hex(got), hex(want))
          << "item " << i << " (" << kind << "): " << hex(bytes) << "(seed " << seed << ")";
    }
    ASSERT_EQ(b.frames, a.frames) << "item " << i << " (" << kind << "): " << hex(bytes)
                                  << "\n  reference: " << hex(want) << "\n  RTL:       " << hex(got)
                                  << "\n  (seed " << seed << ")";
    masked += a.masked ? 1 : 0;
    for (const auto& f : a.frames) {
      if (const auto* e = std::get_if<protocol::ErrorResp>(&f)) {
        ++answers[std::string("ERROR ") + std::string(protocol::error_name(e->code))];
      } else {
        ++answers[std::string(protocol::type_name(protocol::encode(f)[2]))];
      }
    }
  }
  // The pacing kept the RTL's receiver from dropping a byte (LINK_ERRORS reads 0 on both, compared
  // above whenever it was read), and its transmitter sent clean bytes.
  EXPECT_EQ(rtl.counters().tx_framing_errors, 0u);

  std::printf(
      "reference board vs RTL: %d items (seed %llu), %llu answers with TIMESTAMP or gyro data "
      "masked\n  items:",
      kItems, static_cast<unsigned long long>(seed), static_cast<unsigned long long>(masked));
  for (const auto& [k, n] : kinds) std::printf(" %s %d", k.c_str(), n);
  std::printf("\n  answers:");
  for (const auto& [k, n] : answers) std::printf(" %s %d", k.c_str(), n);
  std::printf("\n");
  // Every answer the board can give was compared at least a few times.
  for (const char* k :
       {"READ_RESP", "WRITE_ACK", "SNAPSHOT_RESP", "ERROR BAD_CRC", "ERROR MALFORMED",
        "ERROR BAD_ADDRESS", "ERROR READ_ONLY", "ERROR BAD_VALUE"}) {
    EXPECT_GE(answers[k], 10) << k;
  }
}

}  // namespace
