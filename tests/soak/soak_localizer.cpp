// Soak run of the localizer: minutes of random driving on the simulated field (default noise:
// encoder errors, bumps, a gyro whose bias drifts), rendered frames, the full localizer, twice in
// parallel: with the heading corrected from the image (the default) and from the gyro alone.
// A match half lasts 10 minutes; the 30-second demo cannot show what a drifting gyro does over
// that time. Prints a line per simulated minute for each variant and a verdict; exits 1 when the
// default variant misses the targets (mean < 3 cm, yaw < 1 deg, never lost), so that
// `make soak` is a check and not just a printout. Not part of `make test` (minutes of CPU).
//
//   soak_localizer [--minutes N] [--seed S] [--camera-hz HZ] [--gyro-bias DEG_PER_S]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "omniloc/localizer.hpp"
#include "omniloc_sim/playing_area.hpp"
#include "omniloc_sim/record_sim.hpp"

namespace {

using namespace omniloc;

struct Options {
  double minutes = 10.0;
  std::uint64_t seed = 1;
  double camera_hz = 30.0;
  double gyro_bias_deg_per_s = 0.0;
};

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> double {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      char* end = nullptr;
      const double v = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0' || !std::isfinite(v))
        throw std::invalid_argument(a + ": not a number: " + argv[i]);
      return v;
    };
    if (a == "--minutes")
      o.minutes = value();
    else if (a == "--seed")
      o.seed = static_cast<std::uint64_t>(value());
    else if (a == "--camera-hz")
      o.camera_hz = value();
    else if (a == "--gyro-bias")
      o.gyro_bias_deg_per_s = value();
    else
      throw std::invalid_argument("unknown option " + a +
                                  " (--minutes N --seed S --camera-hz HZ --gyro-bias DEG_PER_S)");
  }
  if (!(o.minutes > 0.0 && o.minutes <= 120.0))
    throw std::invalid_argument("--minutes must be in (0, 120]");
  if (!(o.camera_hz >= 1.0 && o.camera_hz <= 60.0))
    throw std::invalid_argument("--camera-hz must be in [1, 60]");
  return o;
}

/// Random legs over the whole playing field (up to 40 cm from its lines), turns on the spot and
/// pauses, for the requested time: the random walk of issue 5, made as long as a match half.
sim::Trajectory long_random_walk(double seconds, std::uint64_t seed) {
  const sim::PlayingArea& f = sim::fira_robosot_area();
  const double margin = f.robot_half_size_cm + 20.0;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(f.x_min_cm + margin, f.x_max_cm - margin);
  std::uniform_real_distribution<double> uy(f.y_min_cm + margin, f.y_max_cm - margin);
  std::uniform_real_distribution<double> uyaw(-180.0, 180.0), uspeed(40.0, 150.0),
      uaccel(150.0, 350.0), u01(0.0, 1.0);
  sim::Trajectory t("soak", {ux(rng), uy(rng), uyaw(rng)});
  while (t.duration_s() < seconds) {
    const sim::MotionLimits lim{uspeed(rng), uaccel(rng), 60.0 + 120.0 * u01(rng), 360.0};
    const double pick = u01(rng);
    if (pick < 0.1)
      t.rotate_by(uyaw(rng), lim);
    else if (pick < 0.2)
      t.wait(0.5 + 2.0 * u01(rng));
    else {
      const double yaw = uyaw(rng);  // before the point: the order gcc took as arguments
      t.line_to({ux(rng), uy(rng)}, yaw, lim);
    }
  }
  return t;
}

struct MinuteStats {
  double sum_xy = 0.0, max_xy = 0.0, sum_yaw = 0.0, max_yaw = 0.0;
  int windows = 0, lost = 0, odometry = 0;
  void add(const LocalizedPose& p, const Pose2& truth) {
    const double exy = std::hypot(p.pose.x_cm - truth.x_cm, p.pose.y_cm - truth.y_cm);
    const double eyaw = std::abs(angle_diff_deg(p.pose.yaw_deg, truth.yaw_deg));
    sum_xy += exy;
    max_xy = std::max(max_xy, exy);
    sum_yaw += eyaw;
    max_yaw = std::max(max_yaw, eyaw);
    ++windows;
    lost += p.source == PoseSource::kLost || p.source == PoseSource::kNone;
    odometry += p.source == PoseSource::kOdometry;
  }
  void merge(const MinuteStats& o) {
    sum_xy += o.sum_xy;
    max_xy = std::max(max_xy, o.max_xy);
    sum_yaw += o.sum_yaw;
    max_yaw = std::max(max_yaw, o.max_yaw);
    windows += o.windows;
    lost += o.lost;
    odometry += o.odometry;
  }
};

struct VariantResult {
  const char* name = "";
  std::vector<MinuteStats> minutes;
  MinuteStats total;
  LocalizerStats stats;
  double learnt_drift_deg_per_s = 0.0;
  double true_bias_deg_per_s = 0.0;
};

