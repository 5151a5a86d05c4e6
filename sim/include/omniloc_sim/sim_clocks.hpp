// Realistic clocks for the simulator (issue 18): the board's crystal runs off the host's clock by a
// few tens of ppm, a window reaches the host after a USB latency that jitters (exponential, capped)
// and now and then grows in a late burst, and a camera frame is handed over a latency after it was
// exposed (fixed plus jitter), some frames lost. The host clock is the simulation's truth clock;
// board time = host time * (1 + board_drift_ppm * 1e-6) + board_start_ms. Header-only, seeded: the
// same seed gives the same delays. Defaults: SimClockConfig::realistic(); perfect() is every clock
// equal and no delay (what the simulator had before).
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>

namespace omniloc::sim {

struct SimClockConfig {
  double board_drift_ppm = 0.0;  ///< board crystal against the host clock (+: the board runs fast)
  double usb_jitter_mean_ms = 0.0;    ///< exponential USB latency of a window, mean ...
  double usb_jitter_max_ms = 0.0;     ///< ... capped here
  double burst_every_s = 0.0;         ///< mean time between late bursts (0: none)
  double burst_extra_ms = 0.0;        ///< a burst delays every window in it by this much
  double burst_length_ms = 0.0;       ///< how long a burst lasts
  double camera_latency_ms = 0.0;     ///< exposure to hand-over, fixed part ...
  double camera_jitter_ms = 0.0;      ///< ... plus uniform 0 .. this
  double camera_drop_fraction = 0.0;  ///< frames lost in the driver

  /// All clocks equal, no latency, no drops (the simulator before issue 18).
  [[nodiscard]] static SimClockConfig perfect() { return {}; }
  /// A 50 ppm crystal, USB latency exponential with mean 0.5 ms capped at 2 ms, a 20 ms burst of
  /// 100 ms every 7 s on average, the camera 29 + 0..8 ms late (mean 33 ms:
  /// the daemon's default camera_latency_ms, two 60 Hz periods), 2 % dropped.
  [[nodiscard]] static SimClockConfig realistic() {
    SimClockConfig c;
    c.board_drift_ppm = 50.0;
    c.usb_jitter_mean_ms = 0.5;
    c.usb_jitter_max_ms = 2.0;
    c.burst_every_s = 7.0;
    c.burst_extra_ms = 20.0;
    c.burst_length_ms = 100.0;
    c.camera_latency_ms = 29.0;
    c.camera_jitter_ms = 8.0;
    c.camera_drop_fraction = 0.02;
    return c;
  }
  [[nodiscard]] bool is_perfect() const {
    return board_drift_ppm == 0.0 && usb_jitter_mean_ms == 0.0 && burst_every_s == 0.0 &&
           camera_latency_ms == 0.0 && camera_jitter_ms == 0.0 && camera_drop_fraction == 0.0;
  }
};

/// Board time <-> host (truth) time for one board run.
struct BoardCrystal {
  double drift_ppm = 0.0;
  double board_start_ms = 0.0;  ///< board time at host time 0
  [[nodiscard]] double board_ms(double host_ms) const {
    return host_ms * (1.0 + drift_ppm * 1e-6) + board_start_ms;
  }
  [[nodiscard]] double host_ms(double board_ms) const {
    return (board_ms - board_start_ms) / (1.0 + drift_ppm * 1e-6);
  }
};

/// When each window arrives on the host: its host end time plus the latency. Calls must come in
/// time order; arrivals never go back (a USB pipe keeps the order).
class UsbArrivals {
 public:
  UsbArrivals(const SimClockConfig& c, std::uint64_t seed) : c_(c), rng_(seed) {
    schedule_burst(0.0);
  }
  [[nodiscard]] double arrival_ms(double host_end_ms) {
    double lat = 0.0;
    if (c_.usb_jitter_mean_ms > 0.0) {
      std::exponential_distribution<double> e(1.0 / c_.usb_jitter_mean_ms);
      lat = std::min(e(rng_), c_.usb_jitter_max_ms);
    }
    if (c_.burst_every_s > 0.0) {
      while (host_end_ms >= burst_start_ms_ + c_.burst_length_ms)
        schedule_burst(burst_start_ms_ + c_.burst_length_ms);
      if (host_end_ms >= burst_start_ms_)
        lat += c_.burst_extra_ms;  // the host or the bridge stalled
    }
    // Arrivals keep their order (a later window never overtakes an earlier one).
    last_ = std::max(last_.value_or(host_end_ms + lat), host_end_ms + lat);
    return *last_;
  }

 private:
  void schedule_burst(double after_ms) {
    std::exponential_distribution<double> e(1.0 / (c_.burst_every_s * 1000.0));
    burst_start_ms_ = c_.burst_every_s > 0.0 ? after_ms + e(rng_) : kNever;
  }
  SimClockConfig c_;
  std::mt19937_64 rng_;
  static constexpr double kNever = std::numeric_limits<double>::infinity();
  double burst_start_ms_ = kNever;
  std::optional<double> last_;  // the last arrival handed out (none yet)
};

/// A camera's hand-over latency and drops.
class CameraDelays {
 public:
  CameraDelays(const SimClockConfig& c, std::uint64_t seed) : c_(c), rng_(seed) {}
  /// The host time a frame exposed at exposure_ms is handed over.
  [[nodiscard]] double handover_ms(double exposure_ms) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    return exposure_ms + c_.camera_latency_ms + c_.camera_jitter_ms * u(rng_);
  }
  [[nodiscard]] bool dropped() {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    return c_.camera_drop_fraction > 0.0 && u(rng_) < c_.camera_drop_fraction;
  }

 private:
  SimClockConfig c_;
  std::mt19937_64 rng_;
};

}  // namespace omniloc::sim
