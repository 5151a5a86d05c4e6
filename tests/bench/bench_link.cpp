// The simulated board link: round-trip latency of a register read and of a snapshot, in board clock
// cycles and in microseconds at 12 MHz, beside the time the bytes alone need on the 1 Mbaud line
// (the reference: a link that added nothing); and the Verilated board's simulation speed beside
// real time.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>

#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc_sim/board_sim.hpp"

namespace {

using omniloc::sim::BoardSim;
namespace protocol = omniloc::protocol;
namespace rm = omniloc::regmap;

constexpr double kCyclesPerByte = 10.0 * BoardSim::kClockHz / BoardSim::kBaud;

// Sends one request and runs the board cycle by cycle until the whole answer is out of the FPGA.
std::int64_t round_trip_cycles(BoardSim& board, const std::vector<std::uint8_t>& request, std::size_t answer_bytes) {
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

void report(benchmark::State& state, std::int64_t cycles, std::size_t bytes_out, std::size_t bytes_in) {
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

// Simulation speed of the whole Verilated board: board cycles per second of wall time, and the
// fraction of real time (12 M cycles/s) it reaches.
void BM_BoardSimulationSpeed(benchmark::State& state) {
  BoardSim board;
  constexpr std::int64_t kSlice = BoardSim::kClockHz / 100;
  for (auto _ : state) board.run_cycles(kSlice);
  state.counters["cycles_per_s"] = benchmark::Counter(static_cast<double>(state.iterations() * kSlice), benchmark::Counter::kIsRate);
  state.counters["x_real_time"] = benchmark::Counter(static_cast<double>(state.iterations() * kSlice) / BoardSim::kClockHz, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BoardSimulationSpeed)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();
