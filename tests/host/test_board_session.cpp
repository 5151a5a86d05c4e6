// BoardSession against a scripted board written here from the protocol document (a register file
// that answers READ/WRITE requests and sends the telemetry frames the test queues), independent of
// the reference board and the RTL: the session's conversation (ID, VERSION, CONFIG, CONTROL, PERIOD
// reads, then one CONTROL write), its refusals (wrong ID, other major version, bad decoding, a
// robot with another number of wheels than the board's channels, a CONFIG out of range) and its
// window times across a 32-bit timestamp wrap, all against hand-computed values.
#include <gtest/gtest.h>

#include <map>
#include <vector>

#include "omniloc/board_session.hpp"
#include "omniloc/regmap.hpp"

namespace {

using namespace omniloc;
namespace r = omniloc::regmap;

struct Script {
  std::map<std::uint8_t, std::uint32_t> regs;
  std::vector<protocol::Frame> requests;           // in arrival order
  std::vector<std::vector<std::uint8_t>> pending;  // telemetry to send after the configuration
};

class ScriptedTransport final : public Transport {
 public:
  explicit ScriptedTransport(Script& s) : s_(s) {}
  void write(std::span<const std::uint8_t> bytes) override {
    decoder_.feed(bytes);
    while (auto f = decoder_.next()) {
      s_.requests.push_back(*f);
      if (const auto* rd = std::get_if<protocol::ReadReq>(&*f)) {
        answer(protocol::ReadResp{rd->addr, s_.regs[rd->addr]});
      } else if (const auto* wr = std::get_if<protocol::WriteReq>(&*f)) {
        s_.regs[wr->addr] = wr->data;
        answer(protocol::WriteAck{wr->addr});
      }
    }
  }
  std::size_t read(std::span<std::uint8_t> out, std::chrono::milliseconds) override {
    if (out_.empty() && !s_.pending.empty()) {
      out_ = s_.pending.front();
      s_.pending.erase(s_.pending.begin());
    }
    const std::size_t n = std::min(out.size(), out_.size());
    std::copy_n(out_.begin(), n, out.begin());
    out_.erase(out_.begin(), out_.begin() + static_cast<std::ptrdiff_t>(n));
    return n;
  }
  [[nodiscard]] TransportStatus status() const override {
    return {true, false, "scripted board", {}};
  }

