// `omniloc-sim demo`: the whole system on the simulated robot, no hardware. It is the robot's own
// daemon (omniloc/daemon.hpp, as `omnilocd-sim` runs it) on the simulated robot: the world
// simulator's quadrature waveforms drive the Verilated board at 12 MHz, frames rendered at the true
// pose go to the same Localizer, poses go out over UDP. An observer beside the daemon compares with
// the simulator's truth: a table of error over time for image only (the paper's global search at
// the gyro heading, recomputed from each frame), odometry only (dead reckoning from the true start)
// and the daemon's integrated pose, a summary, errors.csv and a PNG of the paths. A 30 s drive
// passes every boundary of the field, has a wheel slip and one kidnapping.
//
// Exit status: 0 when the daemon got a fix and, if the kidnapping falls inside the run, recovered
// from it; 1 otherwise (or when the simulation failed); 2 bad usage.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/daemon_config.hpp"
#include "omniloc/field.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/log.hpp"
#include "omniloc/matcher.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/vision.hpp"
#include "omniloc_sim/demo_drive.hpp"
#include "omniloc_sim/sim_daemon.hpp"

namespace omniloc::cli {
namespace {

using Clock = std::chrono::steady_clock;

double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct DemoOptions {
  std::string out_dir = "build/demo";
  double duration_s = 30.0;
  double camera_hz = 60.0;
  bool camera = true;
  std::uint64_t seed = 1;
  double table_period_s = 2.0;
};

// ---- statistics ----
struct Series {
  std::vector<double> values;
  void add(double v) { values.push_back(v); }
  [[nodiscard]] double mean() const {
    double s = 0;
    for (double v : values) s += v;
    return values.empty() ? NAN : s / static_cast<double>(values.size());
  }
  [[nodiscard]] double quantile(double q) const {
    if (values.empty()) return NAN;
    std::vector<double> v = values;
    std::sort(v.begin(), v.end());
    const double pos = q * static_cast<double>(v.size() - 1);
    const auto i = static_cast<std::size_t>(std::floor(pos));
    const double f = pos - static_cast<double>(i);
    return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
  }
  [[nodiscard]] double max() const {
    return values.empty() ? NAN : *std::max_element(values.begin(), values.end());
  }
};

double dist(const Pose2& a, const Pose2& b) {
  return std::hypot(a.x_cm - b.x_cm, a.y_cm - b.y_cm);
}
double dist(const Eigen::Vector2d& p, const Pose2& b) {
  return std::hypot(p.x() - b.x_cm, p.y() - b.y_cm);
}

// ---- plot ----
void write_plot(const std::string& path, const FieldGeometry& field,
                const std::vector<Pose2>& truth, const std::vector<Pose2>& integrated,
                const std::vector<Pose2>& odometry, const std::vector<Eigen::Vector2d>& image,
                const sim::DemoDrive& drive) {
  constexpr double kPxPerCm = 1.6;
  const int margin = 30;
  const int w = static_cast<int>(field.total_x_cm() * kPxPerCm) + 2 * margin;
  const int h = static_cast<int>(field.total_y_cm() * kPxPerCm) + 2 * margin + 40;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(40, 40, 40));
  auto px = [&](double x_cm, double y_cm) {
    // Field y grows upwards in the picture (v grows downwards).
    return cv::Point(
        margin + static_cast<int>(std::lround(x_cm * kPxPerCm)),
        margin + static_cast<int>(std::lround((field.total_y_cm() - y_cm) * kPxPerCm)));
  };
  // Carpet and the white lines, straight from the field model.
  const WhiteLineIndex lines(field);
  for (int v = 0; v < static_cast<int>(field.total_y_cm() * kPxPerCm); ++v) {
    for (int u = 0; u < static_cast<int>(field.total_x_cm() * kPxPerCm); ++u) {
      const Eigen::Vector2d p((u + 0.5) / kPxPerCm, field.total_y_cm() - (v + 0.5) / kPxPerCm);
      img.at<cv::Vec3b>(margin + v, margin + u) =
          lines.is_white(p) ? cv::Vec3b(235, 235, 235) : cv::Vec3b(40, 110, 40);
    }
  }
  auto polyline = [&](const std::vector<Pose2>& path, const cv::Scalar& colour, int thickness) {
    for (std::size_t i = 1; i < path.size(); ++i) {
      // A jump (kidnapping, relocalization) is not a path segment.
      if (dist(path[i], path[i - 1]) > 20.0) continue;
      cv::line(img, px(path[i - 1].x_cm, path[i - 1].y_cm), px(path[i].x_cm, path[i].y_cm), colour,
               thickness, cv::LINE_AA);
    }
  };
  for (const auto& p : image)
    cv::circle(img, px(p.x(), p.y()), 1, cv::Scalar(255, 0, 255), cv::FILLED);
  polyline(odometry, cv::Scalar(0, 200, 255), 2);
  polyline(truth, cv::Scalar(0, 0, 0), 3);
  polyline(integrated, cv::Scalar(0, 0, 255), 1);
  cv::circle(img, px(drive.kidnap_to.x_cm, drive.kidnap_to.y_cm), 8, cv::Scalar(255, 255, 0), 2);
  const int ty = h - 18;
  cv::putText(img,
              "truth (black)  integrated (red)  odometry only (orange)  image only (magenta dots)  "
              "kidnap drop (cyan)",
              cv::Point(margin, ty), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1,
              cv::LINE_AA);
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write " + path);
}

/// Watches the daemon: truth, the odometry-only and image-only baselines, the integrated pose.
class DemoObserver {
 public:
  DemoObserver(const daemon::DaemonModels& m, const sim::SimulatedRobot& robot,
               const DemoOptions& o, const sim::DemoDrive& drive, std::FILE* csv)
      : m_(m),
        robot_(robot),
        o_(o),
        csv_(csv),
        odometry_(m.robot),
        kidnap_ms_(drive.kidnap_s * 1000.0),
        next_table_ms_(o.table_period_s * 1000.0) {
    std::fprintf(csv_,
                 "t_ms,truth_x_cm,truth_y_cm,truth_yaw_deg,x_cm,y_cm,yaw_deg,source,error_cm,"
                 "odometry_error_cm\n");
  }

