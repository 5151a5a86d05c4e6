// Odometry updates per second: the Odometry class (pseudo-inverse computed once) beside a naive
// reference that rebuilds eq. (9)'s matrix and its pseudo-inverse (SVD) at every window, and the
// paper variant. Windows come from the simulator (random walk, default noise, one slip event).
// Prints updates/s and the ratio to the naive reference measured in the same run.
// Also the cycle-level encoder waveform: QuadratureStream::levels_at per clock cycle beside the
// naive per-cycle evaluation of all four encoder positions (what a testbench would do without the
// stream).
#include <benchmark/benchmark.h>

#include "ratio_reporter.hpp"

#include <Eigen/Dense>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "omniloc/odometry.hpp"
#include "omniloc_sim/encoder_waveform.hpp"
#include "omniloc_sim/world.hpp"

namespace {

using namespace omniloc;

const std::vector<EncoderWindow>& windows() {
  static const std::vector<EncoderWindow> w = [] {
    sim::WorldConfig cfg = sim::WorldConfig::default_noise(RobotConfig{}, 5);
    cfg.slips.push_back({2, 4.0, 0.5, 40.0});
    sim::World world(cfg, sim::make_trajectory("random_walk", 5));
    std::vector<EncoderWindow> out;
    while (!world.finished()) out.push_back(world.next_window().window);
    return out;
  }();
  return w;
}

// The straightforward implementation: everything recomputed per window, no slip handling.
struct NaiveOdometry {
  RobotConfig c;
  Pose2 pose;
  double last_gyro = 0.0;
  void update(const EncoderWindow& w) {
    const Eigen::Matrix<double, 4, 3> j = wheel_jacobian(c.motor_angle_deg, c.center_to_wheel_cm);
    const Eigen::MatrixXd pinv =
        Eigen::MatrixXd(j).completeOrthogonalDecomposition().pseudoInverse();
    Eigen::VectorXd travel(4);
    for (int i = 0; i < 4; ++i) travel[i] = w.counts[static_cast<std::size_t>(i)] * cm_per_count(c);
    const Eigen::VectorXd x = pinv * travel;
    const double mid = last_gyro + 0.5 * angle_diff_deg(w.gyro_yaw_deg, last_gyro);
    const Eigen::Vector2d d = robot_to_field({x[0], x[1]}, mid);
    pose.x_cm += d.x();
    pose.y_cm += d.y();
    pose.yaw_deg = w.gyro_yaw_deg;
    last_gyro = w.gyro_yaw_deg;
  }
};

void BM_NaivePseudoInversePerUpdate(benchmark::State& state) {
  const auto& ws = windows();
  NaiveOdometry odo;
  std::size_t i = 0;
  for (auto _ : state) {
    odo.update(ws[i]);
    if (++i == ws.size()) i = 0;
    benchmark::DoNotOptimize(odo.pose);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_NaivePseudoInversePerUpdate);

void BM_OdometryUpdate(benchmark::State& state) {
  const auto& ws = windows();
  Odometry odo(RobotConfig{});
  std::size_t i = 0;
  double t_offset = 0.0;
  for (auto _ : state) {
    EncoderWindow w = ws[i];
    w.t_end_ms += t_offset;  // keep time increasing when the recording wraps around
    benchmark::DoNotOptimize(odo.update(w));
    if (++i == ws.size()) {
      i = 0;
      t_offset += ws.back().t_end_ms;
    }
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_OdometryUpdate);

void BM_PaperOdometryUpdate(benchmark::State& state) {
  const auto& ws = windows();
  PaperOdometry odo(RobotConfig{});
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(odo.update(ws[i]));
    if (++i == ws.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_PaperOdometryUpdate);

constexpr std::int64_t kCyclesPerIteration = 400'000;  // one window
constexpr std::int64_t kMaxCycles = 1'000'000'000;     // random walk lasts ~1.1e9 cycles

void BM_NaiveWaveformPerCycle(benchmark::State& state) {
  const sim::WorldConfig cfg = sim::WorldConfig::default_noise(RobotConfig{}, 5);
  auto world = std::make_unique<sim::World>(cfg, sim::make_trajectory("random_walk", 5));
  std::int64_t c = 1;
  unsigned acc = 0;
  for (auto _ : state) {
    for (std::int64_t k = 0; k < kCyclesPerIteration; ++k, ++c) {
      if (c > world->cycle()) world->step();
      unsigned v = 0;
      for (int m = 0; m < 4; ++m) {
        const std::int64_t q = sim::quarter_of(sim::position_at(world->last_step(), m, c));
        v |= (sim::level_a(q) ? 1u : 0u) << (2 * m) | (sim::level_b(q) ? 1u : 0u) << (2 * m + 1);
      }
      acc += v;
    }
    if (c > kMaxCycles) {
      state.PauseTiming();
      world = std::make_unique<sim::World>(cfg, sim::make_trajectory("random_walk", 5));
      c = 1;
      state.ResumeTiming();
    }
  }
  benchmark::DoNotOptimize(acc);
  state.SetItemsProcessed(state.iterations() * kCyclesPerIteration);
}
BENCHMARK(BM_NaiveWaveformPerCycle)->Unit(benchmark::kMillisecond);

void BM_QuadratureStreamPerCycle(benchmark::State& state) {
  const sim::WorldConfig cfg = sim::WorldConfig::default_noise(RobotConfig{}, 5);
  auto stream =
      std::make_unique<sim::QuadratureStream>(cfg, sim::make_trajectory("random_walk", 5));
  std::int64_t c = 1;
  unsigned acc = 0;
  for (auto _ : state) {
    for (std::int64_t k = 0; k < kCyclesPerIteration; ++k, ++c) acc += stream->levels_at(c);
    if (c > kMaxCycles) {
      state.PauseTiming();
      stream = std::make_unique<sim::QuadratureStream>(cfg, sim::make_trajectory("random_walk", 5));
      c = 1;
      state.ResumeTiming();
    }
  }
  benchmark::DoNotOptimize(acc);
  state.SetItemsProcessed(state.iterations() * kCyclesPerIteration);
}
BENCHMARK(BM_QuadratureStreamPerCycle)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  (void)windows();
  omniloc::bench::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& m = reporter.ns_per_item;
  const auto ratio = [&](const char* name, const char* naive, const char* unit) {
    const auto a = m.find(name);
    const auto b = m.find(naive);
    if (a == m.end() || b == m.end()) return;
    std::printf("%-30s %12.0f %s (CPU)   %.1fx the naive reference %s\n", name, 1e9 / a->second,
                unit, b->second / a->second, naive);
  };
  ratio("BM_OdometryUpdate", "BM_NaivePseudoInversePerUpdate", "updates/s");
  ratio("BM_PaperOdometryUpdate", "BM_NaivePseudoInversePerUpdate", "updates/s");
  ratio("BM_QuadratureStreamPerCycle", "BM_NaiveWaveformPerCycle", "cycles/s");
  benchmark::Shutdown();
  return 0;
}
