// Odometry over every simulated trajectory, against the simulator's ground truth: drift of the
// correct variant (asserted), the paper variant's error (measured and printed), and slip detection
// and false-alarm rates. The tables printed here are the figures quoted in docs/ODOMETRY.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "omniloc/odometry.hpp"
#include "omniloc_sim/world.hpp"
#include "slip_drive.hpp"

namespace omniloc::sim {
namespace {

struct RunResult {
  double distance_cm = 0.0;
  double final_err_cm = 0.0;
  double max_err_cm = 0.0;
  double final_yaw_err_deg = 0.0;
  double paper_final_err_cm = 0.0;
  double paper_max_err_cm = 0.0;
  double paper_literal_max_err_cm = 0.0;
  double final_sigma_cm = 0.0;
  int slip_flags = 0;
};

RunResult run(const WorldConfig& cfg, const std::string& trajectory, std::uint64_t traj_seed) {
  World world(cfg, make_trajectory(trajectory, traj_seed));
  Odometry odo(cfg.robot);
  PaperOdometry paper(cfg.robot);
  PaperOdometry literal(cfg.robot, PaperHeading::kGyroDifference);
  const Pose2 start = world.truth();
  odo.reset(start);
  paper.reset(start);
  literal.reset(start);
  RunResult r;
  SimWindow sw;
  while (!world.finished()) {
    sw = world.next_window();
    const auto& e = odo.update(sw.window);
    const auto& p = paper.update(sw.window);
    const auto& l = literal.update(sw.window);
    const auto err = [&](const OdometryEstimate& x) {
      return std::hypot(x.pose.x_cm - sw.truth.x_cm, x.pose.y_cm - sw.truth.y_cm);
    };
    r.max_err_cm = std::max(r.max_err_cm, err(e));
    r.paper_max_err_cm = std::max(r.paper_max_err_cm, err(p));
    r.paper_literal_max_err_cm = std::max(r.paper_literal_max_err_cm, err(l));
    r.slip_flags += e.slip.detected ? 1 : 0;
  }
  const auto err = [&](const OdometryEstimate& e) {
    return std::hypot(e.pose.x_cm - sw.truth.x_cm, e.pose.y_cm - sw.truth.y_cm);
  };
  r.distance_cm = sw.truth_distance_cm;
  r.final_err_cm = err(odo.estimate());
  r.final_yaw_err_deg = angle_diff_deg(odo.estimate().pose.yaw_deg, sw.truth.yaw_deg);
  r.paper_final_err_cm = err(paper.estimate());
  r.final_sigma_cm = odo.estimate().sigma_xy_cm;
  return r;
}

double pct(double err, double dist) {
  return dist > 1.0 ? 100.0 * err / dist : 0.0;
}

TEST(OdometryTrajectories, DriftTableNoiseFreeAndDefaultNoise) {
  const RobotConfig robot = load_named_robot_config("default");
  // final: error at the end / distance; max: largest error during the run / distance. Closed
  // trajectories (circle, figure eight, tours) come back to the start, where even a variant that
  // never moves has no final error: the max column is the honest one.
  std::printf("\n%-16s %-8s %8s | %8s %8s %7s %8s | %9s %9s | %9s\n", "trajectory", "noise",
              "dist_cm", "final_%", "max_%", "yaw_deg", "sigma_cm", "paper_fin%", "paper_max%",
              "literal_max%");
  const int kNoisySeeds = 5;
  for (const std::string& name : standard_trajectory_names()) {
    for (int noisy = 0; noisy <= 1; ++noisy) {
      double worst_pct = 0.0, worst_err = 0.0, sum_pct = 0.0, sum_paper_pct = 0.0;
      const int seeds = noisy ? kNoisySeeds : 1;
      for (int s = 1; s <= seeds; ++s) {
        const std::uint64_t seed = 1000 + static_cast<std::uint64_t>(s);
        const WorldConfig cfg =
            noisy ? WorldConfig::default_noise(robot, seed) : WorldConfig::noise_free(robot, seed);
        const RunResult r = run(cfg, name, 1);
        std::printf(
            "%-16s %-8s %8.1f | %8.3f %8.3f %7.3f %8.2f | %9.2f %9.2f | %9.2f   (seed %llu; max "
            "err %.3f cm, paper %.1f cm)\n",
            name.c_str(), noisy ? "default" : "none", r.distance_cm,
            pct(r.final_err_cm, r.distance_cm), pct(r.max_err_cm, r.distance_cm),
            r.final_yaw_err_deg, r.final_sigma_cm, pct(r.paper_final_err_cm, r.distance_cm),
            pct(r.paper_max_err_cm, r.distance_cm), pct(r.paper_literal_max_err_cm, r.distance_cm),
            static_cast<unsigned long long>(seed), r.max_err_cm, r.paper_max_err_cm);
        worst_pct = std::max(worst_pct, pct(r.max_err_cm, r.distance_cm));
        worst_err = std::max(worst_err, r.max_err_cm);
        sum_pct += pct(r.max_err_cm, r.distance_cm);
        sum_paper_pct += pct(r.paper_max_err_cm, r.distance_cm);
        EXPECT_EQ(r.slip_flags, 0)
            << name << (noisy ? " noisy" : " noise-free") << " seed " << seed;
        // The uncertainty must cover the error (3 sigma).
        EXPECT_LE(r.final_err_cm, 3.0 * r.final_sigma_cm + 0.05) << name;
      }
      if (name == "rotate_in_place") {
        // Hardly any distance: the centre must stay put within a few mm.
        EXPECT_LT(worst_err, noisy ? 1.0 : 0.05) << name;
      } else {
        EXPECT_LT(worst_pct, noisy ? 2.0 : 0.5) << name;
      }
      if (noisy)
        std::printf(
            "%-16s %-8s mean max-error drift %.3f %% over %d seeds; paper variant %.1f %%\n",
            name.c_str(), "default", sum_pct / seeds, seeds, sum_paper_pct / seeds);
    }
  }
}

// Slip events on random wheels at random times during random walks and boundary tours with the
// default noise. Detected = flagged on the slipping wheel within two windows of the first window
// the slip touches. False alarm = a flag in a window no slip touched (nor the two windows after
// one).
TEST(OdometryTrajectories, SlipDetectionAndFalseAlarmRates) {
  const RobotConfig robot = load_named_robot_config("default");
  const std::uint64_t seed = 20261122;
  std::printf("slip test seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  int events = 0, detected = 0, right_wheel_first = 0, clean_windows = 0, false_alarms = 0;
  int bump_windows = 0, bump_flags = 0, slip_windows = 0, slip_windows_flagged_right = 0;
  double worst_pct_with_slip = 0.0, worst_pct_blind = 0.0, max_clean_residual = 0.0;
  for (int run_i = 0; run_i < 24; ++run_i) {
    WorldConfig cfg = WorldConfig::default_noise(robot, seed + static_cast<std::uint64_t>(run_i));
    cfg.slips = random_slips(rng, 4, 3);
    const std::string traj = run_i % 2 ? "boundary_tour" : "random_walk";
    const SlipDriveResult r = slip_drive(robot, cfg, traj, static_cast<std::uint64_t>(run_i) + 1);
    clean_windows += r.clean_windows;
    false_alarms += r.false_alarms;
    bump_windows += r.bump_windows;
    bump_flags += r.bump_flags;
    slip_windows += r.slip_windows;
    slip_windows_flagged_right += r.slip_windows_flagged_right;
    max_clean_residual = std::max(max_clean_residual, r.max_clean_residual);
    for (std::size_t k = 0; k < cfg.slips.size(); ++k) {
      const SlipEventScore& e = r.events[k];
      if (!e.seen()) continue;  // trajectory ended before the event
      ++events;
      const bool right_wheel = e.detected_wheel == cfg.slips[k].wheel;
      if (e.in_time() && right_wheel) ++detected;
      if (right_wheel) ++right_wheel_first;
      if (!(e.in_time() && right_wheel))
        std::printf(
            "  missed: run %d %s wheel %d at %.2f s for %.2f s, %.1f cm/s: first flag window %+d "
            "wheel %d\n",
            run_i, traj.c_str(), cfg.slips[k].wheel, cfg.slips[k].start_s, cfg.slips[k].duration_s,
            cfg.slips[k].extra_speed_cm_per_s, e.detect_window - e.first_window, e.detected_wheel);
    }
    worst_pct_with_slip = std::max(worst_pct_with_slip, pct(r.final_err_cm, r.distance_cm));
    worst_pct_blind = std::max(worst_pct_blind, pct(r.blind_final_err_cm, r.distance_cm));
  }
  const double det_rate = static_cast<double>(detected) / events;
  const double fa_rate = static_cast<double>(false_alarms) / clean_windows;
  std::printf(
      "slip events %d: detected on the right wheel within two windows %d (%.1f %%); first flag on "
      "the right wheel %d\n",
      events, detected, 100.0 * det_rate, right_wheel_first);
  std::printf("slip windows %d, flagged on the right wheel %d (%.1f %%)\n", slip_windows,
              slip_windows_flagged_right, 100.0 * slip_windows_flagged_right / slip_windows);
  std::printf("false alarms: %d of %d clean windows (%.3f %%); of which on bump windows %d of %d\n",
              false_alarms, clean_windows, 100.0 * fa_rate, bump_flags, bump_windows);
  std::printf("largest LS residual / threshold in a clean window: %.3f\n", max_clean_residual);
  std::printf("worst final drift with slip events: %.3f %% with rejection, %.3f %% without\n",
              worst_pct_with_slip, worst_pct_blind);
  EXPECT_GE(events, 60);
  EXPECT_GE(det_rate, 0.95);
  EXPECT_LE(fa_rate, 0.001);
  EXPECT_LT(worst_pct_with_slip, 2.0);
}

}  // namespace
}  // namespace omniloc::sim

namespace omniloc::sim {
namespace {

// The integration algorithm resets the origin every 125 ms; here to the truth itself, on a noisy
// random walk: between resets the error stays at the size of 125 ms of drift, and the heading is
// re-anchored although the gyro has drifted since start-up.
TEST(OdometryTrajectories, OriginResetEvery125ms) {
  const RobotConfig robot;
  WorldConfig cfg = WorldConfig::default_noise(robot, 77);
  cfg.gyro.bias_offset_deg_per_s = 0.2;  // a badly calibrated gyro: 5 deg off after 25 s
  World world(cfg, make_trajectory("random_walk", 77));
  Odometry odo(robot);
  odo.reset(world.truth());
  double worst = 0.0, worst_yaw = 0.0, free_yaw_err = 0.0;
  int resets = 0;
  while (!world.finished()) {
    const SimWindow sw = world.next_window();
    const auto& e = odo.update(sw.window);
    worst = std::max(worst, std::hypot(e.pose.x_cm - sw.truth.x_cm, e.pose.y_cm - sw.truth.y_cm));
    worst_yaw = std::max(worst_yaw, std::abs(angle_diff_deg(e.pose.yaw_deg, sw.truth.yaw_deg)));
    free_yaw_err = std::abs(angle_diff_deg(sw.window.gyro_yaw_deg, sw.truth.yaw_deg));
    if (std::floor(sw.window.t_end_ms / 125.0) > resets) {
      ++resets;
      odo.reset(sw.truth, 1.0, 0.2);
      EXPECT_DOUBLE_EQ(odo.estimate().sigma_xy_cm, 1.0);
    }
  }
  std::printf(
      "%d resets every 125 ms: worst error %.3f cm, worst yaw error %.3f deg (raw gyro off by %.2f "
      "deg at the end)\n",
      resets, worst, worst_yaw, free_yaw_err);
  EXPECT_GT(resets, 190);
  EXPECT_GT(free_yaw_err, 1.0);
  EXPECT_LT(worst, 0.5);
  EXPECT_LT(worst_yaw, 0.1);
}

// The wheel-only heading (cross-check) follows the truth when nothing is wrong, and exposes a gyro
// scale error when there is one.
TEST(OdometryTrajectories, WheelYawCrossChecksTheGyro) {
  const RobotConfig robot;
  for (double scale : {0.0, 0.01}) {
    WorldConfig cfg = WorldConfig::noise_free(robot, 3);
    World world(cfg, make_trajectory("circle"));
    Odometry odo(robot);
    odo.reset(world.truth());
    SimWindow sw;
    double gyro_yaw = world.truth().yaw_deg;
    double last_reported = gyro_yaw;
    while (!world.finished()) {
      sw = world.next_window();
      // Apply a scale error to the reported gyro increments.
      EncoderWindow w = sw.window;
      gyro_yaw += angle_diff_deg(sw.window.gyro_yaw_deg, last_reported) * (1.0 + scale);
      last_reported = sw.window.gyro_yaw_deg;
      w.gyro_yaw_deg = wrap_deg(gyro_yaw);
      (void)odo.update(w);
    }
    const double wheel_err = angle_diff_deg(odo.estimate().wheel_yaw_deg, sw.truth.yaw_deg);
    const double gyro_err = angle_diff_deg(odo.estimate().pose.yaw_deg, sw.truth.yaw_deg);
    std::printf(
        "gyro scale error %.2f: after 720 deg the gyro heading is off by %.3f deg, the wheel "
        "heading by %.3f deg\n",
        scale, gyro_err, wheel_err);
    EXPECT_NEAR(wheel_err, 0.0, 0.02);
    EXPECT_NEAR(gyro_err, 720.0 * scale, 0.02);
  }
}

// Windows of 8 ms on a 39.75 MHz clock (the iCE40 PLL's nearest to 40 MHz): the correct variant
// takes time from the timestamps; the paper variant's eq. (10) keeps T = 10 ms and 0.01.
TEST(OdometryTrajectories, OtherWindowPeriodAndClock) {
  const RobotConfig robot;
  auto sim_config = WorldConfig::noise_free(robot, 8);
  sim_config.set_clock(39.75e6, 8.0);  // the host believes the register map's 10 ms
  const RobotConfig& host_robot = robot;
  World world(sim_config, make_trajectory("random_walk", 8));
  EXPECT_EQ(world.config().window_cycles, 318'000);
  Odometry odo(host_robot);
  PaperOdometry paper(host_robot);
  odo.reset(world.truth());
  paper.reset(world.truth());
  SimWindow sw;
  double worst = 0.0, paper_worst = 0.0;
  while (!world.finished()) {
    sw = world.next_window();
    const auto& e = odo.update(sw.window);
    const auto& p = paper.update(sw.window);
    worst = std::max(worst, std::hypot(e.pose.x_cm - sw.truth.x_cm, e.pose.y_cm - sw.truth.y_cm));
    paper_worst =
        std::max(paper_worst, std::hypot(p.pose.x_cm - sw.truth.x_cm, p.pose.y_cm - sw.truth.y_cm));
    ASSERT_NEAR(sw.window.t_end_ms, 8.0 * (sw.window.seq + 1), 1e-9);
  }
  std::printf(
      "8 ms windows at 39.75 MHz over %.0f cm: worst error %.3f cm (paper variant %.1f cm)\n",
      sw.truth_distance_cm, worst, paper_worst);
  EXPECT_LT(worst, 0.005 * sw.truth_distance_cm);
  EXPECT_NEAR(odo.estimate().speed_cm_per_s, 0.0, 1e-9);
}

}  // namespace
}  // namespace omniloc::sim

namespace omniloc::sim {
namespace {

// X1 and X2 decoding: a quarter and a half of the resolution (X4 beside them), still far inside
// the drift bound: window counts are differences of floors of one position, so quantisation does
// not accumulate.
TEST(OdometryTrajectories, CoarserDecodingModes) {
  for (int decoding : {1, 2, 4}) {
    RobotConfig robot;
    robot.decoding = decoding;
    World world(WorldConfig::noise_free(robot, 12), make_trajectory("random_walk", 12));
    Odometry odo(robot);
    odo.reset(world.truth());
    SimWindow sw;
    double worst = 0.0;
    int flags = 0;
    while (!world.finished()) {
      sw = world.next_window();
      const auto& e = odo.update(sw.window);
      flags += e.slip.detected;
      worst = std::max(worst, std::hypot(e.pose.x_cm - sw.truth.x_cm, e.pose.y_cm - sw.truth.y_cm));
    }
    std::printf("decoding X%d: worst error %.3f cm over %.0f cm\n", decoding, worst,
                sw.truth_distance_cm);
    EXPECT_LT(worst, 0.005 * sw.truth_distance_cm);
    EXPECT_EQ(flags, 0);
  }
}

}  // namespace
}  // namespace omniloc::sim

namespace omniloc::sim {
namespace {

// How small a slip is still caught: detection (right wheel within two windows) against the extra
// wheel speed, 16 events per speed on random walks with the default noise. Printed, and asserted
// only well above the threshold (a slip of e leaves a residual of e / sqrt(2); the threshold is
// 5 cm/s, raised to 6 sigma of the wheel noise at speed: about 7 cm/s at 1.3 m/s wheel speed).
TEST(OdometryTrajectories, SlipDetectionVersusMagnitude) {
  const RobotConfig robot;
  const std::uint64_t seed = 99;
  std::printf("slip sweep seed %llu\n", static_cast<unsigned long long>(seed));
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> uwheel(1, 4);
  std::uniform_real_distribution<double> ustart(1.0, 8.0);
  for (double speed : {3.0, 5.0, 7.5, 10.0, 15.0}) {
    int events = 0, caught = 0;
    for (int k = 0; k < 16; ++k) {
      WorldConfig cfg = WorldConfig::default_noise(robot, seed + static_cast<std::uint64_t>(k));
      const SlipEvent ev{uwheel(rng), ustart(rng), 0.3, speed};
      cfg.slips.push_back(ev);
      World world(cfg, make_trajectory("random_walk", static_cast<std::uint64_t>(k) + 40));
      Odometry odo(robot);
      odo.reset(world.truth());
      int first = -1, index = 0;
      bool ok = false;
      while (!world.finished() && (first < 0 || index <= first + 2)) {
        const SimWindow sw = world.next_window();
        const auto& e = odo.update(sw.window);
        if (sw.slip_wheels && first < 0) {
          first = index;
        }
        if (first >= 0 && index - first <= 1 && e.slip.detected && e.slip.wheel == ev.wheel)
          ok = true;
        ++index;
      }
      if (first < 0) continue;
      ++events;
      caught += ok;
    }
    std::printf("extra wheel speed %5.1f cm/s: caught %2d of %2d within two windows\n", speed,
                caught, events);
    if (speed >= 15.0) {
      EXPECT_EQ(caught, events);
    }
  }
}

}  // namespace
}  // namespace omniloc::sim