  daemon::DaemonObserver callbacks() {
    daemon::DaemonObserver o;
    o.on_window = [this](const EncoderWindow& w) { on_window(w); };
    o.on_frame = [this](const daemon::CameraFrame& f) { on_frame(f); };
    o.on_pose = [this](const daemon::PoseEvent& e) { on_pose(e); };
    return o;
  }

  void on_window(const EncoderWindow& w) {
    truth_ = robot_.truth().truth(w.t_end_ms);
    if (!truth_) return;
    truth_->yaw_deg = wrap_deg(truth_->yaw_deg);
    if (!odometry_started_) {
      odometry_.reset(*truth_);  // odometry only: from the known start pose, as in the paper
      odometry_started_ = true;
    } else {
      odometry_.update(w);
    }
    const Pose2 odo = odometry_.estimate().pose;
    e_odo_ = dist(odo, *truth_);
    err_odo.add(e_odo_);
    p_odo_.add(e_odo_);
    path_truth.push_back(*truth_);
    path_odo.push_back(odo);
  }

  /// The paper's image-only method on the same frame: global search at the gyro's heading.
  void on_frame(const daemon::CameraFrame& f) {
    ++frames_;
    const auto truth = robot_.truth().truth(f.t_ms);
    if (!truth) return;
    const double gyro_yaw = robot_.truth().gyro_yaw_at(f.t_ms);
    if (!extractor_) extractor_.emplace(m_.camera);
    ExtractionReport er;
    const BearingScan bearings = extractor_->extract(f.bgr, m_.localizer.scan_rays_per_degree, &er);
    if (!er.usable) return;                                      // no measurement: nothing to match
    const FieldScan scan = make_field_scan(bearings, gyro_yaw);  // rotated and prepared once
    MatchOptions mo;
    mo.refinement = Refinement::kInterpolate;
    MatchResult r = global_search(m_.db, scan, mo);
    if (r.cell < 0 || r.ambiguous) return;
    interpolate_match(m_.db, scan, r);
    const double e = dist(r.position_cm, *truth);
    err_img.add(e);
    p_img_.add(e);
    path_img.push_back(r.position_cm);
  }

