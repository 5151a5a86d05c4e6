// The whole per-frame path as the daemon runs it (issue 13 item 8): the robot-frame scan of one
// frame at the localizer's rays per degree, the local search in the fuzzy range around the
// odometry prediction, and the sub-grid refinement (interpolation, then ray casting), at
// 640 x 480 (common/cameras/default.json) and 1280 x 1024 (the same camera scaled by 2: a larger
// sensor behind the same mirror; the feature format still stops at 254 px). Each is measured
// beside the reference path in the same run: the paper's SAD with the plain pattern search
// (refine_match_reference), which is what the localizer ran before the bounded cost. The ratio
// and the share of each step are printed at the end.
#include <benchmark/benchmark.h>

#include "ratio_reporter.hpp"

#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "omniloc/fuzzy.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/vision.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc {
namespace {

// The scan step as the daemon runs it: one LineExtractor per camera, kept from frame to frame (its
// ray tables are built once and its light adaptation carries over). Switch to the older
// fixed-threshold scan here for comparison: return scan_image_bearings(bgr, camera, rays_per_degree);
BearingScan scan_step(LineExtractor& extractor, const cv::Mat& bgr, int rays_per_degree) {
  return extractor.extract(bgr, rays_per_degree);
}

CameraModel scaled_camera(const CameraModel& base, double factor, int width_px, int height_px) {
  CameraModel c = base;
  c.width_px = width_px;
  c.height_px = height_px;
  c.center_px = Eigen::Vector2d(width_px / 2.0, height_px / 2.0);
  for (auto& m : c.radius_lut) m.radius_px *= factor;
  c.body_radius_px *= factor;
  return c;
}

struct Setup {
  std::unique_ptr<sim::OmniRenderer> renderer;
  FeatureDb db;
  cv::Mat image;
  Pose2 truth{368.4, 371.7, 30.0};
  Eigen::Vector2d predicted_cm{371.4, 367.7};  // the odometry's prediction, 5 cm off
  double range_cm = 0.0;
  LocalizerConfig config;  // the shipped defaults: rays per degree, cost, refinement
  std::unique_ptr<LineExtractor> extractor;  // the daemon's: one per camera, across frames
};

const Setup& setup(int size) {
  static std::map<int, std::unique_ptr<Setup>> cache;  // built once per size: not what is measured
  auto& s = cache[size];
  if (s) return *s;
  s = std::make_unique<Setup>();
  const CameraModel base = load_camera("default");
  const CameraModel camera = size == 0 ? base : scaled_camera(base, 2.0, 1280, 1024);
  s->renderer = std::make_unique<sim::OmniRenderer>(load_field("fira-robosot"), camera);
  s->db = build_feature_db(s->renderer->field(), camera, GridSpec::covering(s->renderer->field(), 10.0));
  sim::RenderOptions opt;
  opt.seed = 5;
  opt.obstacles = sim::random_obstacles(s->renderer->field(), s->truth, 2, opt.seed);
  s->image = s->renderer->render(s->truth, opt);
  s->range_cm = fuzzy_search_range(s->config.fuzzy, 100.0).snapped_cm;  // 100 cm/s: 20 cm, 5 x 5 points
  s->extractor = std::make_unique<LineExtractor>(camera);
  (void)s->extractor->extract(s->image, s->config.scan_rays_per_degree);  // the first frame is walked twice
  return *s;
}

MatchOptions options(const Setup& s, bool reference) {
  MatchOptions mo;
  mo.refinement = Refinement::kRayCast;
  mo.cost = reference ? MatchCost::kPaperSad : s.config.match_cost;
  mo.crossing_cap_px = s.config.crossing_cap_px;
  return mo;
}

// One frame: scan, local search, refinement. `reference`: the paper's SAD and the plain pattern search.
MatchResult frame(const Setup& s, bool reference) {
  const CameraModel& cam = s.renderer->camera();
  const MatchOptions mo = options(s, reference);
  const FieldScan scan = make_field_scan(scan_step(*s.extractor, s.image, s.config.scan_rays_per_degree), s.truth.yaw_deg);
  MatchResult m = local_search(s.db, scan, s.predicted_cm, s.range_cm, mo);
  interpolate_match(s.db, scan, m, mo);
  if (reference) {
    refine_match_reference(s.renderer->field(), cam, scan, m, mo);
  } else {
    refine_match(s.renderer->field(), cam, scan, m, mo);
  }
  return m;
}

void BM_FramePath(benchmark::State& state) {
  const Setup& s = setup(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(frame(s, false).position_cm);
  state.SetItemsProcessed(state.iterations());
}
void BM_FramePathReference(benchmark::State& state) {
  const Setup& s = setup(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(frame(s, true).position_cm);
  state.SetItemsProcessed(state.iterations());
}

// The steps alone, for the breakdown.
void BM_ScanStep(benchmark::State& state) {
  const Setup& s = setup(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(scan_step(*s.extractor, s.image, s.config.scan_rays_per_degree));
  state.SetItemsProcessed(state.iterations());
}
void refine_step(benchmark::State& state, bool reference) {
  const Setup& s = setup(static_cast<int>(state.range(0)));
  const MatchOptions mo = options(s, reference);
  const FieldScan scan =
      make_field_scan(scan_step(*s.extractor, s.image, s.config.scan_rays_per_degree), s.truth.yaw_deg);
  MatchResult start = local_search(s.db, scan, s.predicted_cm, s.range_cm, mo);
  interpolate_match(s.db, scan, start, mo);
  for (auto _ : state) {
    MatchResult m = start;
    if (reference) {
      refine_match_reference(s.renderer->field(), s.renderer->camera(), scan, m, mo);
    } else {
      refine_match(s.renderer->field(), s.renderer->camera(), scan, m, mo);
    }
    benchmark::DoNotOptimize(m.position_cm);
  }
  state.SetItemsProcessed(state.iterations());
}
void BM_RefineStep(benchmark::State& state) { refine_step(state, false); }
void BM_RefineStepReference(benchmark::State& state) { refine_step(state, true); }

BENCHMARK(BM_FramePath)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FramePathReference)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScanStep)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineStep)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineStepReference)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace omniloc

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  omniloc::bench::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& m = reporter.ns_per_item;
  const char* sizes[] = {"640 x 480", "1280 x 1024"};
  for (int size = 0; size < 2; ++size) {
    const auto at = [&](const std::string& name) {
      const auto it = m.find(name + "/" + std::to_string(size));
      return it == m.end() ? -1.0 : it->second / 1e6;
    };
    const double fast = at("BM_FramePath"), ref = at("BM_FramePathReference");
    if (fast <= 0.0 || ref <= 0.0) continue;
    std::printf("%-11s frame path %.3f ms per frame (CPU; scan %.3f, refinement %.3f)   reference %.3f ms "
                "(refinement %.3f)   %.2fx faster   target %s\n",
                sizes[size], fast, at("BM_ScanStep"), at("BM_RefineStep"), ref, at("BM_RefineStepReference"),
                ref / fast, size == 0 ? "< 1 ms" : "< 3 ms");
  }
  benchmark::Shutdown();
  return 0;
}
