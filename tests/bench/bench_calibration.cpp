// `omniloc calibrate`'s work on one frame (issue 13 item 8: below 10 s): calibrate_camera on the
// real TKU RoboSot frame (tests/data/, robot on the centre spot, heading unknown) and on a
// realistic rendered frame (hyperbolic mirror, off centre, tilted, heading given), each against
// the 10 s budget (there is no older implementation to compare with: the ratio printed is
// budget / time).
#include <benchmark/benchmark.h>

#include <cstdio>

#include <opencv2/imgcodecs.hpp>

#include "../host/test_data_path.hpp"
#include "omniloc/calibration.hpp"
#include "omniloc/field.hpp"
#include "omniloc_sim/renderer.hpp"
#include "ratio_reporter.hpp"

namespace omniloc {
namespace {

using test::test_data;

void BM_CalibrateRealFrame(benchmark::State& state) {
  const FieldGeometry field = load_field("fira-robosot");
  const auto path = test_data("tku-robosot-centre-spot.png");
  if (path.empty()) {
    state.SkipWithError(
        "tests/data/tku-robosot-centre-spot.png not found (run from the build directory)");
    return;
  }
  const CalibrationFrame f{cv::imread(path.string()), "tku", {375.0, 275.0}, std::nullopt};
  CalibrationOptions told;  // the centre spot does not tell the handedness
  told.hints.mirrored = false;
  for (auto _ : state) benchmark::DoNotOptimize(calibrate_camera({f}, field, told));
  state.SetItemsProcessed(state.iterations());
}

void BM_CalibrateRealisticFrame(benchmark::State& state) {
  const FieldGeometry field = load_field("fira-robosot");
  const sim::TrueOptics truth;
  const sim::RealisticRenderer renderer(field, truth);
  const CalibrationFrame f{
      renderer.render({150.0, 375.0, 30.0}, sim::realistic(7)), "penalty", {150.0, 375.0}, 30.0};
  for (auto _ : state) benchmark::DoNotOptimize(calibrate_camera({f}, field));
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_CalibrateRealFrame)->Unit(benchmark::kSecond)->Iterations(2);
BENCHMARK(BM_CalibrateRealisticFrame)->Unit(benchmark::kSecond)->Iterations(2);

}  // namespace
}  // namespace omniloc

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  omniloc::bench::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  for (const auto& [name, ns] : reporter.ns_per_item)
    std::printf("%-28s %.2f s per frame (CPU)   budget 10 s   %.1fx inside it\n", name.c_str(),
                ns / 1e9, 10.0 / (ns / 1e9));
  benchmark::Shutdown();
  return 0;
}
