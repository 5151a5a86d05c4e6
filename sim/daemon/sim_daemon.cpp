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
    : robot_(world_config(models, options), std::move(trajectory), options.clocks,
             options.seed ^ 0xC10C5ULL),
      heading_(models.robot, GyroScale::of_board()),
      renderer_(models.field, models.camera) {
  if (options.camera) {
    RenderOptions ro;
    ro.seed = options.seed;
    camera_ = std::make_unique<SimCamera>(renderer_, robot_.log, options.camera_fps, ro);
    camera_->set_delays(options.clocks.camera_latency_ms, options.clocks.camera_jitter_ms,
                        options.clocks.camera_drop_fraction, options.seed ^ 0xCA3E4AULL);
  }
}

daemon::DaemonIo SimulatedRobot::io() {
  daemon::DaemonIo io;
  io.clock = &robot_.clock;
  io.open_board = robot_.transport_factory();
  io.heading = &heading_;  // the board's gyro windows, as omnilocd does
  io.camera = camera_.get();
  return io;
}

std::string SimulatedRobot::describe() const {
  const SimClockConfig& c = robot_.clocks;
  char clocks[200];
  if (c.is_perfect())
    std::snprintf(clocks, sizeof clocks, ", perfect clocks");
  else
    std::snprintf(clocks, sizeof clocks,
                  ", board crystal %+.0f ppm, USB latency exp %.1f ms (max %.1f) + %.0f ms bursts, "
                  "camera %.0f+%.0f ms late, "
                  "%.0f %% dropped",
                  c.board_drift_ppm, c.usb_jitter_mean_ms, c.usb_jitter_max_ms, c.burst_extra_ms,
                  c.camera_latency_ms, c.camera_jitter_ms, c.camera_drop_fraction * 100.0);
  return "simulated robot: Verilated board at " + std::to_string(BoardSim::kClockHz / 1'000'000) +
         " MHz with an ICM-42688-P" + (camera_ ? ", rendered omni camera" : ", no camera") +
         clocks +
         "; the daemon runs at the simulator's pace (slower than real time), not on the wall clock";
}

std::function<void(const EncoderWindow&)> truth_recorder(const SimTruthLog& truth,
                                                         TruthCsvWriter& writer) {
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
