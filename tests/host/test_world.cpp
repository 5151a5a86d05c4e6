// World simulator: trajectories, ground truth, wheel counts, gyro and faults, each against an
// independent reference (hand-computed kinematics, numerical integration, finite differences).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "omniloc/conventions.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc_sim/playing_area.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::sim {
namespace {

RobotConfig robot() {
  return RobotConfig{};
}

std::array<long long, 4> total_counts(World& w) {
  std::array<long long, 4> sum{};
  while (!w.finished()) {
    const SimWindow sw = w.next_window();
    for (std::size_t i = 0; i < 4; ++i) sum[i] += sw.window.counts[i];
  }
  return sum;
}

TEST(SimTrapezoid, HandComputedProfiles) {
  const Trapezoid t = Trapezoid::make(100.0, 50.0, 100.0);
  EXPECT_DOUBLE_EQ(t.t_accel, 0.5);
  EXPECT_DOUBLE_EQ(t.t_cruise, 1.5);
  EXPECT_DOUBLE_EQ(t.duration(), 2.5);
  EXPECT_DOUBLE_EQ(t.position(0.25), 3.125);
  EXPECT_DOUBLE_EQ(t.speed(1.0), 50.0);
  EXPECT_DOUBLE_EQ(t.position(2.5), 100.0);
  EXPECT_DOUBLE_EQ(t.position(2.25), 100.0 - 3.125);
  const Trapezoid tri = Trapezoid::make(16.0, 100.0, 4.0);
  EXPECT_DOUBLE_EQ(tri.peak_speed, 8.0);
  EXPECT_DOUBLE_EQ(tri.duration(), 4.0);
  EXPECT_DOUBLE_EQ(tri.position(2.0), 8.0);
  EXPECT_THROW((void)Trapezoid::make(-1.0, 1.0, 1.0), std::invalid_argument);
}

TEST(SimTrajectory, UnknownNameListsKnownOnes) {
  try {
    (void)make_trajectory("zigzag");
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("zigzag"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("figure_eight"), std::string::npos);
  }
}

// Velocity is the derivative of position, accelerations stay bounded, the robot stays on the
// world (the border included) and the random walk inside the playing field.
// The playing areas come from the field files; the numbers here are the rules' (FIRA RoboSot
// 600 x 400 cm in a 75 cm border, RoboCup MSL 22 x 14 m in a 1 m border), written out by hand.
TEST(PlayingArea, FromTheFieldFiles) {
  const PlayingArea fira = playing_area(load_field("fira-robosot"));
  EXPECT_DOUBLE_EQ(fira.world_x_cm, 750.0);
  EXPECT_DOUBLE_EQ(fira.world_y_cm, 550.0);
  EXPECT_DOUBLE_EQ(fira.x_min_cm, 75.0);
  EXPECT_DOUBLE_EQ(fira.x_max_cm, 675.0);
  EXPECT_DOUBLE_EQ(fira.y_min_cm, 75.0);
  EXPECT_DOUBLE_EQ(fira.y_max_cm, 475.0);
  EXPECT_DOUBLE_EQ(fira_robosot_area().x_max_cm, 675.0);
  const PlayingArea msl = playing_area(load_field("robocup-msl"));
  EXPECT_DOUBLE_EQ(msl.world_x_cm, 2400.0);
  EXPECT_DOUBLE_EQ(msl.world_y_cm, 1600.0);
  EXPECT_DOUBLE_EQ(msl.x_min_cm, 100.0);
  EXPECT_DOUBLE_EQ(msl.x_max_cm, 2300.0);
  EXPECT_DOUBLE_EQ(msl.y_min_cm, 100.0);
  EXPECT_DOUBLE_EQ(msl.y_max_cm, 1500.0);
  EXPECT_DOUBLE_EQ(msl.centre_x_cm(), 1200.0);
}

// Every trajectory, on both fields: smooth (finite differences agree with the analytic
// velocities), bounded in acceleration, inside the world (the border included) and the random walk
// inside the playing field.
TEST(SimTrajectory, EveryStandardTrajectoryIsSmoothBoundedAndOnTheField) {
  const double dt = 1e-3;
  for (const std::string field : {"fira-robosot", "robocup-msl"}) {
    const PlayingArea area = playing_area(load_field(field));
    for (const std::string& name : standard_trajectory_names()) {
      SCOPED_TRACE(field + " " + name);
      const Trajectory t = make_trajectory(name, 7, area);
      EXPECT_GT(t.duration_s(), 3.0);
      double max_acc = 0.0, max_dv_err = 0.0;
      TrajectorySample prev = t.sample(0.0);
      for (double s = dt; s <= t.duration_s() + 0.1; s += dt) {
        const TrajectorySample cur = t.sample(s);
        const Eigen::Vector2d fd((cur.pose.x_cm - prev.pose.x_cm) / dt,
                                 (cur.pose.y_cm - prev.pose.y_cm) / dt);
        const Eigen::Vector2d mean_v = 0.5 * (cur.velocity_cm_per_s + prev.velocity_cm_per_s);
        max_dv_err = std::max(max_dv_err, (fd - mean_v).norm());
        EXPECT_NEAR((cur.pose.yaw_deg - prev.pose.yaw_deg) / dt,
                    0.5 * (cur.yaw_rate_deg_per_s + prev.yaw_rate_deg_per_s), 1.0);
        max_acc = std::max(max_acc, (cur.velocity_cm_per_s - prev.velocity_cm_per_s).norm() / dt);
        const double h = area.robot_half_size_cm;
        EXPECT_GE(cur.pose.x_cm, h);
        EXPECT_LE(cur.pose.x_cm, area.world_x_cm - h);
        EXPECT_GE(cur.pose.y_cm, h);
        EXPECT_LE(cur.pose.y_cm, area.world_y_cm - h);
        if (name == "random_walk") {
          EXPECT_GE(cur.pose.x_cm, area.x_min_cm + h);
          EXPECT_LE(cur.pose.y_cm, area.y_max_cm - h);
        }
        prev = cur;
      }
      EXPECT_LT(max_dv_err, 0.5);  // cm/s: finite difference vs analytic (second-order at 1 ms)
      EXPECT_LT(max_acc, 400.0);   // cm/s^2 incl. centripetal; the profiles use <= 350 tangential
      EXPECT_EQ(t.sample(t.duration_s() + 1.0).velocity_cm_per_s.norm(), 0.0);
    }
  }
}

TEST(SimTrajectory, BoundaryTourCrossesEveryLine) {
  for (const std::string field : {"fira-robosot", "robocup-msl"}) {
    SCOPED_TRACE(field);
    const PlayingArea area = playing_area(load_field(field));
    const Trajectory t = make_trajectory("boundary_tour", 1, area);
    bool left = false, right = false, bottom = false, top = false;
    for (double s = 0.0; s <= t.duration_s(); s += 0.01) {
      const Pose2 p = t.sample(s).pose;
      left = left || p.x_cm < area.x_min_cm;
      right = right || p.x_cm > area.x_max_cm;
      bottom = bottom || p.y_cm < area.y_min_cm;
      top = top || p.y_cm > area.y_max_cm;
    }
    EXPECT_TRUE(left && right && bottom && top);
  }
}

// The world's truth follows a drive on the MSL field far outside the FIRA area (the simulator used
// to know only the FIRA bounds).
TEST(SimWorld, DrivesOnTheMslField) {
  const PlayingArea msl = playing_area(load_field("robocup-msl"));
  World w(WorldConfig::default_noise(robot(), 5, msl), make_trajectory("boundary_tour", 5, msl));
  double max_x = 0.0, max_y = 0.0;
  while (!w.finished()) {
    const SimWindow sw = w.next_window();
    max_x = std::max(max_x, sw.truth.x_cm);
    max_y = std::max(max_y, sw.truth.y_cm);
  }
  EXPECT_GT(max_x, 2300.0) << "past the MSL field's right line";
  EXPECT_GT(max_y, 1500.0);
  EXPECT_LT(max_x, msl.world_x_cm);
}

// Noise-free straight drive forward by 510 cm at yaw 0: eq. (9) gives wheel travels
// (-s, -s, s, s) * 510 cm; counts are that over cm_per_count, within the encoder's phase (1 count).
TEST(SimWorld, StraightDriveCountsMatchEquation9) {
  World w(WorldConfig::noise_free(robot(), 3), make_trajectory("straight"));
  const auto sum = total_counts(w);
  const double s = std::sin(deg_to_rad(45.0));
  const double dx = w.truth().x_cm - 120.0;
  EXPECT_NEAR(dx, 510.0, 0.05);
  EXPECT_NEAR(w.truth().y_cm, 275.0, 0.05);
  const double expect = s * dx / cm_per_count(robot());
  EXPECT_NEAR(static_cast<double>(sum[0]), -expect, 1.5);
  EXPECT_NEAR(static_cast<double>(sum[1]), -expect, 1.5);
  EXPECT_NEAR(static_cast<double>(sum[2]), expect, 1.5);
  EXPECT_NEAR(static_cast<double>(sum[3]), expect, 1.5);
}

// Rotation in place by +720 then -450 degrees: every wheel travels R * 270 degrees.
TEST(SimWorld, RotationInPlaceCountsMatchEquation9) {
  World w(WorldConfig::noise_free(robot(), 5), make_trajectory("rotate_in_place"));
  const auto sum = total_counts(w);
  const double expect = 20.0 * deg_to_rad(270.0) / cm_per_count(robot());
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_NEAR(static_cast<double>(sum[i]), expect, 1.0) << "wheel " << i + 1;
  EXPECT_NEAR(w.truth().yaw_deg, 270.0, 1e-3);
  EXPECT_NEAR(w.truth().x_cm, 375.0, 1e-6);
}

TEST(SimWorld, DecodingModesScaleTheCounts) {
  std::array<std::array<long long, 4>, 3> sums{};
  const int modes[3] = {1, 2, 4};
  for (int m = 0; m < 3; ++m) {
    RobotConfig r = robot();
    r.decoding = modes[m];
    World w(WorldConfig::noise_free(r, 9), make_trajectory("figure_eight"));
    sums[static_cast<std::size_t>(m)] = total_counts(w);
  }
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(static_cast<double>(sums[1][i]) * 2.0, static_cast<double>(sums[2][i]), 4.0);
    EXPECT_NEAR(static_cast<double>(sums[0][i]) * 4.0, static_cast<double>(sums[2][i]), 8.0);
  }
}