  void on_pose(const daemon::PoseEvent& e) {
    if (!e.from_window || !truth_) return;
    const LocalizedPose& lp = e.localized;
    const double t = e.message.t_ms;
    double e_int = NAN;
    if (lp.source != PoseSource::kNone) {
      e_int = dist(lp.pose, *truth_);
      err_int.add(e_int);
      p_int_.add(e_int);
      int_by_time.emplace_back(t, e_int);
      yaw_int.add(std::abs(angle_diff_deg(lp.pose.yaw_deg, truth_->yaw_deg)));
      path_int.push_back(lp.pose);
      track_recovery(t, e_int);
    }
    std::fprintf(csv_, "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%s,%.3f,%.3f\n", t, truth_->x_cm,
                 truth_->y_cm, truth_->yaw_deg, lp.pose.x_cm, lp.pose.y_cm, lp.pose.yaw_deg,
                 pose_source_name(lp.source), e_int, e_odo_);
    if (t >= next_table_ms_ - 1e-6) {
      print_row(t, pose_source_name(lp.source));
      next_table_ms_ += o_.table_period_s * 1000.0;
    }
  }

  void print_header() const {
    std::printf(
        "\n  t [s] | image only [cm] | odometry only [cm] | integrated [cm] | source     | frames "
        "| wall [s] | board speed\n");
    std::printf(
        "  "
        "------+-----------------+--------------------+-----------------+------------+--------+----"
        "------+------------\n");
  }

  [[nodiscard]] double kidnap_ms() const { return kidnap_ms_; }
  [[nodiscard]] double recovered_ms() const { return recovered_ms_; }
  [[nodiscard]] int frames() const { return frames_; }

  Series err_int, err_odo, err_img, yaw_int;
  std::vector<std::pair<double, double>>
      int_by_time;  // (t_ms, error): to leave out the kidnap recovery
  std::vector<Pose2> path_truth, path_int, path_odo;
  std::vector<Eigen::Vector2d> path_img;

 private:
  /// Recovered: from the first time after the kidnapping the error stays below 10 cm for 0.5 s.
  void track_recovery(double t, double e_int) {
    if (t <= kidnap_ms_ || recovered_ms_ >= 0) return;
    if (e_int >= 10.0) {
      below_since_ms_ = -1;
      return;
    }
    if (below_since_ms_ < 0) below_since_ms_ = t;
    if (t - below_since_ms_ >= 500.0) recovered_ms_ = below_since_ms_;
  }

  void print_row(double t, const char* source) {
    auto cell = [](const Series& s) {
      char b[32];
      if (s.values.empty())
        std::snprintf(b, sizeof b, "%15s", "-");
      else
        std::snprintf(b, sizeof b, "%6.1f (max %5.1f)", s.mean(), s.max());
      return std::string(b);
    };
    const double wall = std::chrono::duration<double>(Clock::now() - wall0_).count();
    const double speed = wall > 0 ? static_cast<double>(robot_.board_cycles()) / wall : 0.0;
    std::printf("  %5.1f | %s | %18s | %s | %-10s | %6d | %8.1f | %4.1f Mcyc/s\n", t / 1000.0,
                cell(p_img_).c_str(), cell(p_odo_).c_str(), cell(p_int_).c_str(), source, frames_,
                wall, speed / 1e6);
    std::fflush(stdout);
    p_img_ = p_odo_ = p_int_ = Series{};
  }

