// Vision benchmarks: each fast path beside its straightforward reference in the same run; the
// ratios, the targets and the database size are printed at the end.
//   line scan of one 640 x 480 image        scan_image vs scan_image_reference (OpenCV whole image)
//   line extraction, 360 x 4 rays           LineExtractor::extract vs extract_reference (+ fixed
//   thresholds) global search (75 x 55)                 global_search vs global_search_reference
//   (scalar SAD) local search, range 0/10/20/30 cm       local_search vs a scalar loop over the
//   same window image to pose (local 20 cm, global)     scan + search + refinement vs reference
//   scan + scalar search
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "omniloc/detail/line_extractor.hpp"
#include "omniloc/detail/vision_reference.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/matcher.hpp"
#include "omniloc/vision.hpp"
#include "omniloc_sim/renderer.hpp"

namespace {

using namespace omniloc;

struct Fixture {
  FieldGeometry field = load_field("fira-robosot");
  CameraModel camera = load_camera("default");
  FeatureDb db = build_feature_db(field, camera, GridSpec::covering(field, 10.0));
  Pose2 truth{228.7, 171.2, 37.0};
  cv::Mat image;
  Scan scan;
  Fixture() {
    sim::OmniRenderer renderer(field, camera);
    sim::RenderOptions opt;
    opt.seed = 3;
    opt.obstacles = sim::random_obstacles(field, truth, 2, 3);
    image = renderer.render(truth, opt);
    scan = scan_image(image, camera, truth.yaw_deg);
  }
};

Fixture& fx() {
  static Fixture f;  // built once per process: loading and the database are not what is measured
  return f;
}

// The naive local search: the same window, scalar SAD, keep the minimum.
int local_reference(const FeatureDb& db, const Scan& scan, const Eigen::Vector2d& c,
                    double range_cm) {
  const GridSpec& g = db.grid;
  const int ci = static_cast<int>(std::lround((c.x() - g.x0_cm) / g.step_cm));
  const int cj = static_cast<int>(std::lround((c.y() - g.y0_cm) / g.step_cm));
  const int reach = static_cast<int>(range_cm / g.step_cm);
  std::uint32_t best = UINT32_MAX;
  int best_cell = -1;
  for (int j = std::max(0, cj - reach); j <= std::min(g.ny - 1, cj + reach); ++j) {
    for (int i = std::max(0, ci - reach); i <= std::min(g.nx - 1, ci + reach); ++i) {
      const std::uint32_t e = sad_reference(db.cell_features(j * g.nx + i), scan);
      if (e < best) {
        best = e;
        best_cell = j * g.nx + i;
      }
    }
  }
  return best_cell;
}

void BM_LineScan_Fast(benchmark::State& st) {
  for (auto _ : st)
    benchmark::DoNotOptimize(scan_image(fx().image, fx().camera, fx().truth.yaw_deg));
}
void BM_LineScan_Reference(benchmark::State& st) {
  for (auto _ : st)
    benchmark::DoNotOptimize(scan_image_reference(fx().image, fx().camera, fx().truth.yaw_deg));
}
// The line extraction (LineExtractor::extract, 360 x 4 rays, adaptive carpet-relative classes)
// against its reference walk (extract_reference: every pixel's HSV on every ray touching it; the
// results are equal byte for byte, test_vision_extraction), and the older fixed-threshold
// scan_image_bearings on the same frame for scale.
// Argument: rays per degree (4: the localizer's default).
void BM_Extract_Fast(benchmark::State& st) {
  const int rpd = static_cast<int>(st.range(0));
  LineExtractor ex(fx().camera);
  (void)ex.extract(fx().image, rpd);  // the first frame is walked twice (measuring the light)
  for (auto _ : st) benchmark::DoNotOptimize(ex.extract(fx().image, rpd));
}
void BM_Extract_Reference(benchmark::State& st) {
  const int rpd = static_cast<int>(st.range(0));
  LineExtractor ex(fx().camera);
  (void)detail::LineExtractorAccess::extract_reference(ex, fx().image, rpd);
  for (auto _ : st)
    benchmark::DoNotOptimize(detail::LineExtractorAccess::extract_reference(ex, fx().image, rpd));
}
void BM_ExtractFixedThresholds(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(scan_image_bearings(fx().image, fx().camera, 4));
}
void BM_GlobalSearch_Fast(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(global_search(fx().db, fx().scan));
  st.counters["db_bytes"] = static_cast<double>(fx().db.bytes_in_memory());
}
void BM_GlobalSearch_Reference(benchmark::State& st) {
  for (auto _ : st) benchmark::DoNotOptimize(global_search_reference(fx().db, fx().scan));
}
void BM_LocalSearch_Fast(benchmark::State& st) {
  const Eigen::Vector2d c(fx().truth.x_cm + 7.0, fx().truth.y_cm - 4.0);
  for (auto _ : st)
    benchmark::DoNotOptimize(local_search(fx().db, fx().scan, c, static_cast<double>(st.range(0))));
}
void BM_LocalSearch_Reference(benchmark::State& st) {
  const Eigen::Vector2d c(fx().truth.x_cm + 7.0, fx().truth.y_cm - 4.0);
  for (auto _ : st)
    benchmark::DoNotOptimize(
        local_reference(fx().db, fx().scan, c, static_cast<double>(st.range(0))));
}
void BM_ImageToPose_Local20_Fast(benchmark::State& st) {
  const Eigen::Vector2d c(fx().truth.x_cm + 7.0, fx().truth.y_cm - 4.0);
  for (auto _ : st) {
    benchmark::DoNotOptimize(image_to_position(fx().image, fx().camera, fx().field, fx().db,
                                               fx().truth.yaw_deg, &c, 20.0));
  }
}
void BM_ImageToPose_Local20_Reference(benchmark::State& st) {
  const Eigen::Vector2d c(fx().truth.x_cm + 7.0, fx().truth.y_cm - 4.0);
  for (auto _ : st) {
    const Scan s = scan_image_reference(fx().image, fx().camera, fx().truth.yaw_deg);
    benchmark::DoNotOptimize(local_reference(fx().db, s, c, 20.0));
  }
}
void BM_ImageToPose_Global_Fast(benchmark::State& st) {
  for (auto _ : st) {
    benchmark::DoNotOptimize(image_to_position(fx().image, fx().camera, fx().field, fx().db,
                                               fx().truth.yaw_deg, nullptr, 0.0));
  }
}
void BM_ImageToPose_Global_Reference(benchmark::State& st) {
  for (auto _ : st) {
    const Scan s = scan_image_reference(fx().image, fx().camera, fx().truth.yaw_deg);
    benchmark::DoNotOptimize(global_search_reference(fx().db, s));
  }
}
void BM_Refine_Only(benchmark::State& st) {
  const MatchResult base = global_search(fx().db, fx().scan);
  for (auto _ : st) {
    MatchResult m = base;
    refine_match(fx().field, fx().camera, fx().scan, m);
    benchmark::DoNotOptimize(m);
  }
}
void BM_BuildDatabase_2Threads(benchmark::State& st) {
  for (auto _ : st)
    benchmark::DoNotOptimize(build_feature_db(fx().field, fx().camera, fx().db.grid, {}, 2));
}

BENCHMARK(BM_LineScan_Fast)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LineScan_Reference)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Extract_Fast)->Arg(4)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Extract_Reference)->Arg(4)->Arg(1)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ExtractFixedThresholds)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GlobalSearch_Fast)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GlobalSearch_Reference)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LocalSearch_Fast)->Arg(0)->Arg(10)->Arg(20)->Arg(30)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LocalSearch_Reference)
    ->Arg(0)
    ->Arg(10)
    ->Arg(20)
    ->Arg(30)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ImageToPose_Local20_Fast)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ImageToPose_Local20_Reference)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ImageToPose_Global_Fast)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ImageToPose_Global_Reference)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Refine_Only)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BuildDatabase_2Threads)->Unit(benchmark::kMillisecond)->Iterations(3);

