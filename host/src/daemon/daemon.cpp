// omnilocd's main loop: board windows -> localizer -> UDP, camera frames beside them, recording,
// status line, board reconnects and camera loss. One thread: the localizer is not thread-safe and
// one loop keeps the order of windows and frames obvious.
#include "omniloc/daemon.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>
#include <vector>

#include "omniloc/board_session.hpp"
#include "omniloc/control.hpp"
#include "omniloc/detail/board_clock.hpp"
#include "omniloc/recording.hpp"
#include "omniloc/regmap.hpp"

namespace omniloc::daemon {
namespace {

// A board that answers but stops streaming for this long is treated as gone (a USB bridge can stay
// enumerated while the FPGA is reset or unpowered).
constexpr double kBoardSilentMs = 250.0;
// While the board is gone, a degraded pose goes out every window period, so consumers see the
// state.
constexpr double kDegradedTickMs = regmap::kWindowPeriodMs;
constexpr std::chrono::milliseconds kTelemetryWait{20};
constexpr std::size_t kMaxQueuedAtOpen = 1024;  // the board client's telemetry queue

}  // namespace

struct Daemon::Impl {
  DaemonConfig config;
  const DaemonModels& models;
  DaemonIo io;
  UdpPublisher publisher;
  Localizer localizer;
  std::unique_ptr<RecordingWriter> recorder;
  std::string
      record_dir;  // of the recording now open (config.record_dir, or one started by command)
  std::unique_ptr<control::ControlSocket> control_socket;

  // Board connection.
  std::unique_ptr<BoardSession> client;
  // Board time -> daemon time (board_clock.hpp): one model over all sessions, since the board's
  // time runs on through a reconnect; a board reset starts a new epoch in it.
  BoardClockModel board_clock;
  bool session_started = false;  // the first windows of this session have been read
  // A session's board times start at 0 (BoardSession); the model gets them on one scale over the
  // sessions, continued through a reconnect from the board's raw counter (continued_board_ms).
  double session_base_ms = 0.0;
  std::optional<BoardTimeMark> last_mark;  // the newest window of any session
  double last_window_clock_ms = 0.0;       // clock time a window last arrived
  double next_attempt_ms = 0.0;
  bool ever_connected = false;
  bool board_gone = false;
  std::string last_open_error;

  // Camera.
  std::optional<double> last_frame_ms;  // daemon time of the newest frame given to the localizer
  bool camera_fresh = false;

  // Output.
  std::optional<double> last_window_t_ms;
  std::uint64_t seq = 0;
  DaemonReport report;
  PoseMessage last_message;
  LocalizedPose last_localized;

  std::string heading_described;  ///< io.heading->describe() as last logged
  /// Gyro yaws dropped as implausible (Localizer::on_window): warned about at most every
  /// kGyroWarningPeriodMs, with the count since the last warning.
  std::optional<double> last_gyro_warning_ms;
  int gyro_dropped_unwarned = 0;

  // Status line.
  double next_status_ms = 0.0;
  std::uint64_t windows_at_status = 0, frames_at_status = 0;
  double status_from_ms = 0.0;

  Impl(const DaemonConfig& c, const DaemonModels& m, DaemonIo i)
      : config(c),
        models(m),
        io(std::move(i)),
        publisher(c.udp_address, c.udp_port),
        localizer(m.localizer, m.robot, m.field, m.camera, m.db, m.initial_pose) {
    if (!io.clock || !io.open_board || !io.heading)
      throw std::invalid_argument("Daemon: clock, open_board and heading are required");
    heading_described = io.heading->describe();
    if (config.side != "unknown") {
      try {
        localizer.set_side(config.side == "blue" ? GoalColour::kBlue : GoalColour::kYellow);
      } catch (const std::invalid_argument& e) {
        throw ConfigError(e.what());
      }
    }
    if (!config.record_dir.empty()) start_recording(config.record_dir, config.record_overwrite);
    if (config.control_port > 0) {
      try {
        control_socket = std::make_unique<control::ControlSocket>("127.0.0.1", config.control_port);
      } catch (const std::exception& e) {
        // The poses matter more than the commands: the daemon runs on without them, and says so.
        io.logger.warning(std::string("control channel off: ") + e.what());
      }
    }
  }

