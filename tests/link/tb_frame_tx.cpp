// frame_tx against the golden frame encoder: random types and bodies of 0..26 bytes, a receiver
// that stalls at random, type and length that change while a frame is on the line, and the body
// served byte by byte through body_idx_o / body_byte_i (garbage outside the frame's body).
#include <gtest/gtest.h>

#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "Vframe_tx.h"
#include "golden_frames.hpp"
#include "tb_clocked.hpp"

namespace {

constexpr int kMaxBody = 26;

struct Frame {
  std::uint8_t type;
  std::vector<std::uint8_t> body;
};

std::vector<std::uint8_t> run(const std::vector<Frame>& frames, std::uint64_t seed,
                              const std::string& vcd = {}) {
  const omniloc::rtl_tb::TraceRequest trace{vcd, 0};
  omniloc::rtl_tb::Clocked<Vframe_tx> bench(vcd.empty() ? nullptr : &trace);
  auto& dut = bench.io();
  std::mt19937_64 rng(seed);
  bench.reset();
  std::vector<std::uint8_t> out;
  std::size_t next = 0;
  int idle = 0;
  const std::vector<std::uint8_t>* body =
      nullptr;  // the body frame_tx is sending (held by the caller)
  for (std::uint64_t guard = 0; guard < 10'000'000; ++guard) {
    dut.start_i = 0;
    if (dut.ready_o) body = nullptr;
    if (next < frames.size() && dut.ready_o) {
      dut.start_i = 1;
      dut.type_i = frames[next].type;
      dut.body_len_i = static_cast<std::uint8_t>(frames[next].body.size());
      body = &frames[next].body;
    } else {
      // Garbage on type and length while nothing starts: it must not leak into the frame on the
      // line.
      dut.type_i = static_cast<std::uint8_t>(rng());
      dut.body_len_i = static_cast<std::uint8_t>(rng() % (kMaxBody + 1));
    }
    const unsigned idx = dut.body_idx_o;
    dut.body_byte_i =
        (body != nullptr && idx < body->size()) ? (*body)[idx] : static_cast<std::uint8_t>(rng());
    dut.byte_ready_i = (rng() % 4) != 0;
    const bool started = dut.start_i && dut.ready_o;
    if (dut.byte_valid_o && dut.byte_ready_i) out.push_back(dut.byte_o);
    bench.step();
    if (started) ++next;
    idle = (next >= frames.size() && dut.ready_o && !dut.byte_valid_o) ? idle + 1 : 0;
    if (idle > 4) break;
  }
  return out;
}

TEST(FrameTx, RandomFramesMatchGoldenEncoding) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 31);
  std::mt19937_64 rng(seed);
  std::vector<Frame> frames(2000);
  std::vector<std::uint8_t> expected;
  for (auto& f : frames) {
    f.type = static_cast<std::uint8_t>(rng());
    f.body.resize(rng() % (kMaxBody + 1));
    for (auto& b : f.body) b = static_cast<std::uint8_t>(rng());
    const auto bytes = omniloc::tb::golden_frame(f.type, f.body);
    expected.insert(expected.end(), bytes.begin(), bytes.end());
  }
  const auto out = run(frames, seed);
  if (out != expected) {
    const auto vcd = omniloc::rtl_tb::trace_path("frame_tx", seed);
    run(frames, seed, vcd);
    ADD_FAILURE() << "trace: " << vcd;
  }
  ASSERT_EQ(out.size(), expected.size());
  EXPECT_EQ(out, expected);
}

}  // namespace
