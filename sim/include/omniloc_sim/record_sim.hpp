// A simulated run as the localizer sees it: encoder windows from the World (100 Hz) and camera
// frames rendered at the true pose (60 Hz, taken at physics-step ends), delivered in time order;
// and a writer that stores such a run as a recording directory (recording.hpp) for `omniloc
// replay`.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "omniloc/conventions.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/recording.hpp"
#include "omniloc_sim/renderer.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::sim {

struct SimRunOptions {
  double frame_period_ms = 1000.0 / 60.0;
  double first_frame_ms = 5.0;  ///< nominal time of the first frame
  RenderOptions render;         ///< noise, obstacles...; the seed is advanced per frame
  double max_duration_s = 0.0;  ///< 0: until the trajectory (and its final wait) is over
  bool render_frames = true;    ///< false: SimFrame::bgr stays empty (the caller supplies images)
};

struct SimFrame {
  /// when the image was taken (the first physics-step end at or after the nominal time)
  double t_ms = 0.0;
  Pose2 truth;  ///< true pose then (yaw wrapped)
  cv::Mat bgr;
};

/// What draws a frame: the image taken at t_ms at the true pose, with the run's render options
/// (their seed advanced per frame). OmniRenderer::render is one; a RealisticRenderer, or a renderer
/// whose light changes with t_ms, is another.
using FrameRender =
    std::function<cv::Mat(double t_ms, const Pose2& truth, const RenderOptions& options)>;

/// Runs `world` to the end, calling on_frame and on_window in time order (a frame at t comes
/// before the window whose end is >= t). Either callback may be empty (frames are then not
/// rendered).
void run_simulation(World& world, const FrameRender& render, const SimRunOptions& options,
                    const std::function<void(const SimWindow&)>& on_window,
                    const std::function<void(const SimFrame&)>& on_frame);
void run_simulation(World& world, const OmniRenderer& renderer, const SimRunOptions& options,
                    const std::function<void(const SimWindow&)>& on_window,
                    const std::function<void(const SimFrame&)>& on_frame);

/// Writes the run as a recording directory with truth.csv (one truth row per window). meta.json
/// names `field_name`, `camera` (the renderer's, for an OmniRenderer), the world's robot and, if
/// given, initial_pose.
void record_simulation(const std::filesystem::path& dir, World& world, const CameraModel& camera,
                       const FrameRender& render, const SimRunOptions& options,
                       const std::string& field_name, const std::optional<Pose2>& initial_pose,
                       const RecordingOptions& recording = {});
void record_simulation(const std::filesystem::path& dir, World& world, const OmniRenderer& renderer,
                       const SimRunOptions& options, const std::string& field_name,
                       const std::optional<Pose2>& initial_pose,
                       const RecordingOptions& recording = {});

/// A simulated run fed through a localizer: per window, the truth and the localizer's pose.
struct LocalizedRun {
  std::vector<SimWindow> windows;
  std::vector<LocalizedPose> poses;   ///< poses[i] answers windows[i]
  std::vector<FrameReport> frames;    ///< every frame's outcome, in processing order
  std::vector<SimFrame> frame_truth;  ///< time and truth of each frame (images not kept)
};
[[nodiscard]] LocalizedRun localize_simulation(World& world, const OmniRenderer& renderer,
                                               const SimRunOptions& options, Localizer& localizer);

}  // namespace omniloc::sim