TEST(SimWorld, NoiseFreeGyroReportsTruthWithinQuantisation) {
  World w(WorldConfig::noise_free(robot(), 2), make_trajectory("circle"));
  int windows = 0;
  while (!w.finished()) {
    const SimWindow sw = w.next_window();
    ASSERT_LE(std::abs(angle_diff_deg(sw.window.gyro_yaw_deg, sw.truth.yaw_deg)), 0.005 + 1e-9);
    ASSERT_GT(sw.window.gyro_yaw_deg, -180.0);
    ASSERT_LE(sw.window.gyro_yaw_deg, 180.0);
    ++windows;
  }
  EXPECT_EQ(windows, static_cast<int>(std::ceil(make_trajectory("circle").duration_s() / 0.01)));
}

// A stationary noisy gyro drifts by its bias: after 20 s the reported yaw is the bias times
// 20 s, within the angle random walk (0.005 * sqrt(20) = 0.022 deg, 5 sigma) and bias walk.
TEST(SimWorld, StationaryGyroDriftsByItsBias) {
  Trajectory still("still", {375.0, 275.0, 10.0});
  still.wait(20.0);
  WorldConfig cfg = WorldConfig::default_noise(robot(), 11);
  cfg.gyro.bias_sigma_deg_per_s = 0.02;
  cfg.gyro.bias_walk_deg_per_s_per_sqrt_s = 0.0;
  World w(cfg, still);
  SimWindow last;
  while (!w.finished()) last = w.next_window();
  const double expect = 10.0 + w.gyro().bias_deg_per_s() * 20.0;
  std::printf("gyro bias %.5f deg/s, yaw after 20 s %.4f deg (expect %.4f)\n",
              w.gyro().bias_deg_per_s(), last.window.gyro_yaw_deg, expect);
  EXPECT_NEAR(last.window.gyro_yaw_deg, expect, 0.12);
  EXPECT_NE(w.gyro().bias_deg_per_s(), 0.0);
  EXPECT_EQ(last.truth.yaw_deg, 10.0);
}

