// The simulated robot behind omnilocd's `--board sim --camera sim`, and behind `omniloc demo`:
// the world simulator's truth and gyro, logged as the simulation advances, and a camera that
// renders the field at the true pose. Header-only on top of omniloc_sim (no Verilated board here:
// daemon_board_sim.hpp adds that), so host tests can use it with a reference board.
#pragma once

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <string>

#include "omniloc/conventions.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc_sim/renderer.hpp"
#include "omniloc_sim/trajectory.hpp"

namespace omniloc::daemon {

/// Truth and gyro samples in daemon time, appended as the simulation runs; interpolated lookups.
class SimTruthLog final : public WindowExtras {
 public:
  explicit SimTruthLog(double keep_ms = 10'000.0) : keep_ms_(keep_ms) {}

  /// yaw of `truth` may be unwrapped; gyro_yaw_deg is what the gyro reports (wrapped).
  void add(double t_ms, const Pose2& truth, double gyro_yaw_deg) {
    if (!samples_.empty() && t_ms <= samples_.back().t_ms) return;
    samples_.push_back({t_ms, truth, gyro_yaw_deg});
    while (samples_.size() > 2 && samples_.front().t_ms < t_ms - keep_ms_) samples_.pop_front();
  }

  double gyro_yaw_deg(const EncoderWindow& window) override {
    const auto s = sample_at(window.t_end_ms);
    if (s) return s->gyro_yaw_deg;
    return samples_.empty() ? 0.0 : samples_.back().gyro_yaw_deg;
  }
  [[nodiscard]] bool gyro_is_absolute() const override { return true; }
  [[nodiscard]] bool has_truth() const override { return true; }
  std::optional<Pose2> truth(double t_ms) override {
    const auto s = sample_at(t_ms);
    if (!s) return std::nullopt;
    return s->truth;
  }
  [[nodiscard]] double latest_ms() const { return samples_.empty() ? -1e300 : samples_.back().t_ms; }

 private:
  struct Sample {
    double t_ms;
    Pose2 truth;
    double gyro_yaw_deg;
  };
  [[nodiscard]] std::optional<Sample> sample_at(double t_ms) const {
    if (samples_.empty() || t_ms < samples_.front().t_ms || t_ms > samples_.back().t_ms) return std::nullopt;
    const auto it = std::lower_bound(samples_.begin(), samples_.end(), t_ms,
                                     [](const Sample& s, double t) { return s.t_ms < t; });
    if (it->t_ms == t_ms || it == samples_.begin()) return *it;
    const Sample& a = *(it - 1);
    const Sample& b = *it;
    const double f = (t_ms - a.t_ms) / (b.t_ms - a.t_ms);
    Sample s;
    s.t_ms = t_ms;
    s.truth.x_cm = a.truth.x_cm + f * (b.truth.x_cm - a.truth.x_cm);
    s.truth.y_cm = a.truth.y_cm + f * (b.truth.y_cm - a.truth.y_cm);
    s.truth.yaw_deg = wrap_deg(a.truth.yaw_deg + f * angle_diff_deg(b.truth.yaw_deg, a.truth.yaw_deg));
    s.gyro_yaw_deg = wrap_deg(a.gyro_yaw_deg + f * angle_diff_deg(b.gyro_yaw_deg, a.gyro_yaw_deg));
    return s;
  }
  double keep_ms_;
  std::deque<Sample> samples_;
};

/// A camera rendering the field at the logged true pose, `fps` frames per second of daemon time.
class SimCamera final : public FrameSource {
 public:
  SimCamera(const sim::OmniRenderer& renderer, SimTruthLog& truth, double fps, sim::RenderOptions options = {})
      : renderer_(renderer), truth_(truth), period_ms_(1000.0 / fps), options_(std::move(options)) {}

  /// Frames taken at or after t_ms are not delivered (a camera that stops): for tests and demos.
  void stop_at(double t_ms) { stop_ms_ = t_ms; }

  std::optional<CameraFrame> poll(double now_ms) override {
    const double k = std::floor(std::min(now_ms, truth_.latest_ms()) / period_ms_);
    if (k <= last_k_ || k < 0) return std::nullopt;
    const double t = k * period_ms_;
    if (t >= stop_ms_) return std::nullopt;
    const auto pose = truth_.truth(t);
    if (!pose) return std::nullopt;
    last_k_ = k;
    sim::RenderOptions o = options_;
    o.seed = options_.seed + static_cast<std::uint64_t>(k);  // fresh sensor noise per frame
    return CameraFrame{t, renderer_.render(*pose, o)};
  }
  [[nodiscard]] std::string describe() const override { return "simulated omni camera"; }

 private:
  const sim::OmniRenderer& renderer_;
  SimTruthLog& truth_;
  double period_ms_;
  sim::RenderOptions options_;
  double last_k_ = -1.0;
  double stop_ms_ = 1e300;
};

/// The drive of `omniloc demo`: from the centre to the right goal line, then along all four
/// boundary lines (5-10 cm inside them), back towards the middle, a kidnapping while
/// stopped (carried 250 cm and turned 90 degrees), then a last leg driven from where the robot was
/// put down (the world moves the rest of the reference rigidly with it), padded to duration_s.
struct DemoDrive {
  sim::Trajectory trajectory{"demo", {375.0, 275.0, 0.0}};
  double kidnap_s = 0.0;
  Pose2 kidnap_to;
  double slip_s = 8.0;  ///< wheel 2 slips from here for 0.5 s
};

[[nodiscard]] inline DemoDrive demo_drive(double duration_s = 30.0) {
  DemoDrive d;
  const sim::MotionLimits lim{120.0, 240.0, 120.0, 240.0};
  auto& t = d.trajectory;
  // The field lines are at x = 75 / 675 and y = 75 / 475: the boundary legs run 5-10 cm inside
  // them, where the paper's image-only method fails (its Fig. 18 boundary points).
  t.line_to({665.0, 275.0}, 0.0, lim);    // to the right goal line
  t.line_to({670.0, 470.0}, 90.0, lim);   // along it to the top-right corner
  t.line_to({80.0, 470.0}, 180.0, lim);   // along the top line
  t.line_to({80.0, 80.0}, 270.0, lim);    // along the left goal line
  t.line_to({670.0, 80.0}, 360.0, lim);   // along the bottom line
  t.line_to({450.0, 220.0}, 360.0, lim);
  t.wait(0.6);
  d.kidnap_s = t.duration_s() - 0.3;
  d.kidnap_to = Pose2{250.0, 360.0, 90.0};
  // +x of the old frame becomes +y here: this leg ends near (250, 440).
  t.line_to({530.0, 220.0}, 360.0, lim);
  if (t.duration_s() < duration_s) t.wait(duration_s - t.duration_s());
  return d;
}

}  // namespace omniloc::daemon
