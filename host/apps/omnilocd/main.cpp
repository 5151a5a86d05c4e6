// omnilocd: the localization daemon on the robot. All the work is in the daemon library
// (omniloc/daemon.hpp); this file parses the command line, wires the board and camera the config
// names (USB + V4L2 on the robot, the Verilated board + renderer with `--board sim --camera sim`)
// and turns SIGINT/SIGTERM into a clean stop.
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "omniloc/daemon.hpp"
#include "omniloc/daemon_board_sim.hpp"
#include "omniloc/daemon_camera.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/usb_transport.hpp"
#include "omniloc_sim/renderer.hpp"
#include "omniloc_sim/trajectory.hpp"

namespace {

// The one piece of global state: a signal handler can only reach a static object, and the only
// thing it may safely do is set a volatile sig_atomic_t. The daemon polls it once per loop.
volatile std::sig_atomic_t g_stop = 0;

extern "C" void on_signal(int) { g_stop = 1; }

void install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking read returns early and the loop sees the flag
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int run(const omniloc::daemon::DaemonConfig& config) {
  using namespace omniloc;
  using namespace omniloc::daemon;
  auto say = [](const std::string& s) { std::fprintf(stderr, "omnilocd: %s\n", s.c_str()); };
  if (config.camera == "sim" && config.board != "sim")
    throw ConfigError("config: field 'camera': \"sim\" renders at the simulated robot's pose and needs board \"sim\"");
  if (config.board == "sim" && config.camera != "sim" && config.camera != "none")
    throw ConfigError("config: field 'camera': with board \"sim\" the camera must be \"sim\" or \"none\" "
                      "(a real camera runs on the wall clock, the simulated board on its own)");
  const DaemonModels models = load_models(config, say);

  DaemonIo io;
  std::unique_ptr<SteadyClock> wall;
  std::unique_ptr<WheelYawExtras> wheel_yaw;
  std::unique_ptr<VerilatedRobot> robot;
  std::unique_ptr<sim::OmniRenderer> renderer;
  std::unique_ptr<FrameSource> camera;
  if (config.board == "sim") {
    robot = std::make_unique<VerilatedRobot>(board_world_config(models.robot, config.sim_seed),
                                             sim::make_trajectory(config.sim_trajectory, config.sim_seed));
    io.clock = &robot->clock;
    io.open_board = robot->transport_factory();
    io.extras = &robot->log;
    say("simulated robot: trajectory " + config.sim_trajectory + ", Verilated board at 12 MHz; the daemon runs at "
        "the simulator's pace (slower than real time), not on the wall clock");
    if (config.camera == "sim") {
      renderer = std::make_unique<sim::OmniRenderer>(models.field, models.camera);
      sim::RenderOptions ro;
      ro.seed = config.sim_seed;
      camera = std::make_unique<SimCamera>(*renderer, robot->log, config.camera_fps, ro);
    }
  } else {
    wall = std::make_unique<SteadyClock>();
    wheel_yaw = std::make_unique<WheelYawExtras>(models.robot);
    io.clock = wall.get();
    UsbTransportOptions usb;
    usb.serial = config.board_serial;
    io.open_board = [usb]() -> std::unique_ptr<Transport> { return std::make_unique<UsbTransport>(usb); };
    io.extras = wheel_yaw.get();
    if (config.camera != "none") camera = std::make_unique<OpenCvCamera>(config.camera, config.camera_fps, *wall);
  }
  io.camera = camera.get();
  say("publishing poses to udp://" + config.udp_address + ":" + std::to_string(config.udp_port) +
      (config.record_dir.empty() ? "" : ", recording to " + config.record_dir));
  Daemon daemon(config, models, io);
  install_signal_handlers();
  const DaemonReport r = daemon.run(&g_stop);
  std::fprintf(stderr,
               "omnilocd: stopped (%s) after %.1f s: %llu windows, %llu frames, %llu poses sent (%llu failed), "
               "board lost %llu x / back %llu x, camera lost %llu x\n",
               r.stop_reason.c_str(), r.run_ms / 1000.0, static_cast<unsigned long long>(r.windows),
               static_cast<unsigned long long>(r.frames), static_cast<unsigned long long>(r.published),
               static_cast<unsigned long long>(r.send_failed), static_cast<unsigned long long>(r.board_losses),
               static_cast<unsigned long long>(r.reconnects), static_cast<unsigned long long>(r.camera_losses));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string_view> args(argv + 1, argv + argc);
  try {
    const auto parsed = omniloc::daemon::parse_daemon_args(args);
    if (parsed.help) {
      std::fputs(omniloc::daemon::daemon_usage().c_str(), stdout);
      return 0;
    }
    return run(parsed.config);
  } catch (const omniloc::ConfigError& e) {
    std::fprintf(stderr, "omnilocd: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "omnilocd: error: %s\n", e.what());
    return 1;
  }
}
