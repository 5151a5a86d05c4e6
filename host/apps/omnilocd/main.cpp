// omnilocd: the localization daemon on the robot. All the work is in the daemon library
// (omniloc/daemon.hpp); this file parses the command line (CLI11, daemon_cli.hpp), wires the board
// (USB) and the camera the config names (V4L2 device or video file, or none) and turns
// SIGINT/SIGTERM into a clean stop. It links no simulator: the simulated robot is its own program,
// `omnilocd-sim` (sim/apps/).
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "daemon_cli.hpp"
#include "live_view_attach.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/daemon_camera.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/detail/service_notify.hpp"
#include "omniloc/usb_transport.hpp"
#include "omniloc/version.hpp"
#include "ros2_attach.hpp"
#include "stop_signal.hpp"
#include "subcommand_cli.hpp"

namespace {

int run(const omniloc::daemon::DaemonConfig& config, const omniloc::Logger& log) {
  using namespace omniloc;
  using namespace omniloc::daemon;
  auto say = [&log](const std::string& s) { log.info(s); };
  const DaemonModels models = load_models(config, say);

  SteadyClock wall;
  // The board's gyro when its windows carry one, else the wheels' rotation (gyro_heading.hpp).
  GyroHeading heading(models.robot, GyroScale::of_board());
  DaemonIo io;
  io.logger = log;
  io.clock = &wall;
  UsbTransportOptions usb;
  usb.serial = config.board_serial;
  io.open_board = [usb]() -> std::unique_ptr<Transport> {
    return std::make_unique<UsbTransport>(usb);
  };
  io.heading = &heading;
  std::unique_ptr<FrameSource> camera;
  if (config.camera != "none")
    camera = std::make_unique<OpenCvCamera>(config.camera, config.camera_fps, wall);
  io.camera = camera.get();
  say("publishing poses to udp://" + config.udp_address + ":" + std::to_string(config.udp_port) +
      (config.record_dir.empty() ? "" : ", recording to " + config.record_dir));
  omniloc::cli::Ros2Attachment ros2(config, log);
  omniloc::cli::LiveViewAttachment live_view(config, models, log);
  Daemon daemon(config, models, io);
  // Under systemd (Type=notify): ready once the models are loaded and the loop starts; the loop
  // feeds the watchdog whether or not a board is there.
  ServiceNotifier service;
  DaemonObserver observer;
  observer.on_loop = [&service](double now_ms) { service.loop(now_ms); };
  observer.on_status = [&service](const std::string& line) { service.status(line); };
  ros2.attach(observer, daemon);
  live_view.attach(observer);
  daemon.set_observer(std::move(observer));
  omniloc::cli::install_stop_signal_handlers();
  service.ready();
  const DaemonReport r = daemon.run(&omniloc::cli::g_stop_requested);
  service.stopping();
  log.info(report_line(r));
  if (exit_code(r) != 0) log.error(exit_reason(r));
  return exit_code(r);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "The robot's localization daemon: USB board + camera -> localizer -> UDP poses.\n"
      "Flags override the config file (JSON, docs/DAEMON.md).",
      "omnilocd"};
  app.set_version_flag("--version", omniloc::version_line("omnilocd"));
  app.failure_message(omniloc::cli::failure_message_with_path);  // "omnilocd: error: ..."
  app.footer("SIGINT / SIGTERM stop it cleanly (recording closed, board streaming switched off).");
  omniloc::cli::DaemonCommandLine cl;
  omniloc::cli::add_daemon_options(app, cl);
  return omniloc::cli::parse_and_run(app, argc, argv, "omnilocd", [&] {
    const omniloc::daemon::DaemonConfig config = omniloc::cli::daemon_config_from(cl);
    return run(config, omniloc::cli::daemon_logger(config, cl, "omnilocd"));
  });
}
