// UsbTransport -- the exact code that runs on the robot -- against an emulated FT2232H (umockdev)
// whose UART side is the Verilated board (rtl/omniloc_top.v) with the world simulator's encoder
// waveforms on its pins and the ICM-42688-P model on its SPI pins: open, configure, read the ID
// register, stream a second of windows whose counts must equal the golden decoder's and whose gyro
// sums must partition the model's samples exactly, then unplug in the middle and see the error
// reported.
// Run under `umockdev-wrapper` (CTest does).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>
#include <vector>

#include "../link/golden_quadrature.hpp"
#include "omniloc/board_client.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc/usb_transport.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "omniloc_sim/ft2232h_model.hpp"
#include "omniloc_sim/icm42688.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "tb_support.hpp"

namespace omniloc {
namespace {

namespace r = regmap;
using namespace std::chrono_literals;
using sim::BoardSim;
constexpr std::int64_t kWindowCycles = BoardSim::kClockHz / 100;
constexpr std::int64_t kCaptureLag = 4;  // docs/RTL.md: pin -> window counter with the filter off

/// The Verilated board as the FT2232H's UART side, clocked by its own thread: it runs as fast as
/// the model allows (about half of real time here), one millisecond of board time per lock.
class ClockedBoard final : public sim::UartSide {
 public:
  ClockedBoard(sim::EncoderSource& source, sim::Icm42688& gyro)
      : board_(&source, &gyro), thread_([this] { run(); }) {}
  ~ClockedBoard() override {
    stop_ = true;
    thread_.join();
  }
  void to_board(std::span<const std::uint8_t> bytes) override {
    Turn turn(*this);
    board_.to_board(bytes);
  }
  std::size_t from_board(std::span<std::uint8_t> out) override {
    Turn turn(*this);
    return board_.from_board(out);
  }
  /// Runs `f` while the board's clock thread waits (to read a model it steps).
  template <class F>
  void with_board(F f) {
    Turn turn(*this);
    f();
  }

 private:
  // std::mutex is not fair: a clock thread that relocks at once can starve the USB handlers for
  // seconds on a busy machine (the host then times out while the board runs on). A handler
  // announces itself first, and the clock thread waits between slices until no handler waits.
  class Turn {
   public:
    explicit Turn(ClockedBoard& b) : b_(b) {
      ++b_.waiting_;
      lock_ = std::unique_lock(b_.mutex_);
      --b_.waiting_;
    }

