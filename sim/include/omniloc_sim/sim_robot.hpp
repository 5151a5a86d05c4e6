// The simulated robot's I/O for the robot's own Daemon (omniloc/daemon.hpp), used by
// `omnilocd-sim`, `omniloc-sim demo` and the tests: the world simulator's truth and gyro, logged as
// the simulation advances (the heading source; truth is looked up by observers, never by the
// daemon), and a camera that renders the field at the true pose. Header-only on top of omniloc_sim
// (no Verilated board here: verilated_robot.hpp adds that), so host tests can use it with a
// reference board.
#pragma once

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "omniloc/conventions.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc::sim {

using daemon::CameraFrame;
using daemon::FrameSource;
using daemon::HeadingSource;

/// Truth and gyro samples in daemon time, appended as the simulation runs; interpolated lookups.
/// The daemon sees it only as its heading source (the simulated gyro); observers ask it for truth.
class SimTruthLog final : public HeadingSource {
 public:
  explicit SimTruthLog(double keep_ms = 10'000.0) : keep_ms_(keep_ms) {}

  /// yaw of `truth` may be unwrapped; gyro_yaw_deg is what the gyro reports (wrapped).
  void add(double t_ms, const Pose2& truth, double gyro_yaw_deg) {
    if (!samples_.empty() && t_ms <= samples_.back().t_ms) return;
    samples_.push_back({t_ms, truth, gyro_yaw_deg});
    while (samples_.size() > 2 && samples_.front().t_ms < t_ms - keep_ms_) samples_.pop_front();
    if (on_added_) on_added_(t_ms);
  }
  /// Called on the simulating thread after each new sample (the camera starts renders from it).
  void set_on_added(std::function<void(double t_ms)> f) { on_added_ = std::move(f); }

  double gyro_yaw_deg(const EncoderWindow& window) override { return gyro_yaw_at(window.t_end_ms); }
  /// What the gyro reported at t_ms (the newest sample when t_ms is beyond the log).
  [[nodiscard]] double gyro_yaw_at(double t_ms) const {
    const auto s = sample_at(t_ms);
    if (s) return s->gyro_yaw_deg;
    return samples_.empty() ? 0.0 : samples_.back().gyro_yaw_deg;
  }
  [[nodiscard]] bool is_absolute() const override { return true; }
  /// The true pose at t_ms (interpolated), nullopt outside the logged span.
  [[nodiscard]] std::optional<Pose2> truth(double t_ms) const {
    const auto s = sample_at(t_ms);
    if (!s) return std::nullopt;
    return s->truth;
  }
  /// The newest truth sample's time (none: no sample yet).
  [[nodiscard]] std::optional<double> latest_ms() const {
    if (samples_.empty()) return std::nullopt;
    return samples_.back().t_ms;
  }

 private:
  struct Sample {
    double t_ms;
    Pose2 truth;
    double gyro_yaw_deg;
  };
  [[nodiscard]] std::optional<Sample> sample_at(double t_ms) const {
    if (samples_.empty() || t_ms < samples_.front().t_ms || t_ms > samples_.back().t_ms)
      return std::nullopt;
    const auto it = std::lower_bound(samples_.begin(), samples_.end(), t_ms,
                                     [](const Sample& s, double t) { return s.t_ms < t; });
    if (it->t_ms == t_ms || it == samples_.begin()) return *it;
    const Sample& a = *(it - 1);
    const Sample& b = *it;
    const double f = (t_ms - a.t_ms) / (b.t_ms - a.t_ms);
    Sample s;
    s.t_ms = t_ms;
    s.truth = interpolate(a.truth, b.truth, f);
    s.gyro_yaw_deg = interpolate_deg(a.gyro_yaw_deg, b.gyro_yaw_deg, f);
    return s;
  }
  double keep_ms_;
  std::deque<Sample> samples_;
  std::function<void(double)> on_added_;
};

/// A camera rendering the field at the logged true pose, `fps` frames per second of daemon time.
/// Frame k is taken at k / fps; poll() hands out the newest frame due (older undelivered ones are
/// dropped, as a live camera would). Rendering runs on a worker thread, started as soon as the
/// truth log has passed a frame's time, so the simulation and the renderer use two cores; poll()
/// waits for the frame it returns, so what is delivered does not depend on thread timing.
class SimCamera final : public FrameSource {
 public:
  SimCamera(const OmniRenderer& renderer, SimTruthLog& truth, double fps,
            RenderOptions options = {});
  ~SimCamera() override;
  SimCamera(const SimCamera&) = delete;
  SimCamera& operator=(const SimCamera&) = delete;

  /// Frames taken at or after t_ms are not delivered (a camera that stops): for tests and demos.
  void stop_at(double t_ms) { stop_ms_ = t_ms; }
  /// A driver's delays (sim_clocks.hpp): frame k, exposed at k / fps, is handed over
  /// `latency_ms + jitter_ms x u_k` later (u_k uniform 0..1 from the seed and k) and stamped then
  /// (time_source "host": the daemon subtracts its camera_latency_ms); a fraction `drop` of frames
  /// is lost. Without this call: no delay, stamped with the exposure time (time_source "sim").
  void set_delays(double latency_ms, double jitter_ms, double drop, std::uint64_t seed) {
    latency_ms_ = latency_ms;
    jitter_ms_ = jitter_ms;
    drop_ = drop;
    delay_seed_ = seed;
    delayed_ = latency_ms > 0.0 || jitter_ms > 0.0 || drop > 0.0;
  }
  /// When frame k is handed over (its exposure time with no delays), and whether it is lost.
  [[nodiscard]] double handover_ms(std::int64_t k) const {
    return static_cast<double>(k) * period_ms_ +
           (delayed_ ? latency_ms_ + jitter_ms_ * unit(k, 1) : 0.0);
  }
  [[nodiscard]] bool dropped(std::int64_t k) const { return delayed_ && unit(k, 2) < drop_; }
  [[nodiscard]] double period_ms() const { return period_ms_; }

  std::optional<CameraFrame> poll(double now_ms) override;
  [[nodiscard]] std::string describe() const override { return "simulated omni camera"; }

 private:
  struct Worker;
  void on_truth(double t_ms);
  const OmniRenderer& renderer_;
  SimTruthLog& truth_;
  double period_ms_;
  RenderOptions options_;
  std::int64_t last_k_ = -1;       // last frame handed out
  std::int64_t next_job_k_ = 0;    // next frame to start rendering
  std::optional<double> stop_ms_;  // the camera stops exposing from here (none: never)
  bool delayed_ = false;
  double latency_ms_ = 0.0, jitter_ms_ = 0.0, drop_ = 0.0;
  std::uint64_t delay_seed_ = 0;
  [[nodiscard]] double unit(std::int64_t k, std::uint64_t stream) const {
    std::uint64_t z =
        delay_seed_ ^ (static_cast<std::uint64_t>(k) * 0x9E3779B97F4A7C15ULL) ^ (stream << 56);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;  // splitmix64's finaliser
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
  }
  std::unique_ptr<Worker> worker_;
};

}  // namespace omniloc::sim
