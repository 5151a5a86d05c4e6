// BoardClient against the reference board model (the golden model of the board protocol): register
// reads and writes, errors naming the register, snapshots, streamed telemetry and wrap-safe
// positions.
#include <gtest/gtest.h>

#include <string>

#include "omniloc/board_client.hpp"
#include "omniloc_sim/reference_board.hpp"

namespace omniloc {
namespace {

namespace r = regmap;

std::array<std::int32_t, 4> script(std::uint32_t seq) {
  const auto s = static_cast<std::int32_t>(seq);
  return {s * 3, -s, 1000 - s, (s % 2) ? 7 : -7};
}

struct Rig {
  explicit Rig(sim::ReferenceBoardConfig cfg = {})
      : board(cfg, script), link(board), client(link, fast()) {}
  static BoardClientOptions fast() {
    BoardClientOptions o;
    o.response_timeout = std::chrono::milliseconds(5);
    return o;
  }
  sim::ReferenceBoard board;
  sim::UartSideTransport link;
  BoardClient client;
};

TEST(BoardClient, ReadsIdVersionAndResetValues) {
  Rig rig;
  EXPECT_EQ(rig.client.read_register(r::kRegId), 0x4F4D4E4Cu);
  EXPECT_EQ(rig.client.read_register(r::kRegVersion), 0x00000300u);  // 0.3.0: CONFIG.CHANNELS
  EXPECT_EQ(rig.client.read_register(r::kRegPeriod),
            120'000u);  // 12 MHz / 100 Hz (the board clock of common/regmap.json)
  EXPECT_EQ(rig.client.read_register(r::kRegControl), 0u);
  EXPECT_EQ(rig.client.counters().retries, 0u);
}

TEST(BoardClient, WritesReachTheBoard) {
  Rig rig;
  rig.client.write_register(r::kRegFilter, 12);
  rig.client.write_register(r::kRegPeriod, 40'000);
  EXPECT_EQ(rig.board.reg(r::kRegFilter), 12u);
  EXPECT_EQ(rig.client.read_register(r::kRegPeriod), 40'000u);
}

TEST(BoardClient, ErrorsNameTheRegister) {
  Rig rig;
  try {
    rig.client.write_register(r::kRegId, 1);
    FAIL() << "write to ID accepted";
  } catch (const BoardError& e) {
    EXPECT_EQ(e.error_code(), r::kErrReadOnly);
    EXPECT_NE(std::string(e.what()).find("register ID"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("READ_ONLY"), std::string::npos) << e.what();
  }
  try {
    (void)rig.client.read_register(0x3F);
    FAIL() << "read of unmapped 0x3F accepted";
  } catch (const BoardError& e) {
    EXPECT_EQ(e.error_code(), r::kErrBadAddress);
    EXPECT_NE(std::string(e.what()).find("0x3F (unmapped)"), std::string::npos) << e.what();
  }
  try {
    rig.client.write_register(r::kRegPeriod, r::kPeriodMinCycles - 1);
    FAIL() << "too-short PERIOD accepted";
  } catch (const BoardError& e) {
    EXPECT_EQ(e.error_code(), r::kErrBadValue);
    EXPECT_NE(std::string(e.what()).find("PERIOD"), std::string::npos) << e.what();
  }
  EXPECT_EQ(rig.board.reg(r::kRegPeriod), 120'000u);  // refused whole
  EXPECT_EQ(r::kStatusBadWrite.get(rig.client.read_register(r::kRegStatus)), 1u);
  rig.client.write_register(r::kRegStatus, r::kStatusBadWrite.mask());  // W1C
  EXPECT_EQ(rig.client.read_register(r::kRegStatus), 0u);
}

/// A UART side that never answers: the client must give up after its attempts, naming the register.
struct Silent final : sim::UartSide {
  void to_board(std::span<const std::uint8_t> b) override { received += b.size(); }
  std::size_t from_board(std::span<std::uint8_t>) override { return 0; }
  std::size_t received = 0;
};

TEST(BoardClient, GivesUpAfterItsAttempts) {
  Silent silent;
  sim::UartSideTransport link(silent);
  BoardClientOptions o;
  o.response_timeout = std::chrono::milliseconds(2);
  o.attempts = 3;
  BoardClient client(link, o);
  try {
    (void)client.read_register(r::kRegTimestamp);
    FAIL();
  } catch (const BoardError& e) {
    EXPECT_EQ(e.error_code(), 0);
    EXPECT_NE(std::string(e.what()).find("TIMESTAMP"), std::string::npos) << e.what();
  }
  EXPECT_EQ(silent.received, 3 * protocol::frame_bytes(1));
  EXPECT_EQ(client.counters().timeouts, 3u);
  EXPECT_EQ(client.counters().retries, 2u);
}

TEST(BoardClient, SnapshotAndRegistersDescribeTheSameWindow) {
  sim::ReferenceBoardConfig cfg;
  cfg.initial_position = {0xFFFFFF00u, 0x00000010u, 0x7FFFFFF0u, 0};
  Rig rig(cfg);
  rig.client.write_register(r::kRegControl, r::kControlEnable.mask());
  rig.board.run_windows(5);
  const auto w = rig.client.snapshot();
  const auto ref = rig.board.windows().back();
  EXPECT_EQ(w.seq, 5u);
  EXPECT_EQ(w.count, ref.count);
  EXPECT_EQ(w.count, script(5));
  EXPECT_EQ(w.timestamp_cycles, 5u * 120'000u);
  EXPECT_EQ(w.dir, 0b0010);  // channel 1 counts down; channel 3 (+7 in odd windows) up
  // Register path: reading SNAP_SEQ latches the same window.
  EXPECT_EQ(rig.client.read_register(r::kRegSnapSeq), 5u);
  EXPECT_EQ(static_cast<std::int32_t>(rig.client.read_register(r::kRegSnapCount1)), -5);
  // Positions: initial + sum of counts 1..5, reconstructed across the wrap.
  protocol::PositionUnwrapper p0;
  p0.update(cfg.initial_position[0]);
  EXPECT_EQ(p0.update(rig.client.read_register(r::kRegSnapPosition0)), -256 + 3 * 15);
  protocol::PositionUnwrapper p2;
  p2.update(cfg.initial_position[2]);
  EXPECT_EQ(p2.update(rig.client.read_register(r::kRegSnapPosition2)), 0x7FFFFFF0ll + 5000 - 15);
}

TEST(BoardClient, StreamsTelemetryWithScriptedCounts) {
  Rig rig;
  rig.client.write_register(r::kRegControl, r::kControlEnable.mask());
  rig.client.set_streaming(true);
  EXPECT_EQ(rig.board.reg(r::kRegControl), r::kControlEnable.mask() | r::kControlStream.mask());
  rig.board.run_windows(100);
  protocol::TimestampUnwrapper clock(12'000'000.0);
  for (std::uint32_t seq = 1; seq <= 100; ++seq) {
    const auto w = rig.client.poll_telemetry(std::chrono::milliseconds(20));
    ASSERT_TRUE(w.has_value()) << seq;
    EXPECT_EQ(w->seq, seq);
    EXPECT_EQ(w->count, script(seq));
    clock.update(w->timestamp_cycles);
  }
  EXPECT_DOUBLE_EQ(clock.elapsed_ms(), 990.0);  // 99 windows of 10 ms between the first and last
  EXPECT_FALSE(rig.client.poll_telemetry(std::chrono::milliseconds(2)).has_value());
  EXPECT_EQ(rig.client.decoder_counters().telemetry_gaps, 0u);
  // Telemetry that arrives while a register read waits is kept, not lost.
  rig.board.run_windows(3);
  EXPECT_EQ(rig.client.read_register(r::kRegId), r::kIdValue);
  for (std::uint32_t seq = 101; seq <= 103; ++seq) {
    const auto w = rig.client.poll_telemetry(std::chrono::milliseconds(5));
    ASSERT_TRUE(w.has_value());
    EXPECT_EQ(w->seq, seq);
  }
  rig.client.set_streaming(false);
  rig.board.run_windows(2);
  EXPECT_FALSE(rig.client.poll_telemetry(std::chrono::milliseconds(2)).has_value());
}

TEST(BoardClient, BoardAnswersMalformedRequests) {
  sim::ReferenceBoard board;
  // A response frame sent to the board is well-formed but not a request.
  board.to_board(protocol::encode(protocol::WriteAck{0x02}));
  // A corrupted request: the board must not act on it.
  auto bad = protocol::encode(protocol::WriteReq{r::kRegFilter, 99});
  bad[4] ^= 0x40;
  board.to_board(bad);
  std::vector<std::uint8_t> out(256);
  out.resize(board.from_board(out));
  protocol::FrameDecoder d;
  d.feed(out);
  const auto f1 = d.next();
  const auto f2 = d.next();
  ASSERT_TRUE(f1 && f2);
  EXPECT_EQ(std::get<protocol::ErrorResp>(*f1),
            (protocol::ErrorResp{r::kErrMalformed, r::kFrameWriteAck}));
  EXPECT_EQ(std::get<protocol::ErrorResp>(*f2),
            (protocol::ErrorResp{r::kErrBadCrc, r::kFrameWriteReq}));
  EXPECT_EQ(board.reg(r::kRegFilter), 0u);
  EXPECT_TRUE(board.applied_writes().empty());
  EXPECT_EQ(board.rx_counters().bad_crc, 1u);
  EXPECT_EQ(board.rx_counters().malformed, 1u);
}

}  // namespace
}  // namespace omniloc