  const daemon::DaemonModels& m_;
  const sim::SimulatedRobot& robot_;
  const DemoOptions& o_;
  std::FILE* csv_;
  Odometry odometry_;
  bool odometry_started_ = false;
  std::optional<Pose2> truth_;  // at the current window
  double e_odo_ = NAN;
  Series p_int_, p_odo_, p_img_;  // per table period
  int frames_ = 0;
  std::optional<LineExtractor>
      extractor_;  // the paper path extracts its own lines (adapts per frame)
  double kidnap_ms_;
  double recovered_ms_ = -1;
  double below_since_ms_ = -1;
  double next_table_ms_;
  Clock::time_point wall0_ = Clock::now();
};

void print_summary(const DemoObserver& ob, const sim::DemoDrive& drive, const DemoOptions& o,
                   const daemon::DaemonReport& r) {
  std::printf("\n  mean / median / p95 / max position error over the run [cm]:\n");
  auto row = [](const char* name, const Series& s) {
    std::printf("    %-14s %6.2f / %6.2f / %6.2f / %6.2f   (%zu samples)\n", name, s.mean(),
                s.quantile(0.5), s.quantile(0.95), s.max(), s.values.size());
  };
  row("image only", ob.err_img);
  row("odometry only", ob.err_odo);
  row("integrated", ob.err_int);
  if (ob.recovered_ms() >= 0) {
    Series steady;
    for (const auto& [t, e] : ob.int_by_time)
      if (t < ob.kidnap_ms() || t >= ob.recovered_ms()) steady.add(e);
    row("integrated*", steady);
    std::printf("    (* without the %.2f s from the kidnapping to the recovery)\n",
                (ob.recovered_ms() - ob.kidnap_ms()) / 1000.0);
  }
  std::printf("    integrated yaw error [deg]: mean %.2f, p95 %.2f, max %.2f\n", ob.yaw_int.mean(),
              ob.yaw_int.quantile(0.95), ob.yaw_int.max());
  if (ob.kidnap_ms() >= o.duration_s * 1000.0)
    std::printf("  kidnapping at %.2f s: after the end of this run\n", drive.kidnap_s);
  else if (ob.recovered_ms() >= 0)
    std::printf(
        "  kidnapping at %.2f s: integrated error below 10 cm for good (0.5 s) from %.2f s: "
        "recovery %.2f s\n",
        drive.kidnap_s, ob.recovered_ms() / 1000.0, (ob.recovered_ms() - ob.kidnap_ms()) / 1000.0);
  else
    std::printf(
        "  kidnapping at %.2f s: NOT recovered (integrated error never stayed below 10 cm for 0.5 "
        "s)\n",
        drive.kidnap_s);
  const LocalizerStats& ls = r.localizer;
  std::printf(
      "  localizer: %d frames, %d accepted, %d rejected, %d ambiguous, %d global searches, %d "
      "relocalizations, "
      "%d lost events\n",
      ls.frames, ls.accepted, ls.rejected, ls.ambiguous, ls.global_searches, ls.relocalizations,
      ls.lost_events);
  std::printf("  daemon: %s\n", daemon::report_line(r).c_str());
}

/// The demo's verdict: 0 fixed by the camera (and recovered from a kidnapping inside the run), 1
/// otherwise.
int verdict(const DemoObserver& ob, const DemoOptions& o, const daemon::DaemonReport& r) {
  // The start pose alone is not a fix: the camera must have confirmed it at least once.
  if (ob.err_int.values.empty() || r.localizer.accepted == 0) {
    std::printf("demo: FAILED: the daemon never had a fix from the camera\n");
    return 1;
  }
  if (ob.kidnap_ms() < o.duration_s * 1000.0 && ob.recovered_ms() < 0) {
    std::printf("demo: FAILED: the kidnapping was not recovered\n");
    return 1;
  }
  return 0;
}

// The simulated robot of the demo drive: its seed and camera, a slip of wheel 2 and a kidnapping
// where the drive puts them.
sim::SimRobotOptions demo_robot_options(const DemoOptions& o, const sim::DemoDrive& drive) {
  sim::SimRobotOptions so;
  so.seed = o.seed;
  so.camera = o.camera;
  so.camera_fps = o.camera_hz;
  so.slips.push_back(sim::SlipEvent{2, drive.slip_s, 0.5, 40.0});
  so.kidnaps.push_back(sim::KidnapEvent{drive.kidnap_s, drive.kidnap_to});
  return so;
}

// What is about to run: the robot, the camera, the seed and the drive's events.
void print_demo_plan(double ready_s, const DemoOptions& o, const sim::SimulatedRobot& robot,
                     const sim::DemoDrive& drive) {
  std::printf(
      "demo: database ready after %.1f s; simulating %.0f s with the robot's daemon: %s; camera "
      "%.0f Hz, "
      "seed %llu\n",
      ready_s, o.duration_s, robot.describe().c_str(), o.camera ? o.camera_hz : 0.0,
      static_cast<unsigned long long>(o.seed));
  std::printf(
      "demo: drive of %.0f cm: slip of wheel 2 at %.1f s (0.5 s, +40 cm/s), kidnapping at %.2f s "
      "to "
      "(%.0f, %.0f, %.0f deg)\n",
      drive.trajectory.length_cm(), drive.slip_s, drive.kidnap_s, drive.kidnap_to.x_cm,
      drive.kidnap_to.y_cm, drive.kidnap_to.yaw_deg);
}

// How fast the simulation ran: board cycles per wall second, frames rendered, CPU time.
template <typename Elapsed>
void print_throughput(const sim::SimulatedRobot& robot, const DemoObserver& observer,
                      const Elapsed& elapsed, double cpu_s) {
  const double board_s = static_cast<double>(robot.board_cycles()) / sim::BoardSim::kClockHz;
  std::printf(
      "  board: %.0f M cycles (%.1f s simulated) in %.1f s wall, %.2f M cycles/s; %d frames "
      "rendered\n",
      static_cast<double>(robot.board_cycles()) / 1e6, board_s, elapsed(),
      static_cast<double>(robot.board_cycles()) / 1e6 / std::max(1e-9, elapsed()),
      observer.frames());
  std::printf(
      "  CPU time of the run: %.1f s (board, daemon and observer on one thread, rendering on the "
      "camera's worker)\n",
      cpu_s);
}

int run_demo(const DemoOptions& o) {
  const auto wall0 = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - wall0).count(); };
  std::filesystem::create_directories(o.out_dir);

  daemon::DaemonConfig dc;  // the daemon's defaults: FIRA field, default camera/robot/localizer
  dc.duration_s = o.duration_s;
  dc.camera_fps = o.camera_hz;
  dc.status_period_s = 0;  // the table below says more
  std::printf("demo: building the feature database ...\n");
  std::fflush(stdout);
  daemon::DaemonModels m = daemon::load_models(dc);
  const sim::DemoDrive drive = sim::demo_drive(30.0);
  // The team places the robot at its start pose and tells the daemon, as at a kick-off: the board's
  // gyro is relative (docs/GYRO.md), and on the point-symmetric field a global search without a
  // heading cannot tell the robot from its twin.
  m.initial_pose = drive.trajectory.start();
  sim::SimulatedRobot robot(m, drive.trajectory, demo_robot_options(o, drive));
  print_demo_plan(elapsed(), o, robot, drive);

  const std::string csv_path = o.out_dir + "/errors.csv";
  std::FILE* csv = std::fopen(csv_path.c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + csv_path);
  DemoObserver observer(m, robot, o, drive, csv);
  daemon::DaemonIo io = robot.io();
  io.observer = observer.callbacks();
  io.logger = Logger(LogLevel::kInfo, [](LogLevel level, std::string_view s) {
    std::printf("  [daemon] %s\n", format_log_line("omnilocd", level, s).c_str());
  });
  daemon::Daemon d(dc, m, io);
  observer.print_header();
  const double cpu0 = process_cpu_s();
  const daemon::DaemonReport r = d.run(nullptr);
  const double cpu_s = process_cpu_s() - cpu0;
  const bool csv_ok = std::ferror(csv) == 0;
  if (std::fclose(csv) != 0 || !csv_ok) throw std::runtime_error(csv_path + ": write failed");

  print_summary(observer, drive, o, r);
  print_throughput(robot, observer, elapsed, cpu_s);
  const std::string png = o.out_dir + "/paths.png";
  write_plot(png, m.field, observer.path_truth, observer.path_int, observer.path_odo,
             observer.path_img, drive);
  std::printf("  wrote %s and %s; total wall time %.1f s\n", png.c_str(), csv_path.c_str(),
              elapsed());
  return verdict(observer, o, r);
}

}  // namespace

