// The live view's cost per overlay image (live_view.hpp): LiveState::frame_jpeg (what the page
// shows) and frame_png (lossless, on request) on a new 640 x 480 rendered frame each time (the line
// extraction, the goal observation, locate_overlay, the encoding), beside the reference measured in
// the same run: the line extraction alone, which the localizer runs on every frame (60 Hz). The
// live view makes at most 5 images a second, so its load is ratio x 5 / 60 of the extraction's.
#include <benchmark/benchmark.h>

#include "ratio_reporter.hpp"

#include <cstdio>
#include <string>

#include "omniloc/camera.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/field.hpp"
#include "omniloc/live_view.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/vision.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc {
namespace {

struct Setup {
  daemon::DaemonModels models;
  cv::Mat frame;
  Setup() {
    models.field = load_field("fira-robosot");
    models.camera = load_camera("default");
    models.localizer = load_localizer_config("default");
    frame = sim::render_omni(models.field, models.camera, {300.0, 200.0, 20.0}, {});
  }
};

const Setup& setup() {
  static const Setup s;
  return s;
}

void frame_image(benchmark::State& state, bool png) {
  const Setup& s = setup();
  live::LiveViewOptions o;
  o.frame_min_period_ms = 0.0;  // every call makes an image (the bound is measured, not applied)
  live::LiveState live(s.models, o);
  daemon::PoseEvent pose;
  pose.message.x_cm = 300.0;
  pose.message.y_cm = 200.0;
  pose.message.yaw_deg = 20.0;
  pose.message.status = daemon::DaemonStatus::kOk;
  live.on_pose(pose);
  double t_ms = 0.0;
  std::size_t bytes = 0;
  for (auto _ : state) {
    live.on_frame({t_ms += 1000.0, s.frame});
    bytes = (png ? live.frame_png() : live.frame_jpeg())->size();
    benchmark::DoNotOptimize(bytes);
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["kB"] = static_cast<double>(bytes) / 1024.0;
}
void BM_LiveViewFrameJpeg(benchmark::State& state) {
  frame_image(state, false);
}
void BM_LiveViewFramePng(benchmark::State& state) {
  frame_image(state, true);
}
BENCHMARK(BM_LiveViewFrameJpeg)->Unit(benchmark::kMillisecond)->MinTime(1.0);
BENCHMARK(BM_LiveViewFramePng)->Unit(benchmark::kMillisecond)->MinTime(1.0);

void BM_ReferenceLineExtraction(benchmark::State& state) {
  const Setup& s = setup();
  LineExtractor extractor(s.models.camera);
  for (auto _ : state) {
    auto scan = extractor.extract(s.frame, s.models.localizer.scan_rays_per_degree);
    benchmark::DoNotOptimize(scan);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ReferenceLineExtraction)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace
}  // namespace omniloc

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  omniloc::bench::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  const auto find = [&](const std::string& prefix) {
    for (const auto& [name, ns] : reporter.ns_per_item)
      if (name.rfind(prefix, 0) == 0) return ns;
    return 0.0;
  };
  const double ref = find("BM_ReferenceLineExtraction");
  if (ref > 0) {
    std::printf("\nline extraction (reference) %.2f ms\n", ref / 1e6);
    for (const char* name : {"BM_LiveViewFrameJpeg", "BM_LiveViewFramePng"}) {
      const double t = find(name);
      if (t > 0)
        std::printf(
            "%-22s %.2f ms | %.2fx the extraction; at 5 images/s against 60 frames/s: %.0f%% of "
            "the "
            "extraction's load\n",
            name + 3, t / 1e6, t / ref, 100.0 * (t / ref) * 5.0 / 60.0);
    }
  }
  benchmark::Shutdown();
  return 0;
}
