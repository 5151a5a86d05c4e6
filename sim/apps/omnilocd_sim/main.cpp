// omnilocd-sim: the robot's daemon (the same Daemon as omnilocd) on the simulated robot: the world
// simulator drives the Verilated board, the camera renders the field at the true pose, and time is
// the simulation's host clock (realistic clocks by default, docs/SIMULATOR.md "Clocks";
// --perfect-clocks: the board's simulated time). Takes every omnilocd option (the camera is
// rendered unless `--camera none`) plus the simulation's own: --trajectory NAME, --seed N,
// --perfect-clocks, --board-drift-ppm PPM, --start known|search. With --record-dir it
// also writes the run's truth.csv beside the recording, so `omniloc replay` reports errors.
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>

#include "daemon_cli.hpp"
#include "live_view_attach.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/recording.hpp"
#include "omniloc/version.hpp"
#include "omniloc_sim/playing_area.hpp"
#include "omniloc_sim/sim_daemon.hpp"
#include "ros2_attach.hpp"
#include "stop_signal.hpp"
#include "subcommand_cli.hpp"

namespace {

struct SimArgs {
  std::string trajectory = "figure_eight";
  std::uint64_t seed = 1;
  bool perfect_clocks = false;
  double board_drift_ppm = 50.0;
  std::string start = "known";  ///< known: the daemon is told the start pose; search: it is not
};

int run(const omniloc::daemon::DaemonConfig& config, const SimArgs& sim_args,
        const omniloc::Logger& log) {
  using namespace omniloc;
  auto say = [&log](const std::string& s) { log.info(s); };
  daemon::DaemonModels models = daemon::load_models(config, say);
  sim::SimRobotOptions o;
  o.seed = sim_args.seed;
  o.camera = config.camera != "none";
  o.camera_fps = config.camera_fps;
  if (sim_args.perfect_clocks)
    o.clocks = sim::SimClockConfig::perfect();
  else
    o.clocks.board_drift_ppm = sim_args.board_drift_ppm;
  const sim::Trajectory trajectory =
      sim::make_trajectory(sim_args.trajectory, sim_args.seed, sim::playing_area(models.field));
  // --start known: the team places the robot and tells the daemon its start pose (a kick-off); the
  // board's gyro is relative, so without it (or a side and goal colours) a global search on the
  // point-symmetric field stays ambiguous.
  if (sim_args.start == "known") models.initial_pose = trajectory.start();
  sim::SimulatedRobot robot(models, trajectory, o);
  say(robot.describe() + "; trajectory " + sim_args.trajectory + ", seed " +
      std::to_string(sim_args.seed));
  daemon::DaemonIo io = robot.io();
  io.logger = log;
  say("publishing poses to udp://" + config.udp_address + ":" + std::to_string(config.udp_port) +
      (config.record_dir.empty() ? "" : ", recording to " + config.record_dir));
  omniloc::cli::Ros2Attachment ros2(config, log);
  omniloc::cli::LiveViewAttachment live_view(config, models, log);
  daemon::Daemon d(config, models, io);
  // After the daemon has made the recording directory (and removed an old truth.csv).
  std::unique_ptr<TruthCsvWriter> truth_csv;
  daemon::DaemonObserver observer;
  if (!config.record_dir.empty()) {
    truth_csv =
        std::make_unique<TruthCsvWriter>(std::filesystem::path(config.record_dir) / "truth.csv");
    observer.on_window = sim::truth_recorder(robot.truth(), *truth_csv);
  }
  ros2.attach(observer, d);
  live_view.attach(observer);
  d.set_observer(std::move(observer));
  omniloc::cli::install_stop_signal_handlers();
  const daemon::DaemonReport r = d.run(&omniloc::cli::g_stop_requested);
  if (truth_csv) truth_csv->close();
  say(daemon::report_line(r));
  if (daemon::exit_code(r) != 0) log.error(daemon::exit_reason(r));
  return daemon::exit_code(r);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "The robot daemon (omnilocd's options) on the simulated robot: Verilated board, rendered "
      "camera\n"
      "(--camera none: no camera, odometry only; any other camera value means the rendered one).",
      "omnilocd-sim"};
  app.set_version_flag("--version", omniloc::version_line("omnilocd-sim"));
  app.failure_message(omniloc::cli::failure_message_with_path);  // "omnilocd-sim: error: ..."
  SimArgs sim_args;
  app.add_option("--trajectory", sim_args.trajectory,
                 "the simulated drive: " + omniloc::sim::trajectory_names())
      ->default_str(sim_args.trajectory);
  omniloc::cli::add_number_option(app, "--seed", sim_args.seed, "world and sensor noise seed");
  app.add_flag(
      "--perfect-clocks", sim_args.perfect_clocks,
      "every clock equal, no USB or camera delay (default: realistic clocks, docs/SIMULATOR.md)");
  app.add_option("--board-drift-ppm", sim_args.board_drift_ppm,
                 "the simulated board crystal against the host clock")
      ->default_str("50")
      ->check(CLI::Range(-1000.0, 1000.0));
  app.add_option(
         "--start", sim_args.start,
         "known: the daemon is told the robot's start pose, as a team does at kick-off; search: it "
         "is not "
         "(a global search, ambiguous on a point-symmetric field until set_side or set_pose)")
      ->default_str("known")
      ->check(CLI::IsMember({"known", "search"}));
  omniloc::cli::DaemonCommandLine cl;
  omniloc::cli::add_daemon_options(app, cl);
  return omniloc::cli::parse_and_run(app, argc, argv, "omnilocd-sim", [&] {
    const omniloc::daemon::DaemonConfig config = omniloc::cli::daemon_config_from(cl);
    return run(config, sim_args, omniloc::cli::daemon_logger(config, cl, "omnilocd-sim"));
  });
}