Subcommand add_demo(CLI::App& program) {
  CLI::App* demo = program.add_subcommand(
      "demo", "the robot's daemon on the simulated robot: 30 s drive, error table, paths.png");
  demo->footer(
      "The robot's daemon on the simulated robot (Verilated board, rendered camera), watched "
      "against the\n"
      "simulator's truth. Exit status: 0 fix and kidnapping recovered, 1 no fix / not recovered / "
      "failure,\n"
      "2 bad usage.");
  auto o = std::make_shared<DemoOptions>();
  demo->add_option("--out", o->out_dir, "output directory for paths.png and errors.csv")
      ->capture_default_str();
  add_number_option(*demo, "--camera-hz", o->camera_hz,
                    "rendered camera rate in simulated time (the paper's: 60)", 1.0, 120.0);
  demo->add_option_function<std::string>(
          "--camera", [o](const std::string&) { o->camera = false; },
          "none: no camera (no fix: the run fails, exit status 1)")
      ->check(CLI::IsMember({"none"}))
      ->default_str("rendered");
  add_number_option(*demo, "--seed", o->seed, "world and sensor noise seed");
  add_number_option(*demo, "--duration", o->duration_s,
                    "simulated seconds (the scripted drive lasts 30)", 0.01, 30.0);
  return {demo, [o] { return run_demo(*o); }};
}

}  // namespace omniloc::cli