  void start_recording(const std::string& dir, bool overwrite) {
    RecordingMeta meta;
    meta.field = config.field;
    meta.field_geometry = models.field.spec;  // self-contained: replays without the field file
    meta.camera = models.camera;
    meta.robot = models.robot;
    meta.initial_pose = models.initial_pose;
    RecordingOptions ro;
    ro.overwrite = overwrite;
    ro.frame_format = config.record_format == "png" ? FrameFormat::kPng : FrameFormat::kJpeg;
    recorder = std::make_unique<RecordingWriter>(dir, meta, false, ro);
    record_dir = dir;
  }

  void close_recording() {
    if (!recorder) return;
    try {
      recorder->close();
    } catch (const RecordingError& e) {
      ++report.recording_failures;
      report.recording_error = e.what();
      report.recording_dir = record_dir;
      io.logger.error(std::string("recording could not be closed: ") + e.what());
    }
    recorder.reset();
  }

  // A recording that cannot be written (disk full, file size limit) stops; the pose stream goes on.
  template <class Write>
  void record(Write write) {
    if (!recorder) return;
    try {
      write();
    } catch (const RecordingError& e) {
      ++report.recording_failures;
      report.recording_error = e.what();
      report.recording_dir = record_dir;
      recorder.reset();  // closes what is open; whole rows only are on disk
      io.logger.error(std::string("recording stopped: ") + e.what() + "; poses are still sent");
    }
  }

  DaemonStatus status(double now_ms) const {
    if (!ever_connected) return DaemonStatus::kNoBoard;
    if (board_gone || !client) return DaemonStatus::kDegraded;
    // No camera at all: dead reckoning from the start, and said so (there will never be a fix).
    if (!io.camera) return DaemonStatus::kOdometryOnly;
    if (!localizer.has_fix()) return DaemonStatus::kStarting;
    if (localizer.lost()) return DaemonStatus::kLost;
    if (!camera_fresh_at(now_ms)) return DaemonStatus::kOdometryOnly;
    return DaemonStatus::kOk;
  }

  /// A frame reached the localizer within the camera timeout.
  bool camera_fresh_at(double now_ms) const {
    return last_frame_ms && now_ms - *last_frame_ms <= config.camera_timeout_ms;
  }

  // t_uncertainty_ms none: t_ms is not a board time (no board: the daemon's own clock).
  void publish(const LocalizedPose& lp, DaemonStatus st, double t_ms, bool from_window,
               std::optional<double> t_uncertainty_ms = std::nullopt) {
    PoseMessage m;
    m.seq = ++seq;
    m.t_ms = t_ms;
    m.t_uncertainty_ms = t_uncertainty_ms;
    m.x_cm = lp.pose.x_cm;
    m.y_cm = lp.pose.y_cm;
    m.yaw_deg = lp.pose.yaw_deg;
    m.source = pose_source_name(lp.source);
    m.match_error = lp.match_error;
    m.search_range_cm = lp.search_range_cm;
    if (lp.source != PoseSource::kNone) {  // else no pose, no uncertainty (not 0: certain)
      m.uncertainty_cm = lp.sigma_xy_cm;
      m.uncertainty_yaw_deg = lp.sigma_yaw_deg;
    }
    m.vx_cm_s = lp.vx_cm_s;
    m.vy_cm_s = lp.vy_cm_s;
    m.omega_deg_s = lp.omega_deg_s;
    // The host's own clocks at the send (not the daemon clock, which is the simulator's in
    // simulation): what a consumer on this host compares with its receive time.
    using Ms = std::chrono::duration<double, std::milli>;
    m.mono_ms = Ms(std::chrono::steady_clock::now().time_since_epoch()).count();
    m.wall_ms = Ms(std::chrono::system_clock::now().time_since_epoch()).count();
    m.status = st;
    publisher.send(pose_json(m));
    last_message = m;
    report.published = publisher.sent();
    report.send_failed = publisher.failed();
    if (io.observer.on_pose) io.observer.on_pose(PoseEvent{m, lp, from_window});
  }