TEST(SimWorld, SameSeedSameRunDifferentSeedDifferentRun) {
  auto run = [](std::uint64_t seed) {
    World w(WorldConfig::default_noise(RobotConfig{}, seed), make_trajectory("random_walk", 4));
    std::vector<std::int32_t> v;
    for (int i = 0; i < 300; ++i) {
      const SimWindow sw = w.next_window();
      v.insert(v.end(), sw.window.counts.begin(), sw.window.counts.end());
    }
    return v;
  };
  EXPECT_EQ(run(21), run(21));
  EXPECT_NE(run(21), run(22));
}

// A slip of 30 cm/s on wheel 3 for 0.3 s adds 30 * 0.3 = 9 cm of travel on that wheel only.
TEST(SimWorld, SlipAddsTravelToItsWheelOnly) {
  WorldConfig clean = WorldConfig::noise_free(robot(), 4);
  WorldConfig slipping = clean;
  slipping.slips.push_back({3, 1.0, 0.3, 30.0});
  World a(clean, make_trajectory("straight"));
  World b(slipping, make_trajectory("straight"));
  std::array<long long, 4> sa{}, sb{};
  int flagged = 0;
  while (!a.finished()) {
    const SimWindow wa = a.next_window();
    const SimWindow wb = b.next_window();
    for (std::size_t i = 0; i < 4; ++i) {
      sa[i] += wa.window.counts[i];
      sb[i] += wb.window.counts[i];
    }
    if (wb.slip_wheels != 0) {
      EXPECT_EQ(wb.slip_wheels, 1u << 2);
      ++flagged;
    }
  }
  EXPECT_EQ(flagged, 30);
  EXPECT_EQ(sa[0], sb[0]);
  EXPECT_EQ(sa[1], sb[1]);
  EXPECT_EQ(sa[3], sb[3]);
  EXPECT_NEAR(static_cast<double>(sb[2] - sa[2]) * cm_per_count(robot()), 9.0, 2e-3);
}

