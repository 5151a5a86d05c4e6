// The simulated robot behind the robot's own Daemon: world -> quadrature waveforms and the
// ICM-42688-P model -> Verilated board (rtl/omniloc_top.v) -> SimTransport, the heading from the
// board's gyro windows as on the real robot (GyroHeading, no side channel), a camera rendering the
// field at the true pose, and the simulation's host clock as the daemon's (realistic clocks by
// default, sim_clocks.hpp). `omnilocd-sim`, `omniloc-sim demo` and the tests build their runs from
// it; truth reaches them through the truth log and the daemon's observer, never through the daemon.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "omniloc/daemon.hpp"
#include "omniloc/recording.hpp"
#include "omniloc_sim/renderer.hpp"
#include "omniloc_sim/sim_clocks.hpp"
#include "omniloc_sim/sim_robot.hpp"
#include "omniloc_sim/trajectory.hpp"
#include "omniloc_sim/verilated_robot.hpp"
#include "omniloc_sim/world.hpp"

namespace omniloc::sim {

struct SimRobotOptions {
  std::uint64_t seed = 1;            ///< world noise, and the first frame's sensor noise
  bool camera = true;                ///< false: no camera (the daemon runs odometry only)
  double camera_fps = 60.0;          ///< frames per second of simulated time
  std::vector<SlipEvent> slips;      ///< wheel slips the world injects
  std::vector<KidnapEvent> kidnaps;  ///< kidnappings the world injects
  /// The board's crystal, the USB latency and the camera's delays (sim_clocks.hpp): realistic by
  /// default; SimClockConfig::perfect() for every clock equal and no delay.
  SimClockConfig clocks = SimClockConfig::realistic();
};

class SimulatedRobot {
 public:
  /// `models` must outlive the robot (the renderer keeps the field and camera).
  SimulatedRobot(const daemon::DaemonModels& models, Trajectory trajectory,
                 const SimRobotOptions& options);

  /// Clock, board factory, heading (the board's gyro windows) and camera for the Daemon (observer
  /// and log are the caller's).
  [[nodiscard]] daemon::DaemonIo io();
  [[nodiscard]] const SimTruthLog& truth() const { return robot_.log; }
  [[nodiscard]] BoardSim& board() { return robot_.board; }
  /// The gyro part on the board: its faults() make it fail or vanish (who_am_i) mid-run.
  [[nodiscard]] Icm42688& gyro() { return robot_.gyro; }
  [[nodiscard]] const GyroHeading& heading() const { return heading_; }
  [[nodiscard]] std::int64_t board_cycles() const { return robot_.board.cycle(); }
  [[nodiscard]] std::string describe() const;

 private:
  VerilatedRobot robot_;
  GyroHeading heading_;
  OmniRenderer renderer_;
  std::unique_ptr<SimCamera> camera_;
};

/// Writes the true pose at every window's time into `writer` (truth.csv beside a recording).
/// The writer and the truth log must outlive the daemon run.
[[nodiscard]] std::function<void(const EncoderWindow&)> truth_recorder(const SimTruthLog& truth,
                                                                       TruthCsvWriter& writer);

/// Trajectory names make_trajectory knows, for --help texts.
[[nodiscard]] std::string trajectory_names();

}  // namespace omniloc::sim