 private:
  void answer(const protocol::Frame& f) {
    const auto b = protocol::encode(f);
    out_.insert(out_.end(), b.begin(), b.end());
  }
  Script& s_;
  protocol::FrameDecoder decoder_;
  std::vector<std::uint8_t> out_;
};

Script good_board() {
  Script s;
  s.regs[r::kRegId] = 0x4F4D4E4Cu;  // "OMNL", written out here rather than taken from regmap.hpp
  s.regs[r::kRegVersion] = r::kVersionValue;
  s.regs[r::kRegConfig] = 4;  // CONFIG.CHANNELS (bits 2:0): a four-wheel board
  s.regs[r::kRegControl] = 0;
  s.regs[r::kRegPeriod] = 120'000;  // 12 MHz board, 10 ms windows
  return s;
}

std::vector<std::uint8_t> telemetry(std::uint32_t seq, std::uint32_t ts,
                                    std::array<std::int32_t, 4> counts) {
  protocol::Window w;
  w.seq = seq;
  w.timestamp_cycles = ts;
  w.count = counts;
  return protocol::encode(protocol::Telemetry{w});
}

TEST(BoardSession, IdentifiesConfiguresForTheRobotsDecodingAndUnwrapsTime) {
  // DECODE (docs/REGISTER_MAP.md): x4 = 0, x2 = 1, x1 = 2.
  for (const auto& [decoding, field] : {std::pair{1, 2u}, std::pair{2, 1u}, std::pair{4, 0u}}) {
    Script s = good_board();
    BoardSessionOptions o;
    o.decoding = decoding;
    BoardSession session(std::make_unique<ScriptedTransport>(s), o);
    EXPECT_EQ(session.identity().clock_hz, 12e6);
    EXPECT_EQ(session.identity().period_cycles, 120'000u);
    // Five reads in this order, then one write of CONTROL = ENABLE | DECODE << 1 | STREAM << 3.
    ASSERT_EQ(s.requests.size(), 6u);
    const std::uint8_t order[] = {r::kRegId, r::kRegVersion, r::kRegConfig, r::kRegControl,
                                  r::kRegPeriod};
    for (int i = 0; i < 5; ++i)
      EXPECT_EQ(std::get<protocol::ReadReq>(s.requests[i]).addr, order[i]);
    EXPECT_EQ(session.identity().channels, 4);
    const auto& w = std::get<protocol::WriteReq>(s.requests[5]);
    EXPECT_EQ(w.addr, r::kRegControl);
    EXPECT_EQ(w.data, 0x1u | (field << 1) | (0x1u << 3)) << "decoding x" << decoding;
  }

  // Window times: the cycle counter wraps at 2^32 between the second and the third window.
  Script s = good_board();
  s.pending = {telemetry(7, 0xFFFF0000u, {1, -2, 3, -4}),
               telemetry(8, 0xFFFF0000u + 120'000u, {0, 0, 0, 0}),
               telemetry(9, 0xFFFF0000u + 240'000u, {5, 6, 7, 8})};
  BoardSession session(std::make_unique<ScriptedTransport>(s), BoardSessionOptions{});
  const auto a = session.next_window(std::chrono::milliseconds(5));
  const auto b = session.next_window(std::chrono::milliseconds(5));
  const auto c = session.next_window(std::chrono::milliseconds(5));
  ASSERT_TRUE(a && b && c);
  EXPECT_DOUBLE_EQ(a->board_ms, 0.0);
  EXPECT_DOUBLE_EQ(b->board_ms, 10.0);
  EXPECT_DOUBLE_EQ(c->board_ms, 20.0);  // 240000 cycles at 12 MHz, across the wrap
  const EncoderWindow ew = c->to_encoder_window(1000.0);
  EXPECT_EQ(ew.seq, 9u);
  EXPECT_DOUBLE_EQ(ew.t_end_ms, 1020.0);
  EXPECT_EQ(ew.counts, (std::array<std::int32_t, 4>{5, 6, 7, 8}));
  EXPECT_FALSE(session.next_window(std::chrono::milliseconds(1)).has_value());
}

TEST(BoardSession, RefusesAForeignBoardAnotherMajorVersionAndABadDecoding) {
  Script foreign = good_board();
  foreign.regs[r::kRegId] = 0x12345678u;
  try {
    BoardSession session(std::make_unique<ScriptedTransport>(foreign), BoardSessionOptions{});
    FAIL() << "a board with ID 0x12345678 was accepted";
  } catch (const BoardIdentityError& e) {
    EXPECT_NE(std::string(e.what()).find("scripted board: register ID reads 0x12345678"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(foreign.requests.size(), 1u) << "nothing but the ID read before refusing";

  Script newer = good_board();
  newer.regs[r::kRegVersion] =
      r::kVersionMajor.put(r::kVersionValue, r::kVersionMajor.get(r::kVersionValue) + 1);
  EXPECT_THROW(BoardSession(std::make_unique<ScriptedTransport>(newer), BoardSessionOptions{}),
               BoardIdentityError);
  EXPECT_EQ(newer.regs[r::kRegControl], 0u)
      << "a board of another major version must not be configured";

  // Below 1.0 a minor version changes the layout: the board of before CONFIG (0.2.0, which has no
  // channel count) is refused by this host (0.3.0), naming both versions.
  Script before_gyro = good_board();
  before_gyro.regs[r::kRegVersion] = r::kVersionMinor.put(r::kVersionValue, 2);
  try {
    BoardSession session(std::make_unique<ScriptedTransport>(before_gyro), BoardSessionOptions{});
    FAIL() << "a 0.2.0 board was accepted";
  } catch (const BoardIdentityError& e) {
    EXPECT_NE(std::string(e.what()).find("register map is version 0.2.0, this host speaks 0.3.0"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(before_gyro.regs[r::kRegControl], 0u)
      << "a board of another layout must not be configured";
  EXPECT_TRUE(version_compatible(0x000201u, 0x000200u));
  EXPECT_FALSE(version_compatible(0x000100u, 0x000200u));
  EXPECT_TRUE(version_compatible(0x010300u, 0x010200u))
      << "from 1.0 on a minor version is compatible";
  EXPECT_FALSE(version_compatible(0x020000u, 0x010000u));

  // A patch-level difference is accepted and reported.
  Script patched = good_board();
  patched.regs[r::kRegVersion] =
      r::kVersionPatch.put(r::kVersionValue, r::kVersionPatch.get(r::kVersionValue) + 1);
  BoardSession ok(std::make_unique<ScriptedTransport>(patched), BoardSessionOptions{});
  EXPECT_TRUE(version_differs(ok.identity()));

  Script s = good_board();
  BoardSessionOptions three;
  three.decoding = 3;
  EXPECT_THROW(BoardSession(std::make_unique<ScriptedTransport>(s), three), std::invalid_argument);
}

TEST(BoardSession, ConfigureFalseOnlyIdentifies) {
  Script s = good_board();
  s.regs[r::kRegControl] = 0x5;
  BoardSessionOptions o;
  o.configure = false;
  BoardSession session(std::make_unique<ScriptedTransport>(s), o);
  EXPECT_EQ(s.requests.size(), 5u) << "ID, VERSION, CONFIG, CONTROL, PERIOD: reads only";
  EXPECT_EQ(session.identity().control, 0x5u);
  EXPECT_EQ(s.regs[r::kRegControl], 0x5u);
}

TEST(BoardSession, TheBoardsChannelCountMustMatchTheRobotsWheels) {
  // A three-wheel board (CONFIG.CHANNELS = 3) with a four-wheel robot: refused, naming both, before
  // anything is configured; with a three-wheel robot accepted.
  Script three = good_board();
  three.regs[r::kRegConfig] = 3;
  BoardSessionOptions four_wheels;
  four_wheels.wheels = 4;
  try {
    BoardSession session(std::make_unique<ScriptedTransport>(three), four_wheels);
    FAIL() << "a 3-channel board was accepted for a 4-wheel robot";
  } catch (const BoardIdentityError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "the board counts 3 encoder channels but the robot config has 4"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(three.regs[r::kRegControl], 0u)
      << "a board that does not fit the robot must not be configured";
  BoardSessionOptions three_wheels;
  three_wheels.wheels = 3;
  BoardSession ok(std::make_unique<ScriptedTransport>(three), three_wheels);
  EXPECT_EQ(ok.identity().channels, 3);

  // The other way round: a four-channel board, a three-wheel robot.
  Script four = good_board();
  try {
    BoardSession session(std::make_unique<ScriptedTransport>(four), three_wheels);
    FAIL() << "a 4-channel board was accepted for a 3-wheel robot";
  } catch (const BoardIdentityError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "the board counts 4 encoder channels but the robot config has 3"),
              std::string::npos)
        << e.what();
  }

  // A CONFIG that no omniloc bitstream reads (0, 2, 5, 7 channels): refused naming the register.
  for (std::uint32_t bad : {0u, 2u, 5u, 7u, 0xFFFFFFF8u}) {
    Script s = good_board();
    s.regs[r::kRegConfig] = bad;
    try {
      BoardSession session(std::make_unique<ScriptedTransport>(s), BoardSessionOptions{});
      FAIL() << "CONFIG " << bad << " was accepted";
    } catch (const BoardIdentityError& e) {
      EXPECT_NE(std::string(e.what()).find("register CONFIG reads 0x"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("is not 3 or 4"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
