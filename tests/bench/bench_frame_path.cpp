// The whole per-frame path as the daemon runs it (issue 13 item 8): the robot-frame line extraction
// of one frame at the localizer's rays per degree (one LineExtractor kept from frame to frame), the
// field-frame scan at the heading, the local search in the fuzzy range around the odometry's
// prediction, and the sub-grid refinement (interpolation, then ray casting). Measured on five
// frames:
//   0  rendered 640 x 480      (OmniRenderer, common/cameras/default.json, two robots in view)
//   1  rendered 1280 x 1024    (the same camera scaled by 2: a larger sensor behind the same
//   mirror;
//                               its 477 px view sampled every 1.88 px, CameraModel::scan_step_px)
//   2  realistic 640 x 480     (RealisticRenderer: hyperbolic tilted mirror, walls, people, robots,
//                               noise, JPEG; matched with the optics' nominal camera)
//   3  realistic 1280 x 1024   (the same optics scaled by 2)
//   4  the real frame          (tests/data/tku-robosot-centre-spot.png with its calibrated camera)
// Each beside the reference, the same path as the code stood before this benchmark's speed work
// (LineExtractor::Walk::kBinWalk and refine_match_previous), in the same run; the ratio is printed
// at the end. Both give the same pose (checked here on every frame, and byte for byte in the
// tests).
#include <benchmark/benchmark.h>

#include "ratio_reporter.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "../host/test_data_path.hpp"
#include "omniloc/detail/line_extractor.hpp"
#include "omniloc/detail/vision_reference.hpp"
#include "omniloc/fuzzy.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/vision.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc {
namespace {

constexpr int kCases = 5;
const char* const kCaseNames[kCases] = {"rendered 640 x 480", "rendered 1280 x 1024",
                                        "realistic 640 x 480", "realistic 1280 x 1024",
                                        "real frame 640 x 480"};

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
  FieldGeometry field;
  CameraModel camera;
  FeatureDb db;
  cv::Mat image;
  Pose2 truth;
  Eigen::Vector2d predicted_cm;  // the odometry's prediction, 5 cm off
  double range_cm = 0.0;
  LocalizerConfig config;  // the shipped defaults: rays per degree, cost, refinement
  // The daemon's: one per camera, kept across frames (the new path's and the reference's).
  std::unique_ptr<LineExtractor> fast, reference;
};

Setup* build(int which) {
  auto s = std::make_unique<Setup>();
  s->field = load_field("fira-robosot");
  s->truth = {368.4, 371.7, 30.0};
  if (which == 0 || which == 1) {
    const CameraModel base = load_camera("default");
    s->camera = which == 0 ? base : scaled_camera(base, 2.0, 1280, 1024);
    const sim::OmniRenderer renderer(s->field, s->camera);
    sim::RenderOptions opt;
    opt.seed = 5;
    opt.obstacles = sim::random_obstacles(s->field, s->truth, 2, opt.seed);
    s->image = renderer.render(s->truth, opt);
  } else if (which == 2 || which == 3) {
    sim::TrueOptics optics;
    if (which == 3) {
      optics.width_px = 1280;
      optics.height_px = 1024;
      optics.centre_px *= 2.0;
      optics.focal_px *= 2.0;
      optics.mirror_radius_px *= 2.0;
      optics.ring_px *= 2.0;
    }
    const sim::RealisticRenderer renderer(s->field, optics);
    s->image = renderer.render(s->truth, sim::realistic(7));
    s->camera = nominal_camera(optics);
  } else {
    const auto img = test::test_data("tku-robosot-centre-spot.png");
    const auto cam = test::test_data("tku-robosot-centre-spot.camera.json");
    if (img.empty() || cam.empty()) return nullptr;
    s->image = cv::imread(img.string(), cv::IMREAD_COLOR);
    s->camera = load_camera(cam.string());
    s->truth = {375.0, 275.0,
                0.0};  // the centre spot; heading as `omniloc locate` finds it (-0.2 deg)
  }
  s->predicted_cm = Eigen::Vector2d(s->truth.x_cm + 3.0, s->truth.y_cm - 4.0);
  s->db = build_feature_db(s->field, s->camera, GridSpec::covering(s->field, 10.0));
  s->range_cm =
      fuzzy_search_range(s->config.fuzzy, 100.0).snapped_cm;  // 100 cm/s: 20 cm, 5 x 5 points
  s->fast = std::make_unique<LineExtractor>(s->camera);
  s->reference = std::make_unique<LineExtractor>(s->camera);
  // The first frame is walked twice (measuring the light): not what is measured.
  (void)s->fast->extract(s->image, s->config.scan_rays_per_degree);
  (void)detail::LineExtractorAccess::extract_with(*s->reference,
                                                  detail::LineExtractorAccess::Walk::kBinWalk,
                                                  s->image, s->config.scan_rays_per_degree);
  return s.release();
}

const Setup* setup(int which) {
  static std::map<int, std::unique_ptr<Setup>> cache;  // built once per case: not what is measured
  auto it = cache.find(which);
  if (it == cache.end()) it = cache.emplace(which, std::unique_ptr<Setup>(build(which))).first;
  return it->second.get();
}

MatchOptions options(const Setup& s) {
  MatchOptions mo;
  mo.refinement = Refinement::kRayCast;
  mo.cost = s.config.match_cost;
  mo.crossing_cap_px = s.config.crossing_cap_px;
  return mo;
}

BearingScan scan_step(const Setup& s, bool reference) {
  return reference ? detail::LineExtractorAccess::extract_with(
                         *s.reference, detail::LineExtractorAccess::Walk::kBinWalk, s.image,
                         s.config.scan_rays_per_degree)
                   : s.fast->extract(s.image, s.config.scan_rays_per_degree);
}