// A wheel rolling straight across the middle of a raised-cosine bump travels
// integral (sqrt(1 + h'(x)^2) - 1) dx further; computed here by the trapezoid rule.
TEST(SimWorld, BumpLengthensTheWheelPathByItsArcLength) {
  const double radius = 15.0, height = 2.0;
  double extra = 0.0;
  const int n = 200000;
  for (int k = 0; k < n; ++k) {
    const double x = -radius + (k + 0.5) * 2.0 * radius / n;
    const double slope =
        -0.5 * height * kPi / radius * std::sin(kPi * std::abs(x) / radius) * (x < 0 ? -1.0 : 1.0);
    extra += (std::sqrt(1.0 + slope * slope) - 1.0) * 2.0 * radius / n;
  }
  WorldConfig clean = WorldConfig::noise_free(robot(), 4);
  WorldConfig bumpy = clean;
  // Wheel 4 (front right) sits at (R cos45, -R sin45) in the robot frame; on the straight drive at
  // y = 275 its contact line is y = 275 - 14.142.
  bumpy.bumps.push_back({{300.0, 275.0 - 20.0 * std::sin(deg_to_rad(45.0))}, radius, height});
  World a(clean, make_trajectory("straight"));
  World b(bumpy, make_trajectory("straight"));
  const auto sa = total_counts(a);
  const auto sb = total_counts(b);
  // The wheel's drive direction is 45 degrees off its path: it sees the extra path times sin 45.
  const double expect_counts = extra * std::sin(deg_to_rad(45.0)) / cm_per_count(robot());
  std::printf("bump: extra path %.4f cm, wheel 4 extra counts %lld (expect %.1f)\n", extra,
              sb[3] - sa[3], expect_counts);
  EXPECT_NEAR(static_cast<double>(sb[3] - sa[3]), expect_counts, 0.03 * expect_counts + 2.0);
  EXPECT_EQ(sa[0], sb[0]);
  EXPECT_EQ(sa[1], sb[1]);
}

