// Localizer speed (paper Table 8, Fig. 14): the per-frame pattern match with the fuzzy search
// range against the naive full search (sad_reference over every grid point), and the full mode's
// whole frame (robot-frame scan + local search + ray-cast refinement) against the naive pipeline
// (whole-image HSV scan + naive global search). Ratios printed at the end, measured in this run.
#include <benchmark/benchmark.h>

#include "ratio_reporter.hpp"

#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "omniloc/detail/vision_reference.hpp"
#include "omniloc/fuzzy.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc {
namespace {

struct Setup {
  std::unique_ptr<sim::OmniRenderer> renderer;
  FeatureDb db;
  cv::Mat image;
  Scan scan;
  Pose2 truth{368, 371, 30};
};

const Setup& setup() {
  static const Setup s = [] {
    Setup x;
    x.renderer =
        std::make_unique<sim::OmniRenderer>(load_field("fira-robosot"), load_camera("default"));
    x.db = build_feature_db(x.renderer->field(), x.renderer->camera(),
                            GridSpec::covering(x.renderer->field(), 10.0));
    x.image = x.renderer->render(x.truth, sim::RenderOptions{});
    x.scan = scan_image(x.image, x.renderer->camera(), x.truth.yaw_deg);
    return x;
  }();
  return s;
}

void BM_FuzzyRange(benchmark::State& state) {
  const FuzzyConfig c = FuzzyConfig::defaults();
  double v = 0.0;
  for (auto _ : state) {
    v = v > 290.0 ? 0.0 : v + 7.0;
    benchmark::DoNotOptimize(fuzzy_search_range(c, v).snapped_cm);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FuzzyRange);

void BM_NaiveGlobalSearchPerFrame(benchmark::State& state) {
  const Setup& s = setup();
  for (auto _ : state) benchmark::DoNotOptimize(global_search_reference(s.db, s.scan).cell);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_NaiveGlobalSearchPerFrame)->Unit(benchmark::kMillisecond);

void BM_FuzzyLocalSearchPerFrame(benchmark::State& state) {
  const Setup& s = setup();
  const FuzzyConfig c = FuzzyConfig::defaults();
  for (auto _ : state) {
    const double range = fuzzy_search_range(c, 100.0).snapped_cm;  // 20 cm: 5 x 5 points
    MatchResult m = local_search(s.db, s.scan, {s.truth.x_cm, s.truth.y_cm}, range);
    interpolate_match(s.db, s.scan, m);
    benchmark::DoNotOptimize(m.position_cm);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FuzzyLocalSearchPerFrame)->Unit(benchmark::kMicrosecond);

void BM_NaiveFramePerFrame(benchmark::State& state) {
  const Setup& s = setup();
  for (auto _ : state) {
    const Scan scan = scan_image_reference(s.image, s.renderer->camera(), s.truth.yaw_deg);
    benchmark::DoNotOptimize(global_search_reference(s.db, scan).cell);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_NaiveFramePerFrame)->Unit(benchmark::kMillisecond);

void BM_FullModeFramePerFrame(benchmark::State& state) {
  const Setup& s = setup();
  for (auto _ : state) {
    const BearingScan b = scan_image_bearings(s.image, s.renderer->camera(), 4);
    const FieldScan scan =
        make_field_scan(b, s.truth.yaw_deg);  // rotated and prepared once, as the localizer does
    MatchResult m = local_search(s.db, scan, {s.truth.x_cm, s.truth.y_cm}, 20.0);
    MatchOptions mo;
    mo.refinement = Refinement::kRayCast;
    apply_refinement(s.db, s.renderer->field(), s.renderer->camera(), scan, m, mo);
    benchmark::DoNotOptimize(m.position_cm);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FullModeFramePerFrame)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace omniloc

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  (void)omniloc::setup();
  omniloc::bench::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& m = reporter.ns_per_item;
  const auto ratio = [&](const char* name, const char* naive) {
    const auto a = m.find(name);
    const auto b = m.find(naive);
    if (a == m.end() || b == m.end()) return;
    std::printf("%-30s %10.4f ms per frame (CPU)   %.1fx faster than the naive %s\n", name,
                a->second / 1e6, b->second / a->second, naive);
  };
  ratio("BM_FuzzyLocalSearchPerFrame", "BM_NaiveGlobalSearchPerFrame");
  ratio("BM_FullModeFramePerFrame", "BM_NaiveFramePerFrame");
  benchmark::Shutdown();
  return 0;
}