   private:
    ClockedBoard& b_;
    std::unique_lock<std::mutex> lock_;
  };
  void run() {
    while (!stop_) {
      {
        std::lock_guard lock(mutex_);
        board_.run_cycles(BoardSim::kClockHz / 1000);
      }
      while (waiting_.load() > 0 && !stop_) std::this_thread::yield();
    }
  }
  std::atomic<int> waiting_{0};
  std::mutex mutex_;
  BoardSim board_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The first sample of the gyro log at which the first two windows with samples sum exactly (read
// before the first of them ended); reads.size() when there is none.
std::size_t first_streamed_sample(const std::vector<sim::Icm42688::Sample>& reads,
                                  const std::vector<protocol::Window>& windows) {
  std::vector<const protocol::Window*> with;
  for (const auto& w : windows)
    if (w.gyro_count > 0 && with.size() < 2) with.push_back(&w);
  const auto sums_from = [&](std::size_t at, const protocol::Window& w) {
    if (at + w.gyro_count > reads.size()) return false;
    std::int64_t sum = 0;
    for (std::size_t i = 0; i < w.gyro_count; ++i) sum += reads[at + i].value;
    return sum == w.gyro_sum;
  };
  if (with.size() < 2) return reads.size();
  for (std::size_t at = 0; at < reads.size() && reads[at].cycle <= with[0]->timestamp_cycles;
       ++at) {
    if (sums_from(at, *with[0]) && sums_from(at + with[0]->gyro_count, *with[1])) return at;
  }
  return reads.size();
}

TEST(UsbVerilatedBoard, StreamsGoldenWindowsThenReportsUnplug) {
  const auto seed = omniloc::rtl_tb::test_seed(
      ::testing::UnitTest::GetInstance()->current_test_info()->name(), 71);
  sim::QuadratureStream stream(omniloc::tb::board_world(seed),
                               sim::make_trajectory("circle", seed));
  tb::GoldenQuadrature golden(stream, kWindowCycles);
  sim::EmulatedUsb usb;
  sim::Icm42688Params gp;
  gp.clk_hz = static_cast<double>(BoardSim::kClockHz);
  gp.noise_dps_rms = 0.16;
  gp.seed = seed;
  sim::Icm42688 gyro(
      gp, [](double t) { return 120.0 * std::sin(2.0 * 3.14159265358979 * 0.7 * t) - 40.0; });
  ClockedBoard board(golden, gyro);
  sim::Ft2232hModel device(
      usb, board,
      sim::Ft2232hConfig::programmed_with(sim::read_eeprom_identity(OMNILOC_EEPROM_CONF)));

  UsbTransport transport;
  BoardClientOptions options;
  options.response_timeout = 300ms;  // board time runs at about half of real time
  BoardClient client(transport, options);
  ASSERT_EQ(client.read_register(r::kRegId), r::kIdValue);

  std::uint32_t control = r::kControlEnable.put(0, 1);
  control = r::kControlDecode.put(control, r::kControlDecodeX4);
  control = r::kControlStream.put(control, 1);
  client.write_register(r::kRegControl, control);

  // A second of board time: 100 windows, each equal to the golden decoder's count.
  std::optional<protocol::Window> prev;
  int checked = 0, moving = 0;
  std::vector<protocol::Window> windows;
  while (checked < 100) {
    const auto w = client.poll_telemetry(2000ms);
    ASSERT_TRUE(w.has_value()) << "no telemetry after " << checked << " windows";
    if (prev) {
      ASSERT_EQ(w->seq, prev->seq + 1) << "a window was lost";
      const auto e = golden.counts_at(static_cast<std::int64_t>(w->timestamp_cycles) - kCaptureLag);
      const auto b =
          golden.counts_at(static_cast<std::int64_t>(prev->timestamp_cycles) - kCaptureLag);
      ASSERT_TRUE(e && b) << "window " << w->seq << " does not end at a window boundary";
      for (int m = 0; m < 4; ++m) {
        ASSERT_EQ(w->count[m], (*e)[m] - (*b)[m]) << "window " << w->seq << " motor " << m + 1;
        moving += w->count[m] != 0;
      }
      ++checked;
    }
    prev = w;
    windows.push_back(*w);
  }
  // The gyro's windows against the part's own log: every sample once, in order, summed exactly.
  // (The board thread keeps the model running; its log is only read under the board's turn below.)
  std::vector<sim::Icm42688::Sample> reads;
  board.with_board([&] { reads = gyro.reads(); });
  // gyro_ctrl reads the part from reset, whatever the stream's state: the samples of any window
  // ticked before the first one this test received are in the log but in no window it saw. (The
  // test failed once at window 1 under load, not reproduced since; the offset is printed to tell.)
  // The log is taken from the first sample at which the first two windows with samples both sum
  // exactly; every window after them must then sum exactly too.
  const std::size_t first = first_streamed_sample(reads, windows);
  ASSERT_LT(first, reads.size()) << "no place in the gyro log sums to the first windows";
  std::printf("%zu gyro samples read before the first streamed window\n", first);
  std::size_t next = first;
  int with_samples = 0;
  for (const auto& w : windows) {
    if (w.gyro_count == 0) continue;
    ++with_samples;
    ASSERT_EQ(w.gyro_flags, 0u) << "window " << w.seq;
    ASSERT_LE(next + w.gyro_count, reads.size());
    std::int64_t sum = 0;
    for (std::size_t i = 0; i < w.gyro_count; ++i) sum += reads[next + i].value;
    ASSERT_EQ(w.gyro_sum, sum) << "window " << w.seq;
    next += w.gyro_count;
  }
  EXPECT_GE(with_samples, 95);
  EXPECT_GT(moving, 300);
  EXPECT_EQ(golden.illegal(), 0);
  EXPECT_EQ(transport.status().counters.line_framing, 0u);
  std::printf(
      "%d windows over emulated USB equal the golden decoder (%d motor-windows moving); %zu gyro "
      "samples "
      "summed exactly into %d windows\n",
      checked, moving, next - first, with_samples);

  // Unplug while streaming: the next read reports the device gone.
  device.unplug();
  bool gone = false;
  try {
    for (int i = 0; i < 1000; ++i) (void)client.poll_telemetry(50ms);
  } catch (const TransportError& e) {
    gone = e.kind() == TransportErrorKind::kDeviceGone;
  }
  EXPECT_TRUE(gone) << "the unplug was not reported";
  EXPECT_TRUE(transport.status().device_gone);
}

}  // namespace
}  // namespace omniloc