std::mutex g_print;  // the two variants' progress lines

VariantResult run_variant(const char* name, bool image_heading, const Options& o,
                          const sim::OmniRenderer& renderer, const FeatureDb& db,
                          const RobotConfig& robot) {
  VariantResult r;
  r.name = name;
  const sim::Trajectory trajectory = long_random_walk(o.minutes * 60.0, o.seed);
  sim::WorldConfig wc = sim::WorldConfig::default_noise(robot, o.seed);
  wc.gyro.bias_offset_deg_per_s = o.gyro_bias_deg_per_s;
  sim::World world(wc, trajectory);
  LocalizerConfig config = load_localizer_config("default");
  config.yaw_correction = image_heading;
  Localizer localizer(config, robot, renderer.field(), renderer.camera(), db, trajectory.start());
  sim::SimRunOptions run;
  run.frame_period_ms = 1000.0 / o.camera_hz;
  run.render.seed = o.seed;
  run.max_duration_s = o.minutes * 60.0;
  MinuteStats minute;
  auto flush = [&](double t_ms) {
    r.minutes.push_back(minute);
    r.total.merge(minute);
    std::lock_guard lock(g_print);
    std::printf(
        "  %-13s minute %5.1f | mean %6.2f cm  max %7.2f cm | yaw mean %5.2f  max %6.2f deg | lost "
        "%5.1f %% | "
        "drift learnt %+.3f deg/s\n",
        name, t_ms / 60000.0, minute.sum_xy / std::max(1, minute.windows), minute.max_xy,
        minute.sum_yaw / std::max(1, minute.windows), minute.max_yaw,
        100.0 * minute.lost / std::max(1, minute.windows), localizer.yaw_drift_deg_per_s());
    std::fflush(stdout);
    minute = {};
  };
  sim::run_simulation(
      world, renderer, run,
      [&](const sim::SimWindow& w) {
        minute.add(localizer.on_window(w.window), w.truth);
        (void)localizer.take_frame_reports();
        if (minute.windows == 6000) flush(w.window.t_end_ms);
      },
      [&](const sim::SimFrame& f) {
        (void)localizer.on_image(f.t_ms, f.bgr);
        (void)localizer.take_frame_reports();
      });
  if (minute.windows > 0) flush(o.minutes * 60000.0);
  r.stats = localizer.stats();
  r.learnt_drift_deg_per_s = localizer.yaw_drift_deg_per_s();
  r.true_bias_deg_per_s = world.gyro().bias_deg_per_s();
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Options o = parse(argc, argv);
    const sim::OmniRenderer renderer(load_field("fira-robosot"), load_camera("default"));
    const FeatureDb db = build_feature_db(renderer.field(), renderer.camera(),
                                          GridSpec::covering(renderer.field(), 10.0));
    const RobotConfig robot = load_named_robot_config("default");
    std::printf(
        "soak: %.1f simulated minutes of random driving, seed %llu, camera %.0f Hz, default noise, "
        "extra gyro "
        "bias %.3f deg/s; two variants in parallel\n",
        o.minutes, static_cast<unsigned long long>(o.seed), o.camera_hz, o.gyro_bias_deg_per_s);
    std::fflush(stdout);
    VariantResult with, without;
    std::exception_ptr error;
    std::thread other([&] {
      try {
        without = run_variant("gyro heading", false, o, renderer, db, robot);
      } catch (...) {
        error = std::current_exception();
      }
    });
    with = run_variant("image heading", true, o, renderer, db, robot);
    other.join();
    if (error) std::rethrow_exception(error);

    std::printf("\nsummary over %.1f min (position error in cm, yaw error in deg):\n", o.minutes);
    for (const VariantResult* v : {&with, &without}) {
      const MinuteStats& t = v->total;
      std::printf(
          "  %-13s mean %6.2f  max %7.2f | yaw mean %5.2f  max %6.2f | lost %5.1f %%, "
          "odometry-only %5.1f %% | "
          "frames %d, accepted %d, lost events %d, yaw corrections %d | gyro bias at the end %+.3f "
          "deg/s, "
          "learnt %+.3f\n",
          v->name, t.sum_xy / std::max(1, t.windows), t.max_xy, t.sum_yaw / std::max(1, t.windows),
          t.max_yaw, 100.0 * t.lost / std::max(1, t.windows),
          100.0 * t.odometry / std::max(1, t.windows), v->stats.frames, v->stats.accepted,
          v->stats.lost_events, v->stats.yaw_corrections, v->true_bias_deg_per_s,
          v->learnt_drift_deg_per_s);
    }
    const MinuteStats& t = with.total;
    const bool ok = t.sum_xy / std::max(1, t.windows) < 3.0 && t.max_yaw < 1.0 && t.lost == 0;
    std::printf("verdict: image heading %s the targets (mean < 3 cm, yaw < 1 deg, never lost)\n",
                ok ? "meets" : "MISSES");
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soak_localizer: %s\n", e.what());
    return 2;
  }
}