  void try_connect(double now_ms) {
    if (now_ms < next_attempt_ms) return;
    next_attempt_ms = now_ms + config.reconnect_period_ms;
    try {
      BoardSessionOptions o;
      o.decoding = models.robot.decoding;
      o.wheels = wheel_count(models.robot);  // refuses a board whose encoder channels differ
      client = std::make_unique<BoardSession>(io.open_board(), o);
      if (version_differs(client->identity()))
        io.logger.warning("board register map " + client->identity().version_text() +
                          " differs from the host's");
      session_started = false;
      last_window_clock_ms = io.clock->now_ms();
      if (ever_connected) {
        ++report.reconnects;
        io.logger.info("board back (" + client->describe() + "), streaming again");
      } else {
        io.logger.info("board open (" + client->describe() + "), streaming");
      }
      ever_connected = true;
      board_gone = false;
      last_open_error.clear();
    } catch (const std::exception& e) {
      client.reset();
      if (e.what() != last_open_error)
        io.logger.warning(std::string("board not available: ") + e.what());
      last_open_error = e.what();
    }
  }

  void count_link_errors() {
    if (!client) return;
    report.bad_crc += client->client().decoder_counters().bad_crc;
    report.telemetry_gaps += client->client().decoder_counters().telemetry_gaps;
  }

  void lose_board(const std::string& why) {
    count_link_errors();
    client.reset();
    if (!board_gone) {
      ++report.board_losses;
      io.logger.warning("board lost (" + why + "): status degraded, reconnecting every " +
                        std::to_string(static_cast<int>(config.reconnect_period_ms)) + " ms");
    }
    board_gone = true;
    next_attempt_ms = io.clock->now_ms() + config.reconnect_period_ms;
  }

  // This session's board_ms 0 on the scale the clock model has seen so far; a board that restarted
  // its counter while away starts a new epoch in the model.
  void continue_board_time(const SessionWindow& newest, double arrival_ms) {
    const double clock_hz = client->identity().clock_hz;
    if (!last_mark) {
      session_base_ms = 0.0;
      return;
    }
    if (const auto b =
            continued_board_ms(*last_mark, newest.raw.timestamp_cycles, clock_hz, arrival_ms)) {
      session_base_ms = *b - newest.board_ms;
      return;
    }
    board_clock.restart();
    session_base_ms = last_mark->board_ms + (arrival_ms - last_mark->arrival_ms) - newest.board_ms;
    io.logger.info(
        "board time does not continue from before the reconnect (board reset?): clock re-anchored");
  }

  double scaled_board_ms(const SessionWindow& w) const { return session_base_ms + w.board_ms; }

  // A change of what the heading comes from (a gyro fault and its end, a board without a gyro)
  // is an event worth a line of its own.
  void note_heading() {
    std::string now = io.heading->describe();
    if (now == heading_described) return;
    const bool worse = io.heading->trust() == HeadingTrust::kNone;
    const std::string line = "heading: " + now + " (was " + heading_described + ")";
    if (worse) {
      io.logger.warning(line);
    } else {
      io.logger.info(line);
    }
    heading_described = std::move(now);
  }

  // A window's gyro yaw dropped as implausible: a warning, at most one every 10 s (a gyro that
  // keeps faulting would otherwise write 100 lines a second).
  void note_gyro_dropped(const LocalizedPose& lp, double now_ms) {
    static constexpr double kGyroWarningPeriodMs = 10000.0;
    if (!lp.gyro_yaw_dropped) return;
    ++gyro_dropped_unwarned;
    if (last_gyro_warning_ms && now_ms - *last_gyro_warning_ms < kGyroWarningPeriodMs) return;
    io.logger.warning(
        "window seq " + std::to_string(lp.seq) + ": " + lp.gyro_yaw_dropped->describe() +
        ": dropped, the window's heading taken from the wheels (" +
        std::to_string(gyro_dropped_unwarned) + " window(s) since the last warning, " +
        std::to_string(localizer.stats().gyro_yaw_dropped) + " in all)");
    last_gyro_warning_ms = now_ms;
    gyro_dropped_unwarned = 0;
  }