// Remembers each run's CPU time per iteration (the machine is shared) (microseconds) to print the
// ratios afterwards.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const auto& r : runs) {
      const double us =
          r.GetAdjustedCPUTime() * 1e6 / benchmark::GetTimeUnitMultiplier(r.time_unit);
      times_[r.benchmark_name()] = us;
    }
    ConsoleReporter::ReportRuns(runs);
  }
  void print_summary() const {
    std::printf("\nfast vs reference (same run; speed-up = reference time / fast time):\n");
    for (const auto& [name, fast_us] : times_) {
      const auto pos = name.find("_Fast");
      if (pos == std::string::npos) continue;
      std::string ref = name;
      ref.replace(pos, 5, "_Reference");
      const auto it = times_.find(ref);
      if (it == times_.end()) continue;
      std::printf("  %-40s %9.1f us   reference %9.1f us   speed-up x%.1f\n", name.c_str(), fast_us,
                  it->second, it->second / fast_us);
    }
    auto show = [&](const char* name, const char* label, double target_us) {
      const auto it = times_.find(name);
      if (it == times_.end()) return;
      std::printf("  %-44s %8.3f ms  (target < %.2f ms: %s)\n", label, it->second / 1000.0,
                  target_us / 1000.0, it->second < target_us ? "met" : "NOT met");
    };
    std::printf("\ntargets:\n");
    show("BM_Extract_Fast/4", "line extraction, 360 x 4 rays (LineExtractor)", 350.0);
    show("BM_ImageToPose_Local20_Fast", "image to pose, 20 cm local search + refine", 1000.0);
    show("BM_GlobalSearch_Fast", "global search (75 x 55)", 2000.0);
    show("BM_ImageToPose_Global_Fast", "image to pose, global search + refine", 2000.0);
    std::printf("  database in memory: %zu bytes (%d grid points x %d bytes)\n",
                fx().db.bytes_in_memory(), fx().db.grid.cells(), kFeatureBytes);
  }

 private:
  std::map<std::string, double> times_;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  (void)fx();
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.print_summary();
  benchmark::Shutdown();
  return 0;
}
