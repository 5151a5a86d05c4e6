// One drive with slip events, scored against the simulator's truth: the slip-detection tests of
// test_odometry_trajectories (the default robot) and test_odometry_wheels (every wheel layout)
// share it. An event is scored from the first window it touches; a clean window is one no event
// touches, nor the two windows after one. The "blind" odometry is the same least squares with the
// slip handling switched off (threshold at its upper bound), for the drift comparison.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "omniloc/odometry.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::sim {

/// `count` slip events on wheels 1..n_wheels at random times (1-20 s, 0.1-0.6 s long, 15-60 cm/s),
/// sorted and kept 0.5 s apart so each can be scored on its own.
inline std::vector<SlipEvent> random_slips(std::mt19937_64& rng, int n_wheels, int count) {
  std::uniform_int_distribution<int> uwheel(1, n_wheels);
  std::uniform_real_distribution<double> ustart(1.0, 20.0), udur(0.1, 0.6), uspeed(15.0, 60.0);
  std::vector<SlipEvent> slips;
  for (int k = 0; k < count; ++k)
    slips.push_back({uwheel(rng), ustart(rng), udur(rng), uspeed(rng)});
  std::sort(slips.begin(), slips.end(),
            [](const SlipEvent& a, const SlipEvent& b) { return a.start_s < b.start_s; });
  for (std::size_t k = 1; k < slips.size(); ++k)
    slips[k].start_s =
        std::max(slips[k].start_s, slips[k - 1].start_s + slips[k - 1].duration_s + 0.5);
  return slips;
}

struct SlipEventScore {
  int first_window = -1;   ///< first window the event touches; -1: the drive ended before it
  int detect_window = -1;  ///< first flagged window during the event; -1: never flagged
  int detected_wheel = 0;  ///< the wheel that flag named
  [[nodiscard]] bool seen() const { return first_window >= 0; }
  [[nodiscard]] bool in_time() const {
    return detect_window >= 0 && detect_window - first_window <= 1;
  }
};

struct SlipDriveResult {
  std::vector<SlipEventScore> events;  ///< one per cfg.slips entry
  int clean_windows = 0, false_alarms = 0;
  int bump_windows = 0, bump_flags = 0;  ///< clean windows with a wheel bump, and flags among them
  int slip_windows = 0, slip_windows_flagged_right = 0;
  double max_clean_residual = 0.0;  ///< largest LS residual / threshold in a clean window
  double distance_cm = 0.0;         ///< true path length
  double final_err_cm = 0.0, blind_final_err_cm = 0.0;
};

inline SlipDriveResult slip_drive(const RobotConfig& robot, const WorldConfig& cfg,
                                  const std::string& trajectory, std::uint64_t traj_seed) {
  World world(cfg, make_trajectory(trajectory, traj_seed));
  RobotConfig blind_robot = robot;
  blind_robot.slip_threshold_cm_per_s =
      10000.0;  // the config's upper bound: no realistic slip reaches it
  Odometry odo(robot), blind(blind_robot);
  odo.reset(world.truth());
  blind.reset(world.truth());
  SlipDriveResult r;
  r.events.resize(cfg.slips.size());
  int window_index = 0, since_slip = 100;
  SimWindow sw;
  while (!world.finished()) {
    sw = world.next_window();
    const auto& e = odo.update(sw.window);
    (void)blind.update(sw.window);
    int active = -1;  // which event (if any) touches this window
    const double t1 = sw.window.t_end_ms / 1000.0, t0 = t1 - 0.01;
    for (std::size_t k = 0; k < cfg.slips.size(); ++k)
      if (cfg.slips[k].start_s < t1 && cfg.slips[k].start_s + cfg.slips[k].duration_s > t0)
        active = static_cast<int>(k);
    if (active >= 0) {
      SlipEventScore& s = r.events[static_cast<std::size_t>(active)];
      if (s.first_window < 0) s.first_window = window_index;
      if (e.slip.detected && s.detect_window < 0) {
        s.detect_window = window_index;
        s.detected_wheel = e.slip.wheel;
      }
      ++r.slip_windows;
      r.slip_windows_flagged_right +=
          e.slip.detected && e.slip.wheel == cfg.slips[static_cast<std::size_t>(active)].wheel;
      since_slip = 0;
    } else if (++since_slip > 2) {
      ++r.clean_windows;
      r.max_clean_residual =
          std::max(r.max_clean_residual, e.slip.residual_cm_per_s / e.slip.threshold_cm_per_s);
      r.false_alarms += e.slip.detected ? 1 : 0;
      if (sw.bump_wheels) {
        ++r.bump_windows;
        r.bump_flags += e.slip.detected ? 1 : 0;
      }
    }
    ++window_index;
  }
  const auto err = [&](const Odometry& o) {
    return std::hypot(o.estimate().pose.x_cm - sw.truth.x_cm,
                      o.estimate().pose.y_cm - sw.truth.y_cm);
  };
  r.distance_cm = sw.truth_distance_cm;
  r.final_err_cm = err(odo);
  r.blind_final_err_cm = err(blind);
  return r;
}

}  // namespace omniloc::sim
