// `omniloc demo`: the whole system on the simulated robot, no hardware. The world simulator's
// quadrature waveforms drive the Verilated board (BoardSim) at 12 MHz; the host library talks to it
// through SimTransport + BoardClient with streamed telemetry; frames rendered at the true pose are
// scanned and fed to the same Localizer omnilocd runs. A 30 s drive passes every boundary of the
// field, has a wheel slip and one kidnapping. Prints a table of error over time for image only,
// odometry only and integrated, a summary, and writes a PNG of the paths.
//
// Three threads, because the Verilated board alone needs about one core for real time x 2.4: the
// board thread (simulation + link + truth), the vision thread (render, scan, image-only search) and
// the main thread (localizer, odometry baseline, statistics), joined by queues in time order.
#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.hpp"
#include "omniloc/board_client.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/daemon_board_sim.hpp"
#include "omniloc/daemon_sim.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/matcher.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/protocol.hpp"
#include "omniloc/regmap.hpp"
#include "omniloc_sim/renderer.hpp"

namespace omniloc::cli {
namespace {

using Clock = std::chrono::steady_clock;

/// CPU seconds the calling thread has used: with other work on the machine, wall time says little;
/// the per-thread CPU times show what an otherwise idle 2-core machine would take.
double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct DemoOptions {
  std::string out_dir = "build/demo";
  double duration_s = 30.0;
  double camera_hz = 60.0;
  std::uint64_t seed = 1;
  double table_period_s = 2.0;
};

void demo_usage(std::FILE* out) {
  std::fprintf(out,
               "usage: omniloc demo [--out DIR] [--camera-hz HZ] [--seed N] [--duration S]\n"
               "  The whole system on the simulated robot (Verilated board, rendered camera, localizer).\n"
               "  --out        output directory for paths.png and errors.csv (default build/demo)\n"
               "  --camera-hz  rendered camera rate in simulated time (default 60, the paper's)\n"
               "  --seed       world and sensor noise seed (default 1)\n"
               "  --duration   simulated seconds (default 30; the scripted drive lasts 30)\n");
}

using Drive = daemon::DemoDrive;

Drive make_drive(double duration_s) { return daemon::demo_drive(duration_s); }

template <typename T>
class Queue {
 public:
  void push(T v) {
    {
      std::lock_guard l(mu_);
      q_.push_back(std::move(v));
    }
    cv_.notify_all();
  }
  /// Blocks; nullopt when closed and empty.
  std::optional<T> pop() {
    std::unique_lock l(mu_);
    cv_.wait(l, [&] { return !q_.empty() || closed_; });
    if (q_.empty()) return std::nullopt;
    T v = std::move(q_.front());
    q_.pop_front();
    return v;
  }
  void close() {
    {
      std::lock_guard l(mu_);
      closed_ = true;
    }
    cv_.notify_all();
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<T> q_;
  bool closed_ = false;
};

struct WindowItem {
  EncoderWindow window;
  Pose2 truth;
  double board_cycles_per_s = 0.0;  // simulation speed so far (for progress lines)
};
struct FrameJob {
  int index = 0;
  double t_ms = 0.0;
  Pose2 truth;
  double gyro_yaw_deg = 0.0;
};
struct FrameResult {
  int index = 0;
  double t_ms = 0.0;
  Pose2 truth;
  BearingScan bearings;
  MatchResult image_only;  // global search with the gyro's heading (the paper's image-only method)
  double render_ms = 0.0, scan_ms = 0.0;
};

// ---- board thread ----
struct BoardStats {
  double cpu_s = 0.0;
  std::int64_t cycles = 0;
  double wall_s = 0.0;
  std::uint64_t windows = 0;
  std::uint64_t crc_errors = 0;
  std::uint64_t seq_gaps = 0;
  std::string error;
};

void board_thread(const daemon::DaemonModels& m, const Drive& drive, const DemoOptions& o, Queue<WindowItem>& windows,
                  Queue<FrameJob>& jobs, BoardStats& stats) {
  const auto t0 = Clock::now();
  try {
    auto wc = daemon::board_world_config(m.robot, o.seed);
    wc.slips.push_back(sim::SlipEvent{2, drive.slip_s, 0.5, 40.0});
    wc.kidnaps.push_back(sim::KidnapEvent{drive.kidnap_s, drive.kidnap_to});
    daemon::VerilatedRobot robot(wc, drive.trajectory);
    sim::SimTransport transport(robot.board);
    BoardClient client(transport);
    if (client.read_register(regmap::kRegId) != regmap::kIdValue) throw std::runtime_error("board ID mismatch");
    std::uint32_t control = 0;
    control = regmap::kControlEnable.put(control, 1);
    control = regmap::kControlDecode.put(control, regmap::kControlDecodeX4);
    control = regmap::kControlStream.put(control, 1);
    client.write_register(regmap::kRegControl, control);
    protocol::TimestampUnwrapper unwrap(static_cast<double>(sim::BoardSim::kClockHz));
    std::optional<double> first_ms;
    const double frame_period_ms = 1000.0 / o.camera_hz;
    int next_frame = 1;
    while (robot.board.seconds() < o.duration_s) {
      const auto w = client.poll_telemetry(std::chrono::milliseconds(100));
      if (!w) throw std::runtime_error("no telemetry from the Verilated board for 100 ms of board time");
      unwrap.update(w->timestamp_cycles);
      if (!first_ms) first_ms = w->timestamp_cycles * 1000.0 / sim::BoardSim::kClockHz;
      const double t = *first_ms + unwrap.elapsed_ms();
      // Frames whose time the truth log has reached go to the vision thread first, so that the
      // main thread, given this window, knows every frame before it is on its way.
      while (next_frame * frame_period_ms <= robot.log.latest_ms()) {
        const double tf = next_frame * frame_period_ms;
        EncoderWindow probe;
        probe.t_end_ms = tf;
        // Always queued (the main thread counts on every index): truth exists for tf <= latest.
        jobs.push(FrameJob{next_frame, tf, robot.log.truth(tf).value_or(robot.stream.world().truth()),
                           robot.log.gyro_yaw_deg(probe)});
        ++next_frame;
      }
      WindowItem item;
      item.window.seq = w->seq;
      item.window.t_end_ms = t;
      for (std::size_t i = 0; i < 4; ++i) item.window.counts[i] = w->count[i];
      item.window.gyro_yaw_deg = robot.log.gyro_yaw_deg(item.window);
      item.truth = robot.log.truth(t).value_or(robot.stream.world().truth());
      item.truth.yaw_deg = wrap_deg(item.truth.yaw_deg);
      const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
      item.board_cycles_per_s = wall > 0 ? static_cast<double>(robot.board.cycle()) / wall : 0.0;
      windows.push(item);
      ++stats.windows;
    }
    stats.cycles = robot.board.cycle();
    stats.crc_errors = client.decoder_counters().bad_crc;
    stats.seq_gaps = client.decoder_counters().telemetry_gaps;
  } catch (const std::exception& e) {
    stats.error = e.what();
  }
  stats.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  stats.cpu_s = thread_cpu_s();
  jobs.close();
  windows.close();
}

// ---- vision thread ----
void vision_thread(const daemon::DaemonModels& m, const DemoOptions& o, Queue<FrameJob>& jobs, Queue<FrameResult>& results,
                   double& cpu_s) {
  const sim::OmniRenderer renderer(m.field, m.camera);
  MatchOptions mo;
  mo.refinement = Refinement::kInterpolate;
  while (auto job = jobs.pop()) {
    FrameResult r;
    r.index = job->index;
    r.t_ms = job->t_ms;
    r.truth = job->truth;
    sim::RenderOptions ro;
    ro.seed = o.seed * 100'003 + static_cast<std::uint64_t>(job->index);
    const auto a = Clock::now();
    const cv::Mat bgr = renderer.render(job->truth, ro);
    const auto b = Clock::now();
    r.bearings = scan_image_bearings(bgr, m.camera, m.localizer.scan_rays_per_degree);
    const auto c = Clock::now();
    const Scan scan = rotate_to_field(r.bearings, job->gyro_yaw_deg);
    r.image_only = global_search(m.db, scan, mo);
    if (r.image_only.cell >= 0) interpolate_match(m.db, scan, r.image_only);
    r.render_ms = std::chrono::duration<double, std::milli>(b - a).count();
    r.scan_ms = std::chrono::duration<double, std::milli>(c - b).count();
    results.push(std::move(r));
  }
  cpu_s = thread_cpu_s();
  results.close();
}

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
  [[nodiscard]] double max() const { return values.empty() ? NAN : *std::max_element(values.begin(), values.end()); }
};

double dist(const Pose2& a, const Pose2& b) { return std::hypot(a.x_cm - b.x_cm, a.y_cm - b.y_cm); }
double dist(const Eigen::Vector2d& p, const Pose2& b) { return std::hypot(p.x() - b.x_cm, p.y() - b.y_cm); }

// ---- plot ----
void write_plot(const std::string& path, const FieldGeometry& field, const std::vector<Pose2>& truth,
                const std::vector<Pose2>& integrated, const std::vector<Pose2>& odometry,
                const std::vector<Eigen::Vector2d>& image, const Drive& drive) {
  constexpr double kPxPerCm = 1.6;
  const int margin = 30;
  const int w = static_cast<int>(field.total_x_cm() * kPxPerCm) + 2 * margin;
  const int h = static_cast<int>(field.total_y_cm() * kPxPerCm) + 2 * margin + 40;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(40, 40, 40));
  auto px = [&](double x_cm, double y_cm) {
    // Field y grows upwards in the picture (v grows downwards).
    return cv::Point(margin + static_cast<int>(std::lround(x_cm * kPxPerCm)),
                     margin + static_cast<int>(std::lround((field.total_y_cm() - y_cm) * kPxPerCm)));
  };
  // Carpet and the white lines, straight from the field model.
  const WhiteLineIndex lines(field);
  for (int v = 0; v < static_cast<int>(field.total_y_cm() * kPxPerCm); ++v) {
    for (int u = 0; u < static_cast<int>(field.total_x_cm() * kPxPerCm); ++u) {
      const Eigen::Vector2d p((u + 0.5) / kPxPerCm, field.total_y_cm() - (v + 0.5) / kPxPerCm);
      img.at<cv::Vec3b>(margin + v, margin + u) = lines.is_white(p) ? cv::Vec3b(235, 235, 235) : cv::Vec3b(40, 110, 40);
    }
  }
  auto polyline = [&](const std::vector<Pose2>& path, const cv::Scalar& colour, int thickness) {
    for (std::size_t i = 1; i < path.size(); ++i) {
      // A jump (kidnapping, relocalization) is not a path segment.
      if (dist(path[i], path[i - 1]) > 20.0) continue;
      cv::line(img, px(path[i - 1].x_cm, path[i - 1].y_cm), px(path[i].x_cm, path[i].y_cm), colour, thickness,
               cv::LINE_AA);
    }
  };
  for (const auto& p : image) cv::circle(img, px(p.x(), p.y()), 1, cv::Scalar(255, 0, 255), cv::FILLED);
  polyline(odometry, cv::Scalar(0, 200, 255), 2);
  polyline(truth, cv::Scalar(0, 0, 0), 3);
  polyline(integrated, cv::Scalar(0, 0, 255), 1);
  cv::circle(img, px(drive.kidnap_to.x_cm, drive.kidnap_to.y_cm), 8, cv::Scalar(255, 255, 0), 2);
  const int ty = h - 18;
  cv::putText(img, "truth (black)  integrated (red)  odometry only (orange)  image only (magenta dots)  kidnap drop (cyan)",
              cv::Point(margin, ty), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  if (!cv::imwrite(path, img)) throw std::runtime_error("cannot write " + path);
}

}  // namespace

int cmd_demo(std::span<const std::string_view> args) {
  DemoOptions o;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (a == "-h" || a == "--help") {
      demo_usage(stdout);
      return 0;
    }
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "omniloc demo: %.*s needs a value\n", static_cast<int>(a.size()), a.data());
      demo_usage(stderr);
      return 2;
    }
    const std::string v(args[++i]);
    char* end = nullptr;
    const double num = std::strtod(v.c_str(), &end);
    const bool is_num = !v.empty() && end == v.c_str() + v.size();
    if (a == "--out") {
      o.out_dir = v;
    } else if (a == "--camera-hz" && is_num && num > 0 && num <= 120) {
      o.camera_hz = num;
    } else if (a == "--seed" && is_num && num >= 0) {
      o.seed = static_cast<std::uint64_t>(num);
    } else if (a == "--duration" && is_num && num > 0 && num <= 30) {
      o.duration_s = num;
    } else {
      std::fprintf(stderr, "omniloc demo: bad option %.*s %s\n", static_cast<int>(a.size()), a.data(), v.c_str());
      demo_usage(stderr);
      return 2;
    }
  }
  const auto wall0 = Clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - wall0).count(); };
  std::filesystem::create_directories(o.out_dir);

  daemon::DaemonConfig dc;  // the daemon's defaults: FIRA field, default camera/robot/localizer
  std::printf("demo: building the feature database ...\n");
  std::fflush(stdout);
  const daemon::DaemonModels m = daemon::load_models(dc);
  std::printf("demo: database ready after %.1f s; simulating %.0f s: Verilated board at 12 MHz (%.0f M cycles), "
              "camera %.0f Hz, seed %llu\n",
              elapsed(), o.duration_s, o.duration_s * 12.0, o.camera_hz, static_cast<unsigned long long>(o.seed));
  const Drive drive = make_drive(30.0);
  std::printf("demo: drive of %.0f cm: slip of wheel 2 at %.1f s (0.5 s, +40 cm/s), kidnapping at %.2f s to "
              "(%.0f, %.0f, %.0f deg)\n",
              drive.trajectory.length_cm(), drive.slip_s, drive.kidnap_s, drive.kidnap_to.x_cm, drive.kidnap_to.y_cm,
              drive.kidnap_to.yaw_deg);

  Queue<WindowItem> windows;
  Queue<FrameJob> jobs;
  Queue<FrameResult> results;
  BoardStats bstats;
  std::thread bt(board_thread, std::cref(m), std::cref(drive), std::cref(o), std::ref(windows), std::ref(jobs),
                 std::ref(bstats));
  double vision_cpu_s = 0.0;
  const double main_cpu0_s = thread_cpu_s();
  std::thread vt(vision_thread, std::cref(m), std::cref(o), std::ref(jobs), std::ref(results), std::ref(vision_cpu_s));

  Localizer localizer(m.localizer, m.robot, m.field, m.camera, m.db);
  Odometry odometry(m.robot);
  bool odometry_started = false;
  std::deque<FrameResult> ready;
  bool results_open = true;
  int frames_used = 0;
  int last_frame_index = 0;
  const double frame_period_ms = 1000.0 / o.camera_hz;
  double render_ms = 0, scan_ms = 0;

  Series err_int, err_odo, err_img, yaw_int;
  std::vector<std::pair<double, double>> int_by_time;  // (t_ms, error): to leave out the kidnap recovery
  Series p_int, p_odo, p_img;  // per table period
  std::vector<Pose2> path_truth, path_int, path_odo;
  std::vector<Eigen::Vector2d> path_img;
  double next_table_ms = o.table_period_s * 1000.0;
  double recovered_ms = -1;  // first time after the kidnapping from which the error stays < 10 cm
  double below_since_ms = -1;
  const double kidnap_ms = drive.kidnap_s * 1000.0;
  std::FILE* csv = std::fopen((o.out_dir + "/errors.csv").c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + o.out_dir + "/errors.csv");
  std::fprintf(csv, "t_ms,truth_x_cm,truth_y_cm,truth_yaw_deg,x_cm,y_cm,yaw_deg,source,error_cm,odometry_error_cm\n");

  std::printf("\n  t [s] | image only [cm] | odometry only [cm] | integrated [cm] | source     | frames | wall [s] | board speed\n");
  std::printf("  ------+-----------------+--------------------+-----------------+------------+--------+----------+------------\n");
  double last_speed = 0;
  while (auto item = windows.pop()) {
    const EncoderWindow& w = item->window;
    // Every frame up to this window's time has been queued (the board thread queues frames before
    // the window that covers them): wait for their results, in order.
    while (results_open && (last_frame_index + 1) * frame_period_ms <= w.t_end_ms) {
      auto r = results.pop();
      if (!r) {
        results_open = false;
        break;
      }
      last_frame_index = r->index;
      ready.push_back(std::move(*r));
    }
    while (!ready.empty() && ready.front().t_ms <= w.t_end_ms) {
      FrameResult& r = ready.front();
      (void)localizer.on_bearings(r.t_ms, std::move(r.bearings));
      if (r.image_only.cell >= 0 && !r.image_only.ambiguous) {
        const double e = dist(r.image_only.position_cm, r.truth);
        err_img.add(e);
        p_img.add(e);
        path_img.push_back(r.image_only.position_cm);
      }
      render_ms += r.render_ms;
      scan_ms += r.scan_ms;
      ++frames_used;
      ready.pop_front();
    }
    const LocalizedPose lp = localizer.on_window(w);
    if (!odometry_started) {
      odometry.reset(item->truth);  // odometry only: from the known start pose, as in the paper
      odometry_started = true;
    } else {
      odometry.update(w);
    }
    const Pose2 odo = odometry.estimate().pose;
    const double e_odo = dist(odo, item->truth);
    err_odo.add(e_odo);
    p_odo.add(e_odo);
    path_truth.push_back(item->truth);
    path_odo.push_back(odo);
    double e_int = NAN;
    if (lp.source != PoseSource::kNone) {
      e_int = dist(lp.pose, item->truth);
      err_int.add(e_int);
      p_int.add(e_int);
      int_by_time.emplace_back(w.t_end_ms, e_int);
      yaw_int.add(std::abs(angle_diff_deg(lp.pose.yaw_deg, item->truth.yaw_deg)));
      path_int.push_back(lp.pose);
      if (w.t_end_ms > kidnap_ms && recovered_ms < 0) {
        if (e_int < 10.0) {
          if (below_since_ms < 0) below_since_ms = w.t_end_ms;
          if (w.t_end_ms - below_since_ms >= 500.0) recovered_ms = below_since_ms;
        } else {
          below_since_ms = -1;
        }
      }
    }
    std::fprintf(csv, "%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%s,%.3f,%.3f\n", w.t_end_ms, item->truth.x_cm,
                 item->truth.y_cm, item->truth.yaw_deg, lp.pose.x_cm, lp.pose.y_cm, lp.pose.yaw_deg,
                 pose_source_name(lp.source), e_int, e_odo);
    last_speed = item->board_cycles_per_s;
    if (w.t_end_ms >= next_table_ms - 1e-6) {
      auto cell = [](const Series& s) {
        char b[32];
        if (s.values.empty()) std::snprintf(b, sizeof b, "%15s", "-");
        else std::snprintf(b, sizeof b, "%6.1f (max %5.1f)", s.mean(), s.max());
        return std::string(b);
      };
      std::printf("  %5.1f | %s | %18s | %s | %-10s | %6d | %8.1f | %4.1f Mcyc/s\n", w.t_end_ms / 1000.0,
                  cell(p_img).c_str(), cell(p_odo).c_str(), cell(p_int).c_str(), pose_source_name(lp.source),
                  frames_used, elapsed(), last_speed / 1e6);
      std::fflush(stdout);
      p_img = p_odo = p_int = Series{};
      next_table_ms += o.table_period_s * 1000.0;
    }
  }
  bt.join();
  while (results.pop()) {
  }
  vt.join();
  std::fclose(csv);
  if (!bstats.error.empty()) {
    std::fprintf(stderr, "omniloc demo: board simulation failed: %s\n", bstats.error.c_str());
    return 1;
  }

  std::printf("\n  mean / median / p95 / max position error over the run [cm]:\n");
  auto row = [](const char* name, const Series& s) {
    std::printf("    %-14s %6.2f / %6.2f / %6.2f / %6.2f   (%zu samples)\n", name, s.mean(), s.quantile(0.5),
                s.quantile(0.95), s.max(), s.values.size());
  };
  row("image only", err_img);
  row("odometry only", err_odo);
  row("integrated", err_int);
  if (recovered_ms >= 0) {
    Series steady;
    for (const auto& [t, e] : int_by_time)
      if (t < kidnap_ms || t >= recovered_ms) steady.add(e);
    row("integrated*", steady);
    std::printf("    (* without the %.2f s from the kidnapping to the recovery)\n", (recovered_ms - kidnap_ms) / 1000.0);
  }
  std::printf("    integrated yaw error [deg]: mean %.2f, p95 %.2f, max %.2f\n", yaw_int.mean(), yaw_int.quantile(0.95),
              yaw_int.max());
  if (kidnap_ms >= o.duration_s * 1000.0)
    std::printf("  kidnapping at %.2f s: after the end of this run\n", drive.kidnap_s);
  else if (recovered_ms >= 0)
    std::printf("  kidnapping at %.2f s: integrated error below 10 cm for good (0.5 s) from %.2f s: recovery %.2f s\n",
                drive.kidnap_s, recovered_ms / 1000.0, (recovered_ms - kidnap_ms) / 1000.0);
  else
    std::printf("  kidnapping at %.2f s: NOT recovered (integrated error never stayed below 10 cm for 0.5 s)\n",
                drive.kidnap_s);
  const LocalizerStats& ls = localizer.stats();
  std::printf("  localizer: %d frames, %d accepted, %d rejected, %d ambiguous, %d global searches, %d relocalizations, "
              "%d lost events\n",
              ls.frames, ls.accepted, ls.rejected, ls.ambiguous, ls.global_searches, ls.relocalizations, ls.lost_events);
  std::printf("  board: %.0f M cycles in %.1f s wall (%.2f M cycles/s, %.2fx real time), %llu windows, %llu CRC errors, "
              "%llu telemetry gaps\n",
              static_cast<double>(bstats.cycles) / 1e6, bstats.wall_s,
              static_cast<double>(bstats.cycles) / 1e6 / bstats.wall_s,
              static_cast<double>(bstats.cycles) / sim::BoardSim::kClockHz / bstats.wall_s,
              static_cast<unsigned long long>(bstats.windows), static_cast<unsigned long long>(bstats.crc_errors),
              static_cast<unsigned long long>(bstats.seq_gaps));
  std::printf("  vision: %d frames, render %.1f ms + scan %.1f ms per frame (vision thread)\n", frames_used,
              frames_used ? render_ms / frames_used : 0.0, frames_used ? scan_ms / frames_used : 0.0);
  const double main_cpu_s = thread_cpu_s() - main_cpu0_s;
  std::printf("  CPU time: board thread %.1f s, vision thread %.1f s, localizer (main) thread %.1f s; on an idle\n"
              "  2-core machine the run takes about max(board, vision + localizer) = %.1f s after the database\n",
              bstats.cpu_s, vision_cpu_s, main_cpu_s, std::max(bstats.cpu_s, vision_cpu_s + main_cpu_s));
  const std::string png = o.out_dir + "/paths.png";
  write_plot(png, m.field, path_truth, path_int, path_odo, path_img, drive);
  std::printf("  wrote %s and %s/errors.csv; total wall time %.1f s\n", png.c_str(), o.out_dir.c_str(), elapsed());
  return 0;
}

}  // namespace omniloc::cli
