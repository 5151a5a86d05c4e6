// The core of the robot daemon `omnilocd`, free of processes and signals so that tests drive it
// in-process: it opens the board through a factory (USB on the robot; the simulated robot in sim/
// passes its Verilated board), talks to it through one BoardSession, streams encoder windows into
// the Localizer together with camera frames, publishes one pose per window over UDP, records the
// session (REC_DIR contract, recording.hpp), prints a status line once a second, and keeps going
// when the board is unplugged (reconnect loop) or the camera stops (odometry only, flagged).
// Behaviour and formats: docs/DAEMON.md.
#pragma once

#include <csignal>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/control.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/daemon_publish.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/gyro_heading.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/log.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc/transport.hpp"

namespace omniloc::daemon {

/// The daemon's time (ms): the wall clock on the robot, the simulated board's time in simulation
/// (so a simulated run goes at the simulator's pace, not in real time).
class DaemonClock {
 public:
  virtual ~DaemonClock() = default;
  [[nodiscard]] virtual double now_ms() = 0;
  /// Lets `ms` of daemon time pass (sleeps, or runs the simulation).
  virtual void wait_ms(double ms) = 0;
};

/// std::chrono::steady_clock, 0 at construction.
class SteadyClock final : public DaemonClock {
 public:
  SteadyClock();
  double now_ms() override;
  void wait_ms(double ms) override;

 private:
  std::int64_t start_ns_;
};

struct CameraFrame {
  double t_ms = 0.0;  ///< daemon time the image was taken (exposed)
  cv::Mat bgr;
  /// Where t_ms came from, recorded in frame_times.csv: "buffer" (the driver's buffer timestamp),
  /// "latency" (hand-over time minus camera_latency_ms), "file" (the video file's own time), "sim"
  /// (the simulator's exposure time), "host" (the daemon clock at hand-over, nothing subtracted).
  std::string time_source = "host";
  double handover_ms = -1.0;  ///< daemon time the frame was handed over (< 0: not known)
};

/// Camera frames; poll() never blocks for long.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// The newest frame taken at or before now_ms and not handed out yet (older undelivered frames
  /// are dropped, as a live camera would); nullopt when there is none.
  [[nodiscard]] virtual std::optional<CameraFrame> poll(double now_ms) = 0;
  [[nodiscard]] virtual std::string describe() const = 0;
};

/// The windows' heading (gyro_heading.hpp): GyroHeading on a real board, the simulator's gyro in
/// the simulated robot.
using omniloc::GyroHeading;
using omniloc::HeadingSource;
using omniloc::WheelYawHeading;

/// Opens the board's byte pipe; throws TransportError (kNotFound / kDeviceGone / kConfig) when it
/// is not there.
using TransportFactory = std::function<std::unique_ptr<Transport>()>;

/// The models the localizer works with, loaded once.
struct DaemonModels {
  FieldGeometry field;
  CameraModel camera;
  RobotConfig robot;
  LocalizerConfig localizer;
  FeatureDb db;
  std::optional<Pose2> initial_pose;  ///< known start pose (else a global search)
};

/// Loads field, camera, robot and localizer configs and loads or builds the database, as the
/// config says (a `database` path that does not exist yet is built and saved there; when the save
/// fails the database is used from memory and `progress` gets a line starting "warning: ").
/// `progress` receives human-readable lines.
[[nodiscard]] DaemonModels load_models(
    const DaemonConfig& config, const std::function<void(const std::string&)>& progress = {});

/// What happened in one window, for observers (tests, the demo, the simulated robot's truth log).
struct PoseEvent {
  PoseMessage message;      ///< as published
  LocalizedPose localized;  ///< the localizer's full answer (source kNone while degraded)
  bool from_window = true;  ///< false: a degraded pose published while the board is gone
};

/// Watches the daemon without steering it: each callback is optional and runs on the daemon's
/// thread, after the localizer has taken the window or frame.
struct DaemonObserver {
  std::function<void(const EncoderWindow&)> on_window;  ///< every window, with its heading
  std::function<void(const CameraFrame&)> on_frame;     ///< every frame given to the localizer
  std::function<void(const PoseEvent&)> on_pose;        ///< every datagram published
  std::function<void(double now_ms)> on_loop;  ///< every turn of the main loop (board or not)
  std::function<void(const std::string&)> on_status;  ///< every status line, as logged
};

struct DaemonReport {
  std::uint64_t windows = 0;    ///< encoder windows given to the localizer
  std::uint64_t frames = 0;     ///< camera frames given to the localizer
  std::uint64_t published = 0;  ///< datagrams sent
  std::uint64_t send_failed = 0;
  std::uint64_t board_losses = 0;        ///< times the board went away
  std::uint64_t reconnects = 0;          ///< times it came back
  std::uint64_t camera_losses = 0;       ///< times the camera stopped delivering
  std::uint64_t bad_crc = 0;             ///< frames from the board with a bad CRC (all sessions)
  std::uint64_t telemetry_gaps = 0;      ///< gaps in the telemetry sequence (all sessions)
  double run_ms = 0.0;                   ///< daemon time from start to stop
  std::string stop_reason;               ///< "signal", "duration"
  std::uint64_t recording_failures = 0;  ///< write errors (each stops the recording; poses go on)
  std::string recording_error;           ///< the last one, naming the file and the reason
  std::string recording_dir;             ///< the recording it stopped (the last one)
  LocalizerStats localizer;
};

/// "stopped (signal) after 7.0 s: 600 windows, ..." for the end of a run.
[[nodiscard]] std::string report_line(const DaemonReport& report);

/// The daemons' exit code after a run that stopped cleanly when a write error (a full disk) stopped
/// the recording part-way: the poses went on to the end, the recording did not.
inline constexpr int kExitRecordingLost = 3;
/// 0, or kExitRecordingLost; exit_reason says why ("" for 0): "exit 3: the recording to DIR stopped
/// part-way on a write error (ERROR)".
[[nodiscard]] int exit_code(const DaemonReport& report);
[[nodiscard]] std::string exit_reason(const DaemonReport& report);

/// Everything the daemon talks to.
struct DaemonIo {
  DaemonClock* clock = nullptr;      ///< required
  TransportFactory open_board;       ///< required
  FrameSource* camera = nullptr;     ///< null: no camera (odometry only)
  HeadingSource* heading = nullptr;  ///< required (GyroHeading: the board's gyro, else the wheels)
  DaemonObserver observer;           ///< optional
  Logger logger;  ///< status lines and events (default: info and above to stderr)
};

class Daemon {
 public:
  /// `models` must outlive the daemon. Throws ConfigError for a bad config, std::runtime_error if
  /// the UDP socket or the recording directory cannot be made.
  Daemon(const DaemonConfig& config, const DaemonModels& models, DaemonIo io);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  /// Runs until *stop becomes non-zero (a signal handler sets it) or config.duration_s of daemon
  /// time has passed. Switches streaming off and closes the recording on the way out.
  DaemonReport run(const volatile std::sig_atomic_t* stop);
  /// Replaces the observer given in DaemonIo (before run()).
  void set_observer(DaemonObserver observer);
  /// Carries out one control command (control.hpp) on the daemon's thread, as the control channel
  /// does for a datagram: from an observer callback (on_loop) while run() runs, or before it.
  /// Returns the reply's fields; throws control::ControlError saying why it cannot be done.
  nlohmann::json apply(const control::Command& command);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace omniloc::daemon
