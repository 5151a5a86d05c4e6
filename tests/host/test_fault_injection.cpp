// The link under byte faults in both directions (corrupt, drop, truncate, each at 1 in 1000 bytes):
// no corrupted sample or register value is ever accepted, every loss shows up in the counters, and
// the stream resynchronises within one frame (every frame that arrives intact is accepted).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <set>

#include "omniloc/board_client.hpp"
#include "omniloc_sim/link_faults.hpp"
#include "omniloc_sim/reference_board.hpp"

namespace omniloc {
namespace {

namespace r = regmap;

std::array<std::int32_t, 4> script(std::uint32_t seq) {
  // Large and sign-changing counts so that a corrupted byte anywhere in a count would show.
  const auto s = static_cast<std::int32_t>(seq);
  return {s * 1013 - 70000, -s * 7, (s % 3 == 0) ? -123456 : 654321, s ^ 0x5A5A};
}

/// Logs where each host write starts in the host->board byte stream (one write = one request
/// frame).
struct WriteRecorder final : sim::UartSide {
  explicit WriteRecorder(sim::UartSide& inner) : inner(inner) {}
  void to_board(std::span<const std::uint8_t> b) override {
    chunks.emplace_back(offset, b.size());
    offset += b.size();
    inner.to_board(b);
  }
  std::size_t from_board(std::span<std::uint8_t> out) override { return inner.from_board(out); }
  sim::UartSide& inner;
  std::uint64_t offset = 0;
  std::vector<std::pair<std::uint64_t, std::size_t>> chunks;
};

bool damaged(const std::vector<std::uint64_t>& offsets, std::uint64_t begin, std::size_t bytes) {
  const auto it = std::lower_bound(offsets.begin(), offsets.end(), begin);
  return it != offsets.end() && *it < begin + bytes;
}

TEST(FaultInjection, NothingCorruptIsAcceptedAndEveryLossIsCounted) {
  const char* env = std::getenv("OMNILOC_SEED");
  const std::uint64_t seed = env ? std::strtoull(env, nullptr, 0) : 0xF00DCAFEull;
  std::printf("seed %llu (set OMNILOC_SEED to repeat another)\n",
              static_cast<unsigned long long>(seed));

  sim::FaultRates rates;
  rates.corrupt_per_byte = 1e-3;
  rates.drop_per_byte = 1e-3;
  rates.truncate_per_byte = 1e-3;
  sim::ReferenceBoard board({}, script);
  sim::FaultyUart faulty(board, rates, rates, seed);
  WriteRecorder recorder(faulty);
  sim::UartSideTransport link(recorder);
  BoardClientOptions opt;
  opt.response_timeout = std::chrono::milliseconds(3);
  opt.attempts = 10;
  BoardClient client(link, opt);

  // Clean start: the host must have seen window 1 to count losses after it.
  faulty.set_enabled(false);
  client.write_register(r::kRegControl, r::kControlEnable.mask());
  client.set_streaming(true);
  board.run_windows(1);
  std::map<std::uint32_t, protocol::Window> received;
  auto take = [&](const protocol::Window& w) {
    ASSERT_FALSE(received.contains(w.seq)) << "window " << w.seq << " accepted twice";
    received[w.seq] = w;
  };
  take(*client.poll_telemetry(std::chrono::milliseconds(5)));
  faulty.set_enabled(true);

  constexpr int kWindows = 6000;
  std::mt19937 rng(static_cast<std::uint32_t>(seed));
  std::vector<std::uint32_t> filters_written;
  std::uint32_t filter = 0;
  int reads = 0;
  for (int i = 0; i < kWindows; ++i) {
    board.run_windows(1);
    while (auto w = client.poll_telemetry(std::chrono::milliseconds(0))) take(*w);
    if (i % 10 == 0) {
      filter = rng() & 0xFF;
      filters_written.push_back(filter);
      client.write_register(r::kRegFilter, filter);
    } else if (i % 10 == 5) {
      ASSERT_EQ(client.read_register(r::kRegFilter), filter);
      ASSERT_EQ(client.read_register(r::kRegId), r::kIdValue);
      const std::uint32_t ts = client.read_register(r::kRegTimestamp);
      ASSERT_EQ(ts, board.reg(r::kRegTimestamp));  // nothing moves while the host waits
      reads += 3;
    }
  }
  // End on a clean stream so that every intact frame has been delivered.
  faulty.set_enabled(false);
  board.run_windows(1);
  while (auto w = client.poll_telemetry(std::chrono::milliseconds(5))) take(*w);
  const std::uint32_t total = static_cast<std::uint32_t>(kWindows) + 2;

  // 1. No corrupted sample: every accepted window is exactly the board's window of that sequence
  // number.
  const auto truth = board.windows();
  ASSERT_EQ(truth.size(), total);
  for (const auto& [seq, w] : received) ASSERT_EQ(w, truth[seq - 1]) << "window " << seq;

  // 2. Resync within one frame: the frames accepted are exactly the telemetry frames whose bytes
  // all
  //    arrived unharmed; each frame after a damaged one is accepted.
  const auto& from_log = faulty.from_board_log();
  std::set<std::uint32_t> intact;
  int telemetry_damaged = 0;
  for (const auto& e : board.emitted()) {
    if (const auto* t = std::get_if<protocol::Telemetry>(&e.frame)) {
      if (damaged(from_log.damaged_offsets, e.offset, e.bytes)) {
        ++telemetry_damaged;
      } else {
        intact.insert(t->window.seq);
      }
    }
  }
  std::set<std::uint32_t> got;
  for (const auto& kv : received) got.insert(kv.first);
  EXPECT_EQ(got, intact);
  EXPECT_GT(telemetry_damaged, 100);

  // 3. Every loss counted: received + counted lost = all windows; nothing stale.
  const auto& dc = client.decoder_counters();
  EXPECT_EQ(received.size() + dc.telemetry_lost, total);
  EXPECT_EQ(dc.telemetry_stale, 0u);
  EXPECT_GT(dc.bad_crc + dc.bad_length + dc.unknown_type, 0u);

  // 4. Register writes: the board applied only values the host sent, and FILTER ends as last
  // written.
  for (const auto& w : board.applied_writes()) {
    if (w.addr == r::kRegFilter) {
      ASSERT_NE(std::find(filters_written.begin(), filters_written.end(), w.value),
                filters_written.end())
          << "board applied a FILTER value the host never sent: " << w.value;
    } else {
      ASSERT_EQ(w.addr, r::kRegControl);
    }
  }
  EXPECT_EQ(board.reg(r::kRegFilter), filter);

  // 5. Host->board losses: every damaged request was sent again.
  const auto& to_log = faulty.to_board_log();
  int requests_damaged = 0;
  for (const auto& [off, n] : recorder.chunks)
    requests_damaged += damaged(to_log.damaged_offsets, off, n) ? 1 : 0;
  const auto& cc = client.counters();
  EXPECT_GE(cc.retries, static_cast<std::uint64_t>(requests_damaged));
  EXPECT_GT(requests_damaged, 0);
  const auto board_rx = board.rx_counters();

  std::printf(
      "board->host: %llu bytes, %llu corrupted, %llu dropped (%llu truncations); telemetry %u "
      "sent, %d damaged, "
      "%zu accepted, %llu counted lost in %llu gaps; decoder rejected %llu bad CRC, %llu bad LEN, "
      "%llu unknown TYPE, "
      "%llu resync bytes\n",
      static_cast<unsigned long long>(from_log.bytes_seen),
      static_cast<unsigned long long>(from_log.corrupted),
      static_cast<unsigned long long>(from_log.dropped),
      static_cast<unsigned long long>(from_log.truncations), total, telemetry_damaged,
      received.size(), static_cast<unsigned long long>(dc.telemetry_lost),
      static_cast<unsigned long long>(dc.telemetry_gaps),
      static_cast<unsigned long long>(dc.bad_crc), static_cast<unsigned long long>(dc.bad_length),
      static_cast<unsigned long long>(dc.unknown_type),
      static_cast<unsigned long long>(dc.resync_bytes));
  std::printf(
      "host->board: %llu bytes, %llu corrupted, %llu dropped (%llu truncations); %zu requests (%d "
      "reads checked), "
      "%d damaged; host %llu retries, %llu timeouts, %llu BAD_CRC/MALFORMED answers; board served "
      "%llu requests, "
      "rejected %llu bad CRC, %llu malformed (%llu cut short)\n",
      static_cast<unsigned long long>(to_log.bytes_seen),
      static_cast<unsigned long long>(to_log.corrupted),
      static_cast<unsigned long long>(to_log.dropped),
      static_cast<unsigned long long>(to_log.truncations), recorder.chunks.size(), reads,
      requests_damaged, static_cast<unsigned long long>(cc.retries),
      static_cast<unsigned long long>(cc.timeouts),
      static_cast<unsigned long long>(cc.board_rejected),
      static_cast<unsigned long long>(board_rx.requests),
      static_cast<unsigned long long>(board_rx.bad_crc),
      static_cast<unsigned long long>(board_rx.malformed),
      static_cast<unsigned long long>(board_rx.aborted));
}

}  // namespace
}  // namespace omniloc