  void on_board_window(const SessionWindow& w, const BoardClockEstimate& clock_at) {
    const double now = io.clock->now_ms();
    last_window_clock_ms = now;
    const double board_ms = scaled_board_ms(w);
    last_mark = BoardTimeMark{w.raw.timestamp_cycles, board_ms, now, client->identity().clock_hz};
    EncoderWindow ew = w.to_encoder_window(clock_at.host_ms - w.board_ms);
    if (last_window_t_ms && ew.t_end_ms <= *last_window_t_ms)
      ew.t_end_ms = *last_window_t_ms + 1e-3;  // the localizer needs increasing times
    last_window_t_ms = ew.t_end_ms;
    ew.gyro_yaw_deg = io.heading->gyro_yaw_deg(ew);
    // How far the heading can be trusted is the heading source's to say, window by window: the
    // wheels never (slip), a working gyro once a fix has aligned it (gyro_heading.hpp).
    ew.heading_trust = io.heading->trust();
    note_heading();
    const LocalizedPose lp = localizer.on_window(ew);
    note_gyro_dropped(lp, now);
    ++report.windows;
    last_localized = lp;
    record([&] {
      recorder->add_window(ew);
      recorder->add_clock(ClockRow{ew.seq, board_ms, now, ew.t_end_ms, clock_at.offset_ms,
                                   clock_at.drift_ppm, clock_at.uncertainty_ms, clock_at.epoch});
    });
    if (io.observer.on_window) io.observer.on_window(ew);
    publish(lp, status(now), ew.t_end_ms, true, clock_at.uncertainty_ms);
  }

  void poll_camera(double now_ms) {
    if (!io.camera) return;
    // Frames wait while the board is gone: the localizer can only place them between windows.
    if (!board_gone && client) {
      if (auto f = io.camera->poll(now_ms)) {
        if (f->time_source == "host") {
          // Stamped at hand-over: the exposure was camera_latency_ms before (docs/DAEMON.md "Camera
          // time").
          if (f->handover_ms < 0) f->handover_ms = f->t_ms;
          f->t_ms -= config.camera_latency_ms;
          f->time_source = "latency";
        }
        const FrameReport fr = localizer.on_image(f->t_ms, f->bgr);
        if (io.logger.enabled(LogLevel::kDebug))
          io.logger.debug(
              "frame t=" + nlohmann::json(f->t_ms).dump() + " ms: " +
              (fr.no_measurement.empty() ? "queued" : "no measurement: " + fr.no_measurement));
        record([&] {
          recorder->add_frame(f->t_ms, f->bgr);
          recorder->add_frame_time(
              FrameTimeRow{f->t_ms, f->time_source, f->handover_ms >= 0 ? f->handover_ms : now_ms});
        });
        if (io.observer.on_frame) io.observer.on_frame(*f);
        last_frame_ms = f->t_ms;
        ++report.frames;
      }
    }
    const bool fresh = camera_fresh_at(now_ms);
    if (camera_fresh && !fresh && !board_gone) {
      ++report.camera_losses;
      io.logger.warning("camera stopped delivering (" + io.camera->describe() + "): odometry only");
    } else if (!camera_fresh && fresh && report.camera_losses > 0) {
      io.logger.info("camera delivering again");
    }
    camera_fresh = fresh;
  }

