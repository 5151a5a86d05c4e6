// omnilocd-sim: the robot's daemon (the same Daemon as omnilocd) on the simulated robot: the world
// simulator drives the Verilated board, the camera renders the field at the true pose, and time is
// the board's simulated time. Takes every omnilocd option (the camera is rendered unless
// `--camera none`) plus the simulation's own: --trajectory NAME and --seed N. With --record-dir it
// also writes the run's truth.csv beside the recording, so `omniloc replay` reports errors.
#include <charconv>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "omniloc/daemon.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/recording.hpp"
#include "omniloc_sim/playing_area.hpp"
#include "omniloc_sim/sim_daemon.hpp"
#include "stop_signal.hpp"

namespace {

struct SimArgs {
  std::string trajectory = "figure_eight";
  std::uint64_t seed = 1;
  std::vector<std::string_view> daemon_args;  ///< everything else, for parse_daemon_args
};

std::string sim_usage() {
  return "usage: omnilocd-sim [--trajectory NAME] [--seed N] [omnilocd options]\n"
         "  The robot daemon on the simulated robot (Verilated board, rendered camera).\n"
         "  --trajectory NAME  the simulated drive: " + omniloc::sim::trajectory_names() + " (default figure_eight)\n"
         "  --seed N           world and sensor noise seed, 0 .. 2^64-1 (default 1)\n"
         "  --camera none      no camera (odometry only); any other camera value means the rendered one\n\n"
         "omnilocd options:\n";
}

std::uint64_t parse_seed(std::string_view v) {
  std::uint64_t n = 0;
  const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
  if (v.empty() || ec != std::errc() || p != v.data() + v.size())
    throw omniloc::ConfigError("command line: --seed: must be an integer 0 .. 18446744073709551615 (got '" +
                               std::string(v) + "')");
  return n;
}

/// Takes --trajectory and --seed (as "--key value" or "--key=value") out of the arguments.
SimArgs split_args(std::span<const std::string_view> args) {
  SimArgs s;
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string_view a = args[i];
    std::optional<std::string_view> inline_value;
    if (const auto eq = a.find('='); a.starts_with("--") && eq != std::string_view::npos) {
      inline_value = a.substr(eq + 1);
      a = a.substr(0, eq);
    }
    if (a != "--trajectory" && a != "--seed") {
      s.daemon_args.push_back(args[i]);
      continue;
    }
    if (!inline_value && i + 1 >= args.size())
      throw omniloc::ConfigError("command line: " + std::string(a) + " needs a value");
    const std::string_view v = inline_value ? *inline_value : args[++i];
    if (a == "--seed") s.seed = parse_seed(v);
    else s.trajectory = std::string(v);
  }
  return s;
}

int run(const omniloc::daemon::DaemonConfig& config, const SimArgs& sim_args) {
  using namespace omniloc;
  auto say = [](const std::string& s) { std::fprintf(stderr, "omnilocd-sim: %s\n", s.c_str()); };
  const daemon::DaemonModels models = daemon::load_models(config, say);
  sim::SimRobotOptions o;
  o.seed = sim_args.seed;
  o.camera = config.camera != "none";
  o.camera_fps = config.camera_fps;
  sim::SimulatedRobot robot(models, sim::make_trajectory(sim_args.trajectory, sim_args.seed, sim::playing_area(models.field)), o);
  say(robot.describe() + "; trajectory " + sim_args.trajectory + ", seed " + std::to_string(sim_args.seed));
  daemon::DaemonIo io = robot.io();
  say("publishing poses to udp://" + config.udp_address + ":" + std::to_string(config.udp_port) +
      (config.record_dir.empty() ? "" : ", recording to " + config.record_dir));
  daemon::Daemon d(config, models, io);
  // After the daemon has made the recording directory (and removed an old truth.csv).
  std::unique_ptr<TruthCsvWriter> truth_csv;
  if (!config.record_dir.empty()) {
    truth_csv = std::make_unique<TruthCsvWriter>(std::filesystem::path(config.record_dir) / "truth.csv");
    d.set_observer(daemon::DaemonObserver{sim::truth_recorder(robot.truth(), *truth_csv), {}, {}});
  }
  omniloc::cli::install_stop_signal_handlers();
  const daemon::DaemonReport r = d.run(&omniloc::cli::g_stop_requested);
  if (truth_csv) truth_csv->close();
  say(daemon::report_line(r));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string_view> args(argv + 1, argv + argc);
  try {
    const SimArgs sim_args = split_args(args);
    const auto parsed = omniloc::daemon::parse_daemon_args(sim_args.daemon_args);
    if (parsed.help) {
      std::fputs((sim_usage() + omniloc::daemon::daemon_usage()).c_str(), stdout);
      return 0;
    }
    return run(parsed.config, sim_args);
  } catch (const omniloc::ConfigError& e) {
    std::fprintf(stderr, "omnilocd-sim: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "omnilocd-sim: error: %s\n", e.what());
    return 1;
  }
}