// Carried from mid-straight (x = 375 at about 3 s) to (200, 400) facing -90: no counts for the
// jump, the gyro turns by -90, and the rest of the drive continues from there along the new
// heading.
TEST(SimWorld, KidnapMovesTheTruthButNotTheWheels) {
  WorldConfig plain = WorldConfig::noise_free(robot(), 6);
  WorldConfig carried = plain;
  carried.kidnaps.push_back({3.0, {200.0, 400.0, -90.0}});
  World a(plain, make_trajectory("straight"));
  World b(carried, make_trajectory("straight"));
  Pose2 at_kidnap_a;
  int flagged = 0;
  while (!a.finished()) {
    const SimWindow wa = a.next_window();
    const SimWindow wb = b.next_window();
    ASSERT_EQ(wa.window.counts, wb.window.counts)
        << "window " << wa.window.seq;  // same wheel motion
    if (wb.kidnapped) {
      ++flagged;
      at_kidnap_a = wa.truth;
      EXPECT_NEAR(angle_diff_deg(wb.window.gyro_yaw_deg, wa.window.gyro_yaw_deg), -90.0, 0.011);
    }
  }
  EXPECT_EQ(flagged, 1);
  // After the kidnap the robot drives the rest of the line, 630 - x(3 s), along field -y.
  const double rest = 630.0 - make_trajectory("straight").sample(3.0).pose.x_cm;
  std::printf("kidnapped at x = %.2f; ended at (%.3f, %.3f, %.3f)\n", at_kidnap_a.x_cm,
              b.truth().x_cm, b.truth().y_cm, b.truth().yaw_deg);
  EXPECT_NEAR(b.truth().x_cm, 200.0, 0.05);
  EXPECT_NEAR(b.truth().y_cm, 400.0 - rest, 0.05);
  EXPECT_NEAR(b.truth().yaw_deg, -90.0, 1e-6);
}

// Eq. (9)'s rows put wheel 1 back-left, 2 front-left, 3 back-right, 4 front-right (45 deg, R = 20).
TEST(SimWorld, WheelPositionsFollowFromEquation9) {
  const World w(WorldConfig::noise_free(robot()), make_trajectory("straight"));
  const double a = 20.0 * std::sqrt(0.5);
  const Eigen::Vector2d expect[4] = {{-a, a}, {a, a}, {-a, -a}, {a, -a}};
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR((w.wheel_position_cm(i) - expect[i]).norm(), 0.0, 1e-12) << "wheel " << i + 1;
  }
}

TEST(SimTrajectory, BadBuilderArgumentsAreRefused) {
  Trajectory t("t", {100.0, 100.0, 0.0});
  EXPECT_THROW(t.wait(-1.0), std::invalid_argument);
  EXPECT_THROW(t.figure_eight(0.0, {}), std::invalid_argument);
  EXPECT_THROW(t.line_to({200.0, 100.0}, 0.0, {0.0, 100.0, 90.0, 90.0}), std::invalid_argument);
  EXPECT_THROW(t.arc({100.0, 100.0}, 90.0, false, {}), std::invalid_argument);
}

TEST(SimWorld, BadConfigIsRefusedWithContext) {
  WorldConfig c = WorldConfig::noise_free(robot());
  c.slips.push_back({5, 0.0, 1.0, 1.0});
  EXPECT_THROW(World(c, make_trajectory("straight")), std::invalid_argument);
  WorldConfig d = WorldConfig::noise_free(robot());
  d.window_cycles = d.step_cycles - 1;
  EXPECT_THROW(World(d, make_trajectory("straight")), std::invalid_argument);
  WorldConfig e = WorldConfig::noise_free(robot());
  e.robot.decoding = 3;
  try {
    World w(e, make_trajectory("straight"));
    FAIL();
  } catch (const ConfigError& err) {
    EXPECT_NE(std::string(err.what()).find("decoding"), std::string::npos);
  }
}

}  // namespace
}  // namespace omniloc::sim
