// The simulated robot's wiring for the Daemon (sim_daemon.hpp).
#include "omniloc_sim/sim_daemon.hpp"
#include <cstdio>

namespace omniloc::sim {
namespace {

WorldConfig world_config(const daemon::DaemonModels& models, const SimRobotOptions& options) {
  WorldConfig wc = board_world_config(models.robot, options.seed, playing_area(models.field));
  wc.slips = options.slips;
  wc.kidnaps = options.kidnaps;
  return wc;
}

}  // namespace

SimulatedRobot::SimulatedRobot(const daemon::DaemonModels& models, Trajectory trajectory,
                               const SimRobotOptions& options)
    : robot_(world_config(models, options), std::move(trajectory)), renderer_(models.field, models.camera) {
  if (options.camera) {
    RenderOptions ro;
    ro.seed = options.seed;
    camera_ = std::make_unique<SimCamera>(renderer_, robot_.log, options.camera_fps, ro);
  }
}

daemon::DaemonIo SimulatedRobot::io() {
  daemon::DaemonIo io;
  io.clock = &robot_.clock;
  io.open_board = robot_.transport_factory();
  io.heading = &robot_.log;
  io.camera = camera_.get();
  return io;
}

std::string SimulatedRobot::describe() const {
  return "simulated robot: Verilated board at " + std::to_string(BoardSim::kClockHz / 1'000'000) + " MHz" +
         (camera_ ? ", rendered omni camera" : ", no camera") +
         "; the daemon runs at the simulator's pace (slower than real time), not on the wall clock";
}

std::function<void(const EncoderWindow&)> truth_recorder(const SimTruthLog& truth, TruthCsvWriter& writer) {
  // A full disk stops the truth file as it stops the daemon's recording: the run goes on.
  return [&truth, &writer, failed = false](const EncoderWindow& w) mutable {
    if (failed) return;
    try {
      if (const auto pose = truth.truth(w.t_end_ms)) writer.add(w.t_end_ms, *pose);
    } catch (const RecordingError& e) {
      failed = true;
      std::fprintf(stderr, "omnilocd-sim: truth.csv stopped: %s\n", e.what());
    }
  };
}

std::string trajectory_names() {
  std::string out;
  for (const auto& n : standard_trajectory_names()) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace omniloc::sim