  void status_tick(double now_ms, double start_ms) {
    if (config.status_period_s <= 0 || now_ms < next_status_ms) return;
    const double span_s = (now_ms - status_from_ms) / 1000.0;
    StatusSnapshot s;
    s.t_s = (now_ms - start_ms) / 1000.0;
    s.status = status(now_ms);
    s.x_cm = last_message.x_cm;
    s.y_cm = last_message.y_cm;
    s.yaw_deg = last_message.yaw_deg;
    s.source = last_message.source;
    s.match_error = last_message.match_error;
    s.uncertainty_cm = last_message.uncertainty_cm;
    s.gyro_drift_deg_per_s = localizer.yaw_drift_deg_per_s();
    s.windows_per_s =
        span_s > 0 ? static_cast<double>(report.windows - windows_at_status) / span_s : 0.0;
    s.frames_per_s =
        span_s > 0 ? static_cast<double>(report.frames - frames_at_status) / span_s : 0.0;
    s.published = publisher.sent();
    s.send_failed = publisher.failed();
    s.send_error = publisher.last_error();
    s.reconnects = report.reconnects;
    if (!record_dir.empty()) s.recording = recorder ? "on" : "stopped";
    s.recording_failures = report.recording_failures;
    std::string line = status_line(s);
    line += " heading=" + io.heading->status_token() +
            (localizer.heading_known() ? " heading_known=yes" : " heading_known=no");
    if (board_clock.last().epoch > 0) {  // the board's clock against the daemon's (board_clock.hpp)
      char clk[160];
      const BoardClockEstimate& c = board_clock.last();
      std::snprintf(clk, sizeof clk,
                    " clk_offset=%+.3fms clk_drift=%+.1fppm clk_sigma=%.2fms%s clk_resets=%llu",
                    c.offset_ms, c.drift_ppm, c.uncertainty_ms, c.converged ? "" : " clk=settling",
                    static_cast<unsigned long long>(board_clock.resets()));
      line += clk;
    }
    io.logger.info(line);
    if (io.observer.on_status) io.observer.on_status(line);
    windows_at_status = report.windows;
    frames_at_status = report.frames;
    status_from_ms = now_ms;
    next_status_ms = now_ms + config.status_period_s * 1000.0;
  }

  // --- control channel (control.hpp): requests are served between windows, a few per turn ---
  nlohmann::json apply(const control::Command& command) {
    using nlohmann::json;
    const auto fail = [&](const std::string& why) {
      return control::ControlError(std::nullopt,
                                   std::string(control::command_name(command)) + ": " + why);
    };
    if (std::holds_alternative<control::Status>(command)) return status_json();
    if (const auto* p = std::get_if<control::SetPose>(&command)) {
      const FieldGeometry& f = models.field;
      if (!placeable(f,
                     {p->x_cm, p->y_cm}))  // as for an initial pose: on the carpet, or just off it
        throw fail("(" + json(p->x_cm).dump() + ", " + json(p->y_cm).dump() +
                   ") cm is not on the carpet of field '" + f.name + "' (0 .. " +
                   json(f.total_x_cm()).dump() + " x 0 .. " + json(f.total_y_cm()).dump() +
                   " cm, 100 cm margin)");
      const Pose2 pose{p->x_cm, p->y_cm, wrap_deg(p->yaw_deg)};
      localizer.set_pose(pose, models.localizer.image_sigma_cm,
                         models.localizer.image_sigma_yaw_deg);
      last_localized = localizer.pose();
      io.logger.info("pose set by command to (" + json(pose.x_cm).dump() + ", " +
                     json(pose.y_cm).dump() + ") cm, " + json(pose.yaw_deg).dump() + " deg");
      return {
          {"x_cm", pose.x_cm}, {"y_cm", pose.y_cm}, {"yaw_deg", pose.yaw_deg}, {"last_seq", seq}};
    }
    if (const auto* s = std::get_if<control::SetSide>(&command)) {
      try {
        localizer.set_side(s->side == "blue" ? GoalColour::kBlue : GoalColour::kYellow);
      } catch (const std::invalid_argument& e) {
        throw fail(e.what());
      }
      io.logger.info("side set by command: defending the " + s->side +
                     " goal (decides the first fix's twin)");
      return {{"side", s->side}, {"has_fix", localizer.has_fix()}, {"last_seq", seq}};
    }
    if (std::holds_alternative<control::Relocalize>(command)) {
      localizer.force_global_search();
      io.logger.info("relocalizing by command: global search on the next frames");
      return {{"status", std::string(to_string(DaemonStatus::kLost))}, {"last_seq", seq}};
    }
    if (const auto* r = std::get_if<control::RecordStart>(&command)) {
      if (recorder) throw fail("already recording to " + record_dir);
      try {
        start_recording(r->dir, false);
      } catch (const std::exception& e) {
        throw fail(e.what());
      }
      io.logger.info("recording to " + r->dir + " (by command)");
      return {{"dir", r->dir}};
    }
    if (!recorder) throw fail("not recording");
    const std::string dir = record_dir;
    close_recording();
    io.logger.info("recording to " + dir + " stopped by command");
    return {{"dir", dir}};
  }