void refine_step(const Setup& s, const FieldScan& scan, MatchResult& m, const MatchOptions& mo,
                 bool reference) {
  if (reference) {
    refine_match_previous(s.field, s.camera, scan, m, mo);
  } else {
    refine_match(s.field, s.camera, scan, m, mo);
  }
}

// One frame: extraction, field-frame scan, local search, interpolation, ray-cast refinement.
MatchResult frame(const Setup& s, bool reference) {
  const MatchOptions mo = options(s);
  const FieldScan scan = make_field_scan(scan_step(s, reference), s.truth.yaw_deg);
  MatchResult m = local_search(s.db, scan, s.predicted_cm, s.range_cm, mo);
  interpolate_match(s.db, scan, m, mo);
  refine_step(s, scan, m, mo, reference);
  return m;
}

void run_frames(benchmark::State& state, bool reference) {
  const Setup* s = setup(static_cast<int>(state.range(0)));
  if (s == nullptr) {
    state.SkipWithError(
        "tests/data/tku-robosot-centre-spot.png not found (run from the build directory)");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(frame(*s, reference).position_cm);
  state.SetItemsProcessed(state.iterations());
}
void BM_FramePath(benchmark::State& state) {
  run_frames(state, false);
}
void BM_FramePathReference(benchmark::State& state) {
  run_frames(state, true);
}

// The steps alone, for the breakdown.
void extract_only(benchmark::State& state, bool reference) {
  const Setup* s = setup(static_cast<int>(state.range(0)));
  if (s == nullptr) {
    state.SkipWithError("tests/data/tku-robosot-centre-spot.png not found");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(scan_step(*s, reference));
  state.SetItemsProcessed(state.iterations());
}
void BM_ScanStep(benchmark::State& state) {
  extract_only(state, false);
}
void BM_ScanStepReference(benchmark::State& state) {
  extract_only(state, true);
}

void refine_only(benchmark::State& state, bool reference) {
  const Setup* s = setup(static_cast<int>(state.range(0)));
  if (s == nullptr) {
    state.SkipWithError("tests/data/tku-robosot-centre-spot.png not found");
    return;
  }
  const MatchOptions mo = options(*s);
  const FieldScan scan = make_field_scan(scan_step(*s, reference), s->truth.yaw_deg);
  MatchResult start = local_search(s->db, scan, s->predicted_cm, s->range_cm, mo);
  interpolate_match(s->db, scan, start, mo);
  for (auto _ : state) {
    MatchResult m = start;
    refine_step(*s, scan, m, mo, reference);
    benchmark::DoNotOptimize(m.position_cm);
  }
  state.SetItemsProcessed(state.iterations());
}
void BM_RefineStep(benchmark::State& state) {
  refine_only(state, false);
}
void BM_RefineStepReference(benchmark::State& state) {
  refine_only(state, true);
}

BENCHMARK(BM_FramePath)->DenseRange(0, kCases - 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FramePathReference)->DenseRange(0, kCases - 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScanStep)->DenseRange(0, kCases - 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScanStepReference)->DenseRange(0, kCases - 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineStep)->DenseRange(0, kCases - 1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineStepReference)->DenseRange(0, kCases - 1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace omniloc

namespace omniloc {
namespace {

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// The machine is shared: the new path and the reference are timed in alternating rounds of a few
// frames each (thread CPU time), so that both see the same load, and the median round is taken.
struct Paired {
  double fast_ms = 0.0, reference_ms = 0.0;
};
Paired paired(const Setup& s, int rounds = 41, int frames = 5) {
  std::vector<double> f, r;
  for (int i = 0; i < rounds; ++i) {
    for (int which = 0; which < 2; ++which) {
      const double t0 = thread_cpu_ms();
      for (int k = 0; k < frames; ++k) benchmark::DoNotOptimize(frame(s, which == 1).position_cm);
      (which == 0 ? f : r).push_back((thread_cpu_ms() - t0) / frames);
    }
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  return {median(f), median(r)};
}

}  // namespace
}  // namespace omniloc

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  omniloc::bench::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto& m = reporter.ns_per_item;
  std::printf(
      "\nper frame, CPU ms, median of 41 alternating rounds of 5 frames: new path | reference (the "
      "code before) "
      "| ratio | target | same pose | steps above (extraction + refinement), new | reference\n");
  int failures = 0;
  for (int c = 0; c < omniloc::kCases; ++c) {
    const auto at = [&](const std::string& name) {
      const auto it = m.find(name + "/" + std::to_string(c));
      return it == m.end() ? -1.0 : it->second / 1e6;
    };
    if (at("BM_FramePath") <= 0.0 || at("BM_FramePathReference") <= 0.0) continue;
    const omniloc::Setup& s = *omniloc::setup(c);
    const omniloc::Paired p = omniloc::paired(s);
    const double fast = p.fast_ms, ref = p.reference_ms;
    const auto a = omniloc::frame(s, false), b = omniloc::frame(s, true);
    const bool same = a.position_cm == b.position_cm && a.refined_error == b.refined_error;
    failures += same ? 0 : 1;
    const bool big = s.camera.width_px > 1000;
    std::printf("%-22s %6.3f ms | %6.3f ms | %5.2fx | %s %-7s | %-3s | %.3f + %.3f | %.3f + %.3f\n",
                omniloc::kCaseNames[c], fast, ref, ref / fast, big ? "< 3 ms" : "< 1 ms",
                fast < (big ? 3.0 : 1.0) ? "met" : "NOT met", same ? "yes" : "NO",
                at("BM_ScanStep"), at("BM_RefineStep"), at("BM_ScanStepReference"),
                at("BM_RefineStepReference"));
  }
  benchmark::Shutdown();
  return failures == 0 ? 0 : 1;
}
