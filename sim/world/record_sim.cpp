// Simulated runs for the localizer tests, the paper benchmark and recordings.
#include "omniloc_sim/record_sim.hpp"

#include "omniloc/recording.hpp"

namespace omniloc::sim {

namespace {

FrameRender omni_render(const OmniRenderer& renderer) {
  return [&renderer](double, const Pose2& truth, const RenderOptions& options) {
    return renderer.render(truth, options);
  };
}

}  // namespace

void run_simulation(World& world, const OmniRenderer& renderer, const SimRunOptions& options,
                    const std::function<void(const SimWindow&)>& on_window,
                    const std::function<void(const SimFrame&)>& on_frame) {
  run_simulation(world, omni_render(renderer), options, on_window, on_frame);
}

void run_simulation(World& world, const FrameRender& renderer, const SimRunOptions& options,
                    const std::function<void(const SimWindow&)>& on_window,
                    const std::function<void(const SimFrame&)>& on_frame) {
  const double clock_hz = world.config().clock_hz;
  const double window_ms = static_cast<double>(world.config().window_cycles) * 1000.0 / clock_hz;
  const double end_s =
      options.max_duration_s > 0.0 ? options.max_duration_s : world.trajectory().duration_s();
  double next_frame_ms = options.first_frame_ms;
  double next_window_ms =
      static_cast<double>(world.config().first_window_end_cycles) * 1000.0 / clock_hz;
  RenderOptions render = options.render;
  const std::uint64_t seed0 = render.seed;
  std::uint64_t frame_index = 0;
  while (world.time_s() < end_s) {
    if (next_frame_ms < next_window_ms) {
      // Step until the frame time, render there (frames are taken at physics-step ends).
      while (world.time_s() * 1000.0 < next_frame_ms - 1e-9) world.step();
      if (on_frame) {
        SimFrame f;
        f.t_ms = world.time_s() * 1000.0;
        f.truth = world.truth();
        f.truth.yaw_deg = wrap_deg(f.truth.yaw_deg);
        render.seed = seed0 + 7919 * ++frame_index;  // fresh sensor noise per frame
        if (options.render_frames) f.bgr = renderer(f.t_ms, f.truth, render);
        on_frame(f);
      }
      next_frame_ms += options.frame_period_ms;
    } else {
      const SimWindow w = world.next_window();
      if (on_window) on_window(w);
      next_window_ms += window_ms;
    }
  }
}

void record_simulation(const std::filesystem::path& dir, World& world, const OmniRenderer& renderer,
                       const SimRunOptions& options, const std::string& field_name,
                       const std::optional<Pose2>& initial_pose,
                       const RecordingOptions& recording) {
  record_simulation(dir, world, renderer.camera(), omni_render(renderer), options, field_name,
                    initial_pose, recording);
}

void record_simulation(const std::filesystem::path& dir, World& world, const CameraModel& camera,
                       const FrameRender& renderer, const SimRunOptions& options,
                       const std::string& field_name, const std::optional<Pose2>& initial_pose,
                       const RecordingOptions& recording) {
  RecordingMeta meta;
  meta.field = field_name;
  meta.field_geometry = load_field(field_name).spec;
  meta.camera = camera;
  meta.robot = world.config().robot;
  meta.initial_pose = initial_pose;
  RecordingWriter writer(dir, meta, true, recording);
  run_simulation(
      world, renderer, options,
      [&](const SimWindow& w) {
        writer.add_window(w.window);
        writer.add_truth(w.window.t_end_ms, w.truth);
      },
      [&](const SimFrame& f) { writer.add_frame(f.t_ms, f.bgr); });
  writer.close();
}

LocalizedRun localize_simulation(World& world, const OmniRenderer& renderer,
                                 const SimRunOptions& options, Localizer& localizer) {
  LocalizedRun run;
  run_simulation(
      world, renderer, options,
      [&](const SimWindow& w) {
        run.windows.push_back(w);
        run.poses.push_back(localizer.on_window(w.window));
        for (FrameReport& r : localizer.take_frame_reports()) run.frames.push_back(r);
      },
      [&](const SimFrame& f) {
        (void)localizer.on_image(f.t_ms, f.bgr);
        for (FrameReport& r : localizer.take_frame_reports()) run.frames.push_back(r);
        run.frame_truth.push_back({f.t_ms, f.truth, cv::Mat()});
      });
  return run;
}

}  // namespace omniloc::sim