  nlohmann::json status_json() const {
    const double now = io.clock->now_ms();
    nlohmann::json j = {{"status", std::string(to_string(status(now)))},
                        {"x_cm", last_message.x_cm},
                        {"y_cm", last_message.y_cm},
                        {"yaw_deg", last_message.yaw_deg},
                        {"source", last_message.source},
                        {"windows", report.windows},
                        {"frames", report.frames},
                        {"published", publisher.sent()},
                        {"recording", recorder             ? "on"
                                      : record_dir.empty() ? "off"
                                                           : "stopped"},
                        {"heading", io.heading->describe()},
                        {"heading_known", localizer.heading_known()}};
    if (!record_dir.empty()) j["record_dir"] = record_dir;
    if (last_message.match_error) j["match_error"] = *last_message.match_error;
    if (last_message.uncertainty_cm) j["uncertainty_cm"] = *last_message.uncertainty_cm;
    return j;
  }

  void poll_control() {
    if (!control_socket) return;
    for (int i = 0; i < 8; ++i) {  // bounded: a flood of requests cannot starve the windows
      const auto d = control_socket->receive();
      if (!d) return;
      std::string reply;
      try {
        if (d->truncated)
          throw control::ControlError(std::nullopt, "request of " + std::to_string(d->size) +
                                                        " bytes is larger than " +
                                                        std::to_string(control::kMaxRequestBytes));
        const control::Request q = control::parse_request(d->text);
        try {
          reply = control::ok_reply(q.id, apply(q.command));
        } catch (const control::ControlError& e) {
          throw control::ControlError(q.id, e.what());
        }
      } catch (const control::ControlError& e) {
        reply = control::error_reply(e.id(), e.what());
      }
      io.logger.debug("control: " + d->text + " -> " + reply);
      control_socket->reply(*d, reply);
    }
  }

  // A session's first windows may be stale: the board streams on while the link is down, so
  // windows wait in the link for the session to open and arrive at once. The clock model takes
  // them all first (their lower envelope is the newest one), then gives each its time: on the very
  // first connection that anchors on the newest one, after a reconnect the line from before holds.
  void open_session(const SessionWindow& first, double arrival) {
    DaemonClock& clock = *io.clock;
    session_started = true;
    std::vector<SessionWindow> queued{first};
    while (queued.size() < kMaxQueuedAtOpen) {
      auto more = client->next_window(std::chrono::milliseconds(0));
      if (!more) break;
      queued.push_back(*more);
    }
    const double read_at = clock.now_ms();
    continue_board_time(queued.back(), read_at);
    for (std::size_t i = 0; i < queued.size(); ++i)
      (void)board_clock.add(scaled_board_ms(queued[i]), i == 0 ? arrival : read_at);
    for (const SessionWindow& q : queued) {
      BoardClockEstimate e = board_clock.map(scaled_board_ms(q));
      e.host_ms = std::min(e.host_ms, read_at);
      on_board_window(q, e);
    }
  }

  // The next window from the board, if one comes; a silent or failing board is let go (and the
  // degraded datagrams start at once).
  void read_board(double& next_degraded_ms) {
    DaemonClock& clock = *io.clock;
    try {
      if (const auto w = client->next_window(kTelemetryWait)) {
        const double arrival = clock.now_ms();
        if (!session_started)
          open_session(*w, arrival);
        else
          on_board_window(*w, board_clock.add(scaled_board_ms(*w), arrival));
      } else if (clock.now_ms() - last_window_clock_ms > kBoardSilentMs) {
        throw TransportError(TransportErrorKind::kIo, "no telemetry for 250 ms");
      }
    } catch (const TransportError& e) {
      lose_board(std::string(to_string(e.kind())) + ": " + e.what());
      next_degraded_ms = clock.now_ms();
    } catch (const BoardError& e) {
      lose_board(e.what());
      next_degraded_ms = clock.now_ms();
    }
  }

