// The drive `omniloc-sim demo` runs (sim/include/omniloc_sim/demo_drive.hpp) through the world
// simulator with the demo's events: 30 s long, the robot on the carpet all the time with its centre
// at most 10 cm outside the field lines (the world moves the reference rigidly after the
// kidnapping; keeping it on the field is the drive's job), within 10 cm of each of the four
// boundary lines at some point, one kidnapping at the stated time and place, and the wheel-2 slip
// in the stated windows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "omniloc/robot_config.hpp"
#include "omniloc_sim/demo_drive.hpp"
#include "omniloc_sim/playing_area.hpp"
#include "omniloc_sim/world.hpp"

namespace {

TEST(DemoDrive, ThirtySecondsOnTheFieldPastEveryBoundaryWithOneKidnapAndTheSlip) {
  const std::uint64_t seed = 1;  // the demo's default seed
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const auto drive = omniloc::sim::demo_drive(30.0);
  EXPECT_NEAR(drive.trajectory.duration_s(), 30.0, 1e-9);
  EXPECT_LT(drive.kidnap_s, 25.0) << "leave the demo at least 5 s to show the recovery";
  EXPECT_GT(drive.kidnap_s, drive.slip_s + 1.0);

  const auto robot = omniloc::load_named_robot_config("default");
  auto wc = omniloc::sim::WorldConfig::default_noise(robot, seed);
  wc.slips.push_back(omniloc::sim::SlipEvent{2, drive.slip_s, 0.5, 40.0});
  wc.kidnaps.push_back(omniloc::sim::KidnapEvent{drive.kidnap_s, drive.kidnap_to});
  omniloc::sim::World world(wc, drive.trajectory);
  const auto& f = omniloc::sim::fira_robosot_area();

  double min_left = 1e9, min_right = 1e9, min_bottom = 1e9, min_top = 1e9;
  int kidnapped_windows = 0, slip_windows = 0;
  double kidnap_window_s = -1.0, slip_first_s = -1.0, slip_last_s = -1.0;
  omniloc::Pose2 before_kidnap, after_kidnap;
  omniloc::Pose2 prev = drive.trajectory.start();
  int windows = 0;
  while (world.time_s() < 30.0 - 1e-9) {
    const auto w = world.next_window();
    ++windows;
    const double t = w.window.t_end_ms / 1000.0;
    const auto& p = w.truth;
    ASSERT_GE(p.x_cm, f.x_min_cm - 10.0) << "t=" << t;
    ASSERT_LE(p.x_cm, f.x_max_cm + 10.0) << "t=" << t;
    ASSERT_GE(p.y_cm, f.y_min_cm - 10.0) << "t=" << t;
    ASSERT_LE(p.y_cm, f.y_max_cm + 10.0) << "t=" << t;
    min_left = std::min(min_left, p.x_cm - f.x_min_cm);
    min_right = std::min(min_right, f.x_max_cm - p.x_cm);
    min_bottom = std::min(min_bottom, p.y_cm - f.y_min_cm);
    min_top = std::min(min_top, f.y_max_cm - p.y_cm);
    if (w.kidnapped) {
      ++kidnapped_windows;
      kidnap_window_s = t;
      before_kidnap = prev;
      after_kidnap = p;
    }
    if (w.slip_wheels & 0x2) {
      ++slip_windows;
      if (slip_first_s < 0) slip_first_s = t;
      slip_last_s = t;
    }
    EXPECT_EQ(w.slip_wheels & ~0x2, 0) << "only wheel 2 slips, t=" << t;
    prev = p;
  }
  EXPECT_EQ(windows, 3000);
  std::printf("closest to the lines: left %.1f right %.1f bottom %.1f top %.1f cm\n", min_left,
              min_right, min_bottom, min_top);
  EXPECT_LE(min_left, 10.0);
  EXPECT_LE(min_right, 10.0);
  EXPECT_LE(min_bottom, 10.0);
  EXPECT_LE(min_top, 10.0);

  EXPECT_EQ(kidnapped_windows, 1);
  EXPECT_NEAR(kidnap_window_s, drive.kidnap_s, 0.01);
  // Carried from where the reference stood still, (450, 220), to the stated pose.
  EXPECT_NEAR(std::hypot(before_kidnap.x_cm - 450.0, before_kidnap.y_cm - 220.0), 0.0, 2.0);
  EXPECT_NEAR(after_kidnap.x_cm, drive.kidnap_to.x_cm, 1.0);
  EXPECT_NEAR(after_kidnap.y_cm, drive.kidnap_to.y_cm, 1.0);
  EXPECT_NEAR(omniloc::angle_diff_deg(after_kidnap.yaw_deg, drive.kidnap_to.yaw_deg), 0.0, 1.0);

  // 0.5 s of slip = 50 windows (the first and last may be partial).
  EXPECT_GE(slip_windows, 50);
  EXPECT_LE(slip_windows, 51);
  EXPECT_NEAR(slip_first_s, drive.slip_s + 0.01, 0.011);
  EXPECT_NEAR(slip_last_s, drive.slip_s + 0.5, 0.011);
}

}  // namespace
