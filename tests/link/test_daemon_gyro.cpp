// Issue 35, item 1: the heading of the robot's daemon comes from the gyro on the board, end to end:
// the world's true yaw rate -> the ICM-42688-P model on the Verilated board's SPI pins ->
// rtl/gyro/gyro_ctrl.v summing its samples per window -> the window bank -> TELEMETRY bytes ->
// BoardSession -> GyroHeading -> the daemon's windows and datagrams. Judged against the simulator's
// truth (the yaw the robot really turned), and against the board with no gyro fitted (WHO_AM_I
// reads the pull-up's 0xFF): the status says the gyro is missing and the wheels hold the heading.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "omniloc/conventions.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc_sim/sim_daemon.hpp"

namespace omniloc {
namespace {

const daemon::DaemonModels& models() {
  static const daemon::DaemonModels m = [] {
    daemon::DaemonModels out = daemon::load_models(daemon::DaemonConfig{});
    return out;
  }();
  return m;
}

struct GyroRun {
  std::vector<EncoderWindow> windows;  // as the daemon took them, with their heading
  std::vector<Pose2> truth;            // the simulator's pose at each window's end
  std::vector<std::string> status_lines;
  std::string datagram;                        // one datagram from the middle of the run
  std::string describe;                        // the heading source at the end
  double worst_published_yaw_error_deg = 0.0;  // the datagrams' yaw against truth (field frame)
  GyroState state = GyroState::kNoGyro;
};

/// Drives the daemon for `seconds` of simulated time on `trajectory` (no camera: the heading is
/// what the windows give), the gyro part answering WHO_AM_I with `who_am_i`.
GyroRun drive(const char* trajectory, std::uint64_t seed, double seconds, std::uint8_t who_am_i,
              std::vector<sim::SlipEvent> slips = {}) {
  std::printf("trajectory %s, seed %llu, WHO_AM_I 0x%02X, %zu wheel slips\n", trajectory,
              static_cast<unsigned long long>(seed), who_am_i, slips.size());
  sim::SimRobotOptions ro;
  ro.seed = seed;
  ro.slips = std::move(slips);
  ro.camera = false;
  ro.clocks = sim::SimClockConfig::perfect();
  daemon::DaemonModels mod = models();
  const sim::Trajectory traj = sim::make_trajectory(trajectory, seed);
  mod.initial_pose = traj.start();
  sim::SimulatedRobot robot(mod, traj, ro);
  robot.gyro().faults().who_am_i = who_am_i;
  daemon::DaemonIo io = robot.io();
  GyroRun run;
  io.observer.on_window = [&](const EncoderWindow& w) {
    run.windows.push_back(w);
    const auto t = robot.truth().truth(w.t_end_ms);
    run.truth.push_back(t ? *t : Pose2{});
  };
  io.observer.on_pose = [&](const daemon::PoseEvent& e) {
    if (run.windows.size() == 150) run.datagram = daemon::pose_json(e.message);
    if (const auto t = robot.truth().truth(e.message.t_ms))
      run.worst_published_yaw_error_deg =
          std::max(run.worst_published_yaw_error_deg,
                   std::fabs(angle_diff_deg(e.message.yaw_deg, t->yaw_deg)));
  };
  io.observer.on_status = [&](const std::string& line) { run.status_lines.push_back(line); };
  io.logger = Logger(LogLevel::kWarning, [](LogLevel, std::string_view) {});
  daemon::DaemonConfig cfg;
  cfg.udp_address = "127.0.0.1";
  cfg.udp_port = 9;  // discard
  cfg.duration_s = seconds;
  cfg.status_period_s = 0.5;
  daemon::Daemon d(cfg, mod, io);
  volatile std::sig_atomic_t stop = 0;
  (void)d.run(&stop);
  run.describe = robot.heading().describe();
  run.state = robot.heading().state();
  return run;
}

/// The largest difference between a heading's turn since window `from` and the truth's.
double worst_turn_error_deg(const GyroRun& run, const std::vector<double>& heading_deg,
                            std::size_t from) {
  double worst = 0.0;
  for (std::size_t i = from; i < run.windows.size(); ++i) {
    const double measured = angle_diff_deg(heading_deg[i], heading_deg[from]);
    const double truth = angle_diff_deg(run.truth[i].yaw_deg, run.truth[from].yaw_deg);
    worst = std::max(worst, std::fabs(angle_diff_deg(measured, truth)));
  }
  return worst;
}

/// The heading the daemon used, window by window.
std::vector<double> daemon_heading(const GyroRun& run) {
  std::vector<double> out;
  for (const auto& w : run.windows) out.push_back(w.gyro_yaw_deg);
  return out;
}

/// The heading the wheels alone give over the same windows (WheelYawHeading: eq. (9)'s rotation).
std::vector<double> wheel_heading(const GyroRun& run) {
  WheelYawHeading wheels(models().robot);
  std::vector<double> out;
  for (const auto& w : run.windows) out.push_back(wheels.gyro_yaw_deg(w));
  return out;
}

TEST(DaemonGyro, HeadingComesFromTheBoardsGyroWindowsEndToEnd) {
  // Wheel 2 slips for half a second (40 cm/s more than the ground): the wheels' rotation takes the
  // slip for a turn, the gyro does not.
  const GyroRun run = drive("figure_eight", 11, 3.0, 0x47, {sim::SlipEvent{2, 1.0, 0.5, 40.0}});
  ASSERT_GE(run.windows.size(), 290u);
  // The gyro starts 31 ms after the board's reset (soft reset 1 ms, power 0.2 ms, start-up 30 ms):
  // the first windows carry NOT_RUNNING and no sample, every later one ten 1 kHz samples.
  std::size_t first_running = run.windows.size();
  for (std::size_t i = 0; i < run.windows.size(); ++i)
    if (run.windows[i].gyro.flags == 0 && run.windows[i].gyro.samples > 0) {
      first_running = i;
      break;
    }
  ASSERT_LT(first_running, 10u) << "the gyro never ran";
  EXPECT_TRUE((run.windows[0].gyro.flags >> regmap::kGyroFlagNotRunning) & 1u);
  int flagged_later = 0;
  std::uint64_t samples = 0;
  for (std::size_t i = first_running; i < run.windows.size(); ++i) {
    const WindowGyro& g = run.windows[i].gyro;
    ASSERT_TRUE(g.present);
    flagged_later += g.flags != 0;
    EXPECT_GE(g.samples, 9u) << "window " << i;
    EXPECT_LE(g.samples, 11u) << "window " << i;
    samples += g.samples;
  }
  EXPECT_EQ(flagged_later, 0);
  // What the heading turned against what the robot turned (the circle turns ~40 deg a second):
  // the gyro's scale error (0.2 % sigma) and noise, nothing else; the wheels' own rotation over the
  // same windows carries the slip.
  const double worst = worst_turn_error_deg(run, daemon_heading(run), first_running + 10);
  const double wheels = worst_turn_error_deg(run, wheel_heading(run), first_running + 10);
  const double turned =
      std::fabs(angle_diff_deg(run.truth.back().yaw_deg, run.truth[first_running + 10].yaw_deg));
  std::printf(
      "%zu windows, %llu gyro samples; the robot turned %.1f deg net; worst heading error: the "
      "daemon's "
      "(gyro) %.3f deg, the wheels' alone %.3f deg\n",
      run.windows.size(), static_cast<unsigned long long>(samples), turned, worst, wheels);
  EXPECT_LT(worst, 1.0);
  EXPECT_GT(wheels, 3.0 * worst) << "the slip should fool the wheels, not the gyro";
  // The published yaw is the field's: the start pose aligned the relative gyro (no camera here).
  std::printf("worst published yaw error against truth %.3f deg\n",
              run.worst_published_yaw_error_deg);
  EXPECT_LT(run.worst_published_yaw_error_deg, 1.0);
  EXPECT_TRUE(run.state == GyroState::kLearningBias || run.state == GyroState::kRunning)
      << run.describe;
  bool said_gyro = false;
  for (const auto& line : run.status_lines)
    said_gyro |= line.find("heading=gyro") != std::string::npos;
  EXPECT_TRUE(said_gyro) << "no status line said heading=gyro";
  std::printf("a datagram as sent: %s\n", run.datagram.c_str());
  EXPECT_FALSE(run.datagram.empty());
}

TEST(DaemonGyro, NoGyroOnTheBoardIsReportedAndTheWheelsHoldTheHeading) {
  const GyroRun run = drive("circle", 11, 2.0, 0xFF);  // the PMOD's pull-up: nothing answers
  ASSERT_GE(run.windows.size(), 190u);
  int absent = 0;
  for (std::size_t i = 20; i < run.windows.size(); ++i) {
    const WindowGyro& g = run.windows[i].gyro;
    EXPECT_EQ(g.samples, 0u);
    absent += (g.flags >> regmap::kGyroFlagAbsent) & 1u;
  }
  EXPECT_EQ(absent, static_cast<int>(run.windows.size()) - 20)
      << "ABSENT from the first wrong WHO_AM_I on";
  EXPECT_EQ(run.state, GyroState::kMissing);
  EXPECT_NE(run.describe.find("gyro missing"), std::string::npos) << run.describe;
  bool said = false;
  for (const auto& line : run.status_lines)
    said |= line.find("heading=wheels-no-gyro") != std::string::npos;
  EXPECT_TRUE(said) << "no status line said heading=wheels-no-gyro";
  // The wheels' rotation (least squares of eq. (9)) still follows the turn, with the encoders'
  // noise.
  const double worst = worst_turn_error_deg(run, daemon_heading(run), 20);
  std::printf("no gyro: the wheels' heading's worst error %.3f deg (%s)\n", worst,
              run.describe.c_str());
  EXPECT_LT(worst, 5.0);
}

}  // namespace
}  // namespace omniloc