  // Without a board: a connection attempt when due, else the degraded datagrams (a consumer
  // tells "no board" / "board gone" from "daemon down" by them) and a wait. False while there is
  // still no board.
  bool connect_or_idle(double now, double start, double& next_degraded_ms) {
    try_connect(now);
    if (client) return true;
    if (now >= next_degraded_ms) {
      publish(last_localized, status(now), now, false);
      next_degraded_ms = now + kDegradedTickMs;
    }
    status_tick(now, start);
    io.clock->wait_ms(kDegradedTickMs);
    return false;
  }

  // Why the loop should stop now ("signal", "duration"), or null to go on.
  const char* stop_reason(const volatile std::sig_atomic_t* stop, double now, double start) const {
    if (stop && *stop) return "signal";
    if (config.duration_s > 0 && now - start >= config.duration_s * 1000.0) return "duration";
    return nullptr;
  }

  // The run's end: streaming off, the recording closed, the report's totals.
  DaemonReport finish_run(double start) {
    if (client) {
      if (const auto err = client->stop_streaming())
        io.logger.warning("could not switch streaming off: " + *err);
      count_link_errors();
    }
    close_recording();
    report.run_ms = io.clock->now_ms() - start;
    report.localizer = localizer.stats();
    report.published = publisher.sent();
    report.send_failed = publisher.failed();
    return report;
  }

  DaemonReport run(const volatile std::sig_atomic_t* stop) {
    DaemonClock& clock = *io.clock;
    const double start = clock.now_ms();
    next_status_ms = start + config.status_period_s * 1000.0;
    status_from_ms = start;
    next_attempt_ms = start;
    double next_degraded_ms = start;
    for (;;) {
      const double now = clock.now_ms();
      if (io.observer.on_loop) io.observer.on_loop(now);
      poll_control();
      if (const char* why = stop_reason(stop, now, start)) {
        report.stop_reason = why;
        break;
      }
      if (!client && !connect_or_idle(now, start, next_degraded_ms)) continue;
      read_board(next_degraded_ms);
      poll_camera(clock.now_ms());
      status_tick(clock.now_ms(), start);
    }
    return finish_run(start);
  }
};

std::string report_line(const DaemonReport& r) {
  char buf[320];
  std::snprintf(
      buf, sizeof buf,
      "stopped (%s) after %.1f s: %llu windows, %llu frames, %llu poses sent (%llu failed), "
      "board lost %llu x / back %llu x, camera lost %llu x, %llu bad CRC, %llu telemetry gaps%s",
      r.stop_reason.c_str(), r.run_ms / 1000.0, static_cast<unsigned long long>(r.windows),
      static_cast<unsigned long long>(r.frames), static_cast<unsigned long long>(r.published),
      static_cast<unsigned long long>(r.send_failed),
      static_cast<unsigned long long>(r.board_losses),
      static_cast<unsigned long long>(r.reconnects),
      static_cast<unsigned long long>(r.camera_losses), static_cast<unsigned long long>(r.bad_crc),
      static_cast<unsigned long long>(r.telemetry_gaps),
      r.recording_failures > 0 ? ", recording stopped on a write error" : "");
  return buf;
}

int exit_code(const DaemonReport& r) {
  return r.recording_failures > 0 ? kExitRecordingLost : 0;
}

std::string exit_reason(const DaemonReport& r) {
  if (exit_code(r) == 0) return {};
  return "exit " + std::to_string(kExitRecordingLost) + ": the recording to " + r.recording_dir +
         " stopped part-way on a write error (" + r.recording_error + ")";
}

Daemon::Daemon(const DaemonConfig& config, const DaemonModels& models, DaemonIo io) {
  validate_daemon_config(config, "daemon config");
  impl_ = std::make_unique<Impl>(config, models, std::move(io));
}

Daemon::~Daemon() = default;

DaemonReport Daemon::run(const volatile std::sig_atomic_t* stop) {
  return impl_->run(stop);
}

void Daemon::set_observer(DaemonObserver observer) {
  impl_->io.observer = std::move(observer);
}

nlohmann::json Daemon::apply(const control::Command& command) {
  return impl_->apply(command);
}

}  // namespace omniloc::daemon
