// The simulated board link: round-trip latency of a register read and of a snapshot, in board clock
// cycles and in microseconds at 12 MHz, beside the time the bytes alone need on the 1 Mbaud line
// (the reference: a link that added nothing); and the Verilated board's simulation speed beside
// real time and beside the model as it was built and stepped before (the reference).
#include <benchmark/benchmark.h>

#include <verilated.h>

#include <array>
#include <cstdint>
#include <cstdio>

#include "Vomniloc_top_reference.h"
#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc_sim/board_sim.hpp"
#include "ratio_reporter.hpp"

namespace {

using omniloc::sim::BoardSim;
namespace protocol = omniloc::protocol;
namespace rm = omniloc::regmap;

constexpr double kCyclesPerByte = 10.0 * BoardSim::kClockHz / BoardSim::kBaud;

// Sends one request and runs the board cycle by cycle until the whole answer is out of the FPGA.
std::int64_t round_trip_cycles(BoardSim& board, const std::vector<std::uint8_t>& request,
                               std::size_t answer_bytes) {
  const std::int64_t start = board.cycle();
  board.to_board(request);
  std::size_t got = 0;
  std::array<std::uint8_t, 64> buf{};
  while (got < answer_bytes) {
    board.run_cycles(1);
    got += board.from_board(buf);
  }
  return board.cycle() - start;
}

void report(benchmark::State& state, std::int64_t cycles, std::size_t bytes_out,
            std::size_t bytes_in) {
  const double line = static_cast<double>(bytes_out + bytes_in) * kCyclesPerByte;
  state.counters["cycles"] = static_cast<double>(cycles);
  state.counters["us"] = static_cast<double>(cycles) * 1e6 / BoardSim::kClockHz;
  state.counters["line_cycles"] = line;
  state.counters["ratio_to_line"] = static_cast<double>(cycles) / line;
}

void BM_RegisterReadRoundTrip(benchmark::State& state) {
  BoardSim board;
  const auto request = protocol::encode(protocol::ReadReq{rm::kRegId});
  const std::size_t answer = protocol::frame_bytes(rm::kFrameReadRespBodyBytes);
  std::int64_t cycles = 0;
  for (auto _ : state) cycles = round_trip_cycles(board, request, answer);
  report(state, cycles, request.size(), answer);
}
BENCHMARK(BM_RegisterReadRoundTrip)->Iterations(20);

void BM_SnapshotRoundTrip(benchmark::State& state) {
  BoardSim board;
  const auto request = protocol::encode(protocol::SnapshotReq{});
  const std::size_t answer = protocol::frame_bytes(rm::kFrameSnapshotRespBodyBytes);
  std::int64_t cycles = 0;
  for (auto _ : state) cycles = round_trip_cycles(board, request, answer);
  report(state, cycles, request.size(), answer);
}
BENCHMARK(BM_SnapshotRoundTrip)->Iterations(20);

constexpr std::int64_t kSpeedSlice = BoardSim::kClockHz / 100;

void speed_counters(benchmark::State& state) {
  const auto cycles = static_cast<double>(state.iterations() * kSpeedSlice);
  state.counters["cycles_per_s"] = benchmark::Counter(cycles, benchmark::Counter::kIsRate);
  state.counters["x_real_time"] =
      benchmark::Counter(cycles / BoardSim::kClockHz, benchmark::Counter::kIsRate);
  state.SetItemsProcessed(state.iterations() * kSpeedSlice);
}

// Simulation speed of the whole Verilated board: board cycles per second of CPU time, and the
// fraction of real time (12 M cycles/s) it reaches.
void BM_BoardSimulationSpeed(benchmark::State& state) {
  BoardSim board;
  for (auto _ : state) board.run_cycles(kSpeedSlice);
  speed_counters(state);
}
BENCHMARK(BM_BoardSimulationSpeed)->Unit(benchmark::kMillisecond)->MinTime(1.0);

// The reference: omniloc_top verilated and stepped as BoardSim did before issue 35 item 5: the
// whole model compiled with the tree's compiler (bench_board_reference; BoardSim's per-cycle model
// code is now clang's) and an eval() on each clock edge (BoardSim now skips the falling edge's,
// which changes nothing), with the idle UART line BoardSim drives when the host sends nothing.
void BM_BoardSimulationSpeedEvalBothEdges(benchmark::State& state) {
  VerilatedContext context;
  Vomniloc_top_reference top(&context);
  const auto step = [&top] {
    top.clk_i = 1;
    top.eval();
    top.clk_i = 0;
    top.eval();
  };
  top.uart_rx_i = 1;
  top.spi_miso_i = 1;
  top.enc_a_i = 0;
  top.enc_b_i = 0;
  top.rst_i = 1;
  for (int i = 0; i < 4; ++i) step();
  top.rst_i = 0;
  unsigned tx = 0;
  for (auto _ : state) {
    for (std::int64_t i = 0; i < kSpeedSlice; ++i) {
      top.uart_rx_i = 1;
      step();
      tx += top.uart_tx_o;
    }
  }
  benchmark::DoNotOptimize(tx);
  top.final();
  speed_counters(state);
}
BENCHMARK(BM_BoardSimulationSpeedEvalBothEdges)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  omniloc::bench::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& m = reporter.ns_per_item;
  const auto a = m.find("BM_BoardSimulationSpeed/min_time:1.000");
  const auto b = m.find("BM_BoardSimulationSpeedEvalBothEdges/min_time:1.000");
  if (a != m.end() && b != m.end()) {
    std::printf(
        "%-38s %6.2f M cycles/s (CPU), %.2fx real time (12 M cycles/s), %.2fx the reference %s "
        "(%.2f M cycles/s)\n",
        "BM_BoardSimulationSpeed", 1e3 / a->second, 1e9 / a->second / BoardSim::kClockHz,
        b->second / a->second, "BM_BoardSimulationSpeedEvalBothEdges", 1e3 / b->second);
  }
  benchmark::Shutdown();
  return 0;
}
