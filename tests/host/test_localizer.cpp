// The localizer on simulated runs (World with default noise + rendered frames at 60 Hz): the
// issue's accuracy targets at the paper's 19 test points, recovery from a kidnapping, frames
// applied at the time they were taken, paper mode, and the handling of bad frames. Ground truth
// comes from the simulator. One feature database per test binary.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "omniloc/localizer.hpp"
#include "omniloc_sim/record_sim.hpp"
#include "short_mode.hpp"

namespace omniloc {
namespace {

struct Point {
  const char* label;
  double x_cm, y_cm;
};
// "Real" positions of Tables 5 (general) and 6 (boundary): the integrated-localization tables.
constexpr Point kGeneral[] = {{"G1", 225, 170}, {"G2", 375, 173}, {"G3", 517, 166},
                              {"G4", 157, 278}, {"G5", 375, 275}, {"G6", 595, 274},
                              {"G7", 225, 385}, {"G8", 368, 371}, {"G9", 507, 380}};
constexpr Point kBoundary[] = {
    {"B1", 81, 82},  {"B2", 225, 73},  {"B3", 386, 78},  {"B4", 525, 80},  {"B5", 661, 76},
    {"B6", 89, 479}, {"B7", 245, 479}, {"B8", 386, 479}, {"B9", 509, 475}, {"B10", 649, 479}};

class LocalizerSim : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    renderer_ =
        std::make_unique<sim::OmniRenderer>(load_field("fira-robosot"), load_camera("default"));
    db_ = std::make_unique<FeatureDb>(build_feature_db(
        renderer_->field(), renderer_->camera(), GridSpec::covering(renderer_->field(), 10.0)));
    robot_ = load_named_robot_config("default");
  }
  static void TearDownTestSuite() {
    renderer_.reset();
    db_.reset();
  }
  static double position_error(const LocalizedPose& p, const Pose2& t) {
    return std::hypot(p.pose.x_cm - t.x_cm, p.pose.y_cm - t.y_cm);
  }
  /// Drives 80 cm from a start beside the point (towards the field centre) onto it while
  /// turning by 40 degrees, then stands for 0.2 s; no initial pose (global search at start).
  static sim::LocalizedRun drive_to(const Point& p, std::uint64_t seed,
                                    const LocalizerConfig& config) {
    const Eigen::Vector2d target(p.x_cm, p.y_cm);
    Eigen::Vector2d towards = Eigen::Vector2d(375, 275) - target;
    if (towards.norm() < 1.0) towards = {1.0, 0.0};
    const Eigen::Vector2d start = target + 80.0 * towards.normalized();
    const double yaw0 = -60.0 + 13.0 * static_cast<double>(seed % 10);
    sim::MotionLimits limits;
    limits.max_speed_cm_per_s = 150.0;
    limits.max_accel_cm_per_s2 = 300.0;
    sim::Trajectory tr(p.label, Pose2{start.x(), start.y(), yaw0});
    tr.wait(0.1).line_to(target, yaw0 + 40.0, limits).wait(0.2);
    sim::World world(sim::WorldConfig::default_noise(robot_, seed), tr);
    Localizer loc(config, robot_, renderer_->field(), renderer_->camera(), *db_);
    sim::SimRunOptions opt;
    opt.render.seed = seed;
    return sim::localize_simulation(world, *renderer_, opt, loc);
  }
  static std::unique_ptr<sim::OmniRenderer> renderer_;
  static std::unique_ptr<FeatureDb> db_;
  static RobotConfig robot_;
};
std::unique_ptr<sim::OmniRenderer> LocalizerSim::renderer_;
std::unique_ptr<FeatureDb> LocalizerSim::db_;
RobotConfig LocalizerSim::robot_;

/// Runs the points of one group, prints the table and checks the targets: mean below
/// `mean_target_cm`, no point (nor any pose along the drives after the first fix) above 15 cm,
/// yaw error below 1 degree. In the short mode (short_mode.hpp) 3 points spread over the group,
/// each with the seed it has in the full run, against the same targets.
void check_group(const char* name, const Point* pts, int n_all, std::uint64_t seed,
                 double mean_target_cm,
                 sim::LocalizedRun (*drive)(const Point&, std::uint64_t, const LocalizerConfig&)) {
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const int n = test::full_or_short(n_all, 3, "points");
  double sum = 0.0, worst = 0.0, worst_yaw = 0.0, worst_along = 0.0;
  for (int k = 0; k < n; ++k) {
    const int i = k * n_all / n;
    const sim::LocalizedRun run =
        drive(pts[i], seed + static_cast<std::uint64_t>(i), LocalizerConfig{});
    const LocalizedPose& last = run.poses.back();
    const Pose2& truth = run.windows.back().truth;
    const double e = std::hypot(last.pose.x_cm - truth.x_cm, last.pose.y_cm - truth.y_cm);
    const double ey = std::abs(angle_diff_deg(last.pose.yaw_deg, truth.yaw_deg));
    double along = 0.0;
    for (std::size_t k = 0; k < run.poses.size(); ++k)
      if (run.poses[k].source != PoseSource::kNone)
        along = std::max(along, std::hypot(run.poses[k].pose.x_cm - run.windows[k].truth.x_cm,
                                           run.poses[k].pose.y_cm - run.windows[k].truth.y_cm));
    std::printf(
        "%-4s (%3.0f, %3.0f): error %5.2f cm, yaw %5.2f deg, worst along the drive %5.2f cm, "
        "source %s\n",
        pts[i].label, truth.x_cm, truth.y_cm, e, ey, along, pose_source_name(last.source));
    EXPECT_NE(last.source, PoseSource::kNone) << pts[i].label;
    EXPECT_NE(last.source, PoseSource::kLost) << pts[i].label;
    sum += e;
    worst = std::max(worst, e);
    worst_yaw = std::max(worst_yaw, ey);
    worst_along = std::max(worst_along, along);
  }
  std::printf(
      "%s: mean %.2f cm, worst %.2f cm, worst yaw %.2f deg, worst along the drives %.2f cm\n", name,
      sum / n, worst, worst_yaw, worst_along);
  EXPECT_LT(sum / n, mean_target_cm);
  EXPECT_LT(worst, 15.0);
  EXPECT_LT(worst_along, 15.0);
  EXPECT_LT(worst_yaw, 1.0);
}

TEST_F(LocalizerSim, GeneralTestPointsMeetTheTargets) {
  check_group("general", kGeneral, 9, 7, 3.0, &drive_to);
}

TEST_F(LocalizerSim, BoundaryTestPointsMeetTheTargets) {
  check_group("boundary", kBoundary, 10, 17, 5.0, &drive_to);
}

/// The kidnapping drive: 1.2 s in, the robot is carried from near (330, 200) to (560, 400, 120).
struct KidnapRun {
  sim::LocalizedRun run;
  LocalizerStats stats;
  /// from the kidnapping to the first window from which every pose is within 10 cm
  double recovery_ms = 0.0;
  bool recovered = false;
};
KidnapRun kidnap_drive(const LocalizerConfig& config, std::uint64_t seed, const RobotConfig& robot,
                       const sim::OmniRenderer& renderer, const FeatureDb& db) {
  sim::MotionLimits limits;
  sim::Trajectory tr("kidnap", Pose2{200, 200, 0});
  tr.line_to({330, 200}, 0, limits).line_to({330, 300}, 20, limits).wait(0.3);
  sim::WorldConfig wc = sim::WorldConfig::default_noise(robot, seed);
  const double kidnap_s = 1.2;
  wc.kidnaps.push_back({kidnap_s, Pose2{560, 400, 120}});
  sim::World world(wc, tr);
  Localizer loc(config, robot, renderer.field(), renderer.camera(), db, Pose2{200, 200, 0});
  sim::SimRunOptions opt;
  opt.render.seed = seed;
  KidnapRun k;
  k.run = sim::localize_simulation(world, renderer, opt, loc);
  k.stats = loc.stats();
  std::size_t first_good = k.run.poses.size();
  for (std::size_t i = k.run.poses.size(); i-- > 0;) {
    const Pose2& t = k.run.windows[i].truth;
    if (std::hypot(k.run.poses[i].pose.x_cm - t.x_cm, k.run.poses[i].pose.y_cm - t.y_cm) >= 10.0)
      break;
    first_good = i;
  }
  k.recovered = first_good < k.run.poses.size();
  if (k.recovered) k.recovery_ms = k.run.windows[first_good].window.t_end_ms - kidnap_s * 1000.0;
  return k;
}

TEST_F(LocalizerSim, RecoversFromAKidnappingWithinOneSecond) {
  const std::uint64_t seed = 11;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const KidnapRun k = kidnap_drive(LocalizerConfig{}, seed, robot_, *renderer_, *db_);
  ASSERT_TRUE(k.recovered);
  std::printf(
      "kidnapped at 1200 ms; within 10 cm again %.0f ms later; lost events %d, relocalizations "
      "%d\n",
      k.recovery_ms, k.stats.lost_events, k.stats.relocalizations);
  EXPECT_GT(k.recovery_ms, 0.0);  // it was wrong right after the kidnapping (the test can fail)
  EXPECT_LT(k.recovery_ms, 1000.0);
  EXPECT_GE(k.stats.lost_events, 1);
  const Pose2& truth = k.run.windows.back().truth;
  EXPECT_LT(position_error(k.run.poses.back(), truth), 3.0);
  EXPECT_LT(std::abs(angle_diff_deg(k.run.poses.back().pose.yaw_deg, truth.yaw_deg)), 1.0);
}

// The cross-check's global search on its worker thread (cross_check_worker, the default) against
// the same search inline (the reference): on the kidnapping drive both notice the kidnapping and
// recover, the worker at most a few frames later (it judges a check when the next frame comes); and
// the worker's outcome does not depend on the thread's timing: two runs give the same poses.
TEST_F(LocalizerSim, TheCrossCheckOnItsWorkerRecoversAsTheInlineOneAndRepeatsExactly) {
  const std::uint64_t seed = 11;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  LocalizerConfig inline_cfg;
  inline_cfg.cross_check_worker = false;
  const KidnapRun in = kidnap_drive(inline_cfg, seed, robot_, *renderer_, *db_);
  const KidnapRun w1 = kidnap_drive(LocalizerConfig{}, seed, robot_, *renderer_, *db_);
  const KidnapRun w2 = kidnap_drive(LocalizerConfig{}, seed, robot_, *renderer_, *db_);
  ASSERT_TRUE(in.recovered);
  ASSERT_TRUE(w1.recovered);
  std::printf(
      "recovery: inline %.0f ms (global searches %d, lost events %d), worker %.0f ms (%d, %d)\n",
      in.recovery_ms, in.stats.global_searches, in.stats.lost_events, w1.recovery_ms,
      w1.stats.global_searches, w1.stats.lost_events);
  EXPECT_GE(w1.stats.lost_events, 1);
  EXPECT_LE(w1.recovery_ms, in.recovery_ms + 4 * 1000.0 / 60.0)
      << "at most a few frames later than inline";
  EXPECT_LT(w1.recovery_ms, 1000.0);
  ASSERT_EQ(w1.run.poses.size(), w2.run.poses.size());
  for (std::size_t i = 0; i < w1.run.poses.size(); ++i) {
    ASSERT_EQ(w1.run.poses[i].pose.x_cm, w2.run.poses[i].pose.x_cm) << "window " << i;
    ASSERT_EQ(w1.run.poses[i].pose.y_cm, w2.run.poses[i].pose.y_cm) << "window " << i;
    ASSERT_EQ(w1.run.poses[i].pose.yaw_deg, w2.run.poses[i].pose.yaw_deg) << "window " << i;
  }
}

/// A gyro left with a bad start-up calibration (0.4 deg/s of bias on top of the default noise):
/// over the 12 s drive the gyro heading drifts by ~5 degrees. The image heading must hold the yaw
/// error below 1 degree once learnt, keep the position on target and learn the drift rate; with the
/// correction off the same run ends far off (the scenario really is a drifting gyro).
TEST_F(LocalizerSim, ImageHeadingCorrectsADriftingGyro) {
  const std::uint64_t seed = 23;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  sim::MotionLimits limits;
  limits.max_speed_cm_per_s = 120.0;
  const Pose2 start{250, 200, 10};
  auto run_once = [&](bool correct, double* drift_true, double* drift_learnt) {
    sim::Trajectory tr("drifting gyro", start);
    tr.line_to({500, 200}, 60, limits)
        .line_to({500, 350}, 150, limits)
        .arc({375, 275}, 180, true, limits);
    tr.line_to({250, 200}, -30, limits)
        .rotate_by(90, limits)
        .line_to({375, 275}, 45, limits)
        .wait(0.5);
    sim::WorldConfig wc = sim::WorldConfig::default_noise(robot_, seed);
    wc.gyro.bias_offset_deg_per_s = 0.4;
    sim::World world(wc, tr);
    LocalizerConfig config;
    config.yaw_correction = correct;
    Localizer loc(config, robot_, renderer_->field(), renderer_->camera(), *db_, start);
    sim::SimRunOptions opt;
    opt.render.seed = seed;
    sim::LocalizedRun run = sim::localize_simulation(world, *renderer_, opt, loc);
    *drift_true = world.gyro().bias_deg_per_s();
    *drift_learnt = loc.yaw_drift_deg_per_s();
    std::printf("yaw correction %s: %d corrections, %d lost events\n", correct ? "on" : "off",
                loc.stats().yaw_corrections, loc.stats().lost_events);
    return run;
  };
  double bias = 0.0, learnt = 0.0;
  const sim::LocalizedRun run = run_once(true, &bias, &learnt);
  const double duration_ms = run.windows.back().window.t_end_ms;
  double worst_yaw = 0.0, sum_xy = 0.0, worst_xy = 0.0;
  int n = 0;
  for (std::size_t k = 0; k < run.poses.size(); ++k) {
    const double t = run.windows[k].window.t_end_ms;
    const double ey =
        std::abs(angle_diff_deg(run.poses[k].pose.yaw_deg, run.windows[k].truth.yaw_deg));
    const double exy = position_error(run.poses[k], run.windows[k].truth);
    if (t >= 4000.0) worst_yaw = std::max(worst_yaw, ey);
    worst_xy = std::max(worst_xy, exy);
    sum_xy += exy;
    ++n;
  }
  std::printf(
      "%.1f s, gyro bias %.3f deg/s (drift %.1f deg over the run); learnt correction %.3f deg/s\n",
      duration_ms / 1000.0, bias, bias * duration_ms / 1000.0, learnt);
  std::printf(
      "corrected: worst yaw error after 4 s %.2f deg, position mean %.2f cm, worst %.2f cm\n",
      worst_yaw, sum_xy / n, worst_xy);
  EXPECT_GT(duration_ms, 12000.0);
  EXPECT_LT(worst_yaw, 1.0);
  EXPECT_LT(sum_xy / n, 3.0);
  EXPECT_LT(worst_xy, 15.0);
  EXPECT_NEAR(learnt, -bias, 0.15);  // the learnt rate cancels the gyro's bias
  EXPECT_NE(run.poses.back().source, PoseSource::kLost);

  if (test::short_mode()) {
    std::printf("short mode (OMNILOC_TEST_SHORT): the run with the correction off left out\n");
    return;
  }
  double bias_off = 0.0, learnt_off = 0.0;
  const sim::LocalizedRun off = run_once(false, &bias_off, &learnt_off);
  const double final_yaw_off =
      std::abs(angle_diff_deg(off.poses.back().pose.yaw_deg, off.windows.back().truth.yaw_deg));
  std::printf("uncorrected: final yaw error %.2f deg\n", final_yaw_off);
  EXPECT_GT(final_yaw_off, 3.0);
  EXPECT_EQ(learnt_off, 0.0);
}

TEST_F(LocalizerSim, PaperModeDoesNotNoticeAKidnapping) {
  const std::uint64_t seed = 11;
  sim::MotionLimits limits;
  sim::Trajectory tr("kidnap", Pose2{200, 200, 0});
  tr.line_to({330, 200}, 0, limits).wait(0.6);
  sim::WorldConfig wc = sim::WorldConfig::default_noise(robot_, seed);
  wc.kidnaps.push_back({1.2, Pose2{560, 400, 0}});
  sim::World world(wc, tr);
  Localizer loc(LocalizerConfig::paper(), robot_, renderer_->field(), renderer_->camera(), *db_,
                Pose2{200, 200, 0});
  const sim::LocalizedRun run = sim::localize_simulation(world, *renderer_, {}, loc);
  // Without lost detection the local search keeps looking near the old place: the pose stays wrong.
  EXPECT_GT(position_error(run.poses.back(), run.windows.back().truth), 100.0);
  EXPECT_EQ(loc.stats().global_searches, 0);
  EXPECT_EQ(loc.stats().lost_events, 0);
}

TEST_F(LocalizerSim, FramesAreAppliedAtTheTimeTheyWereTaken) {
  // The same run twice: frames given as soon as taken, and held back by 60 ms (processing
  // latency). Applied at their own time, both give the same poses once the late frames are in;
  // a localizer that used a frame when it arrived would be ~speed x 60 ms = 6 cm off.
  auto run_with_delay = [&](double delay_ms) {
    sim::MotionLimits limits;
    sim::Trajectory tr("line", Pose2{150, 275, 0});
    tr.line_to({600, 275}, 0, limits);
    sim::World world(sim::WorldConfig::noise_free(robot_, 3), tr);
    LocalizerConfig cfg;
    cfg.check_period_ms = 1e9;  // only the local search path
    Localizer loc(cfg, robot_, renderer_->field(), renderer_->camera(), *db_, Pose2{150, 275, 0});
    std::vector<sim::SimFrame> held;
    std::vector<std::pair<LocalizedPose, Pose2>> out;
    sim::SimRunOptions opt;
    opt.render = sim::noise_free();
    sim::run_simulation(
        world, *renderer_, opt,
        [&](const sim::SimWindow& w) {
          out.emplace_back(loc.on_window(w.window), w.truth);
          while (!held.empty() && held.front().t_ms + delay_ms <= w.window.t_end_ms) {
            (void)loc.on_image(held.front().t_ms, held.front().bgr);
            held.erase(held.begin());
          }
        },
        [&](const sim::SimFrame& f) { held.push_back(f); });
    EXPECT_EQ(loc.stats().dropped, 0);
    EXPECT_GT(loc.stats().accepted, 50);
    return out;
  };
  const auto prompt = run_with_delay(0.0);
  const auto late = run_with_delay(60.0);
  ASSERT_EQ(prompt.size(), late.size());
  double worst_diff = 0.0, worst_truth = 0.0;
  for (std::size_t k = 20; k < prompt.size(); ++k) {
    // The late run's pose at window k knows only the frames up to t_k - 60 ms, carried forward
    // by odometry: it must still be as good as the prompt run's.
    worst_truth = std::max(worst_truth, position_error(late[k].first, late[k].second));
    worst_diff = std::max(worst_diff, position_error(late[k].first, Pose2{prompt[k].first.pose}));
  }
  std::printf(
      "late frames: worst error vs truth %.2f cm, worst difference to prompt frames %.2f cm\n",
      worst_truth, worst_diff);
  EXPECT_LT(worst_truth, 3.0);
  EXPECT_LT(worst_diff, 3.0);
}

TEST_F(LocalizerSim, ReportedUncertaintyCoversTheTrueError) {
  // Issue 15.5: the pose's uncertainty comes from the match (the error surface's curvature) and
  // the odometry's growth since the fix. Over the simulator's random walk with default noise, and
  // a 3 s stretch without frames in the middle (odometry only), the true position error must lie
  // within the reported 2 sigma in at least 90 % of the windows, and the sigma must say something:
  // it must not cover by being several times the error it describes.
  const std::uint64_t seed = 29;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  sim::World world(sim::WorldConfig::default_noise(robot_, seed),
                   sim::make_trajectory("random_walk", seed));
  Localizer loc(LocalizerConfig{}, robot_, renderer_->field(), renderer_->camera(), *db_);
  sim::SimRunOptions opt;
  opt.render.seed = seed;
  constexpr double kOutageFromMs = 12000.0, kOutageToMs = 15000.0;
  int windows = 0, covered = 0, outage_windows = 0, outage_covered = 0;
  std::vector<double> error_over_sigma;
  double sum_sq_error = 0.0, sum_sq_sigma = 0.0;
  sim::run_simulation(
      world, *renderer_, opt,
      [&](const sim::SimWindow& w) {
        const LocalizedPose p = loc.on_window(w.window);
        if (p.source == PoseSource::kNone || p.source == PoseSource::kLost) return;
        const double e = position_error(p, w.truth);
        const bool in = e <= 2.0 * p.sigma_xy_cm;
        ++windows;
        covered += in ? 1 : 0;
        const bool outage = w.window.t_end_ms > kOutageFromMs && w.window.t_end_ms < kOutageToMs;
        outage_windows += outage ? 1 : 0;
        outage_covered += outage && in ? 1 : 0;
        error_over_sigma.push_back(e / p.sigma_xy_cm);
        sum_sq_error += e * e;
        sum_sq_sigma += p.sigma_xy_cm * p.sigma_xy_cm;
      },
      [&](const sim::SimFrame& f) {
        if (f.t_ms > kOutageFromMs && f.t_ms < kOutageToMs) return;
        (void)loc.on_image(f.t_ms, f.bgr);
      });
  ASSERT_GT(windows, 1000);
  ASSERT_GT(outage_windows, 250);
  std::sort(error_over_sigma.begin(), error_over_sigma.end());
  const double rms_error = std::sqrt(sum_sq_error / windows),
               rms_sigma = std::sqrt(sum_sq_sigma / windows);
  std::printf(
      "uncertainty: %d windows, true error within 2 sigma in %.1f %% (outage: %.1f %% of %d); "
      "error / sigma median %.2f, p90 %.2f; RMS error %.2f cm, RMS sigma %.2f cm\n",
      windows, 100.0 * covered / windows, 100.0 * outage_covered / outage_windows, outage_windows,
      error_over_sigma[error_over_sigma.size() / 2],
      error_over_sigma[error_over_sigma.size() * 9 / 10], rms_error, rms_sigma);
  EXPECT_GE(covered, 0.9 * windows);
  EXPECT_GE(outage_covered, 0.9 * outage_windows);
  EXPECT_LT(rms_sigma, 3.0 * rms_error) << "a sigma that covers only by being far too large";
}

TEST_F(LocalizerSim, FramesWithNoMeasurementLeaveTheOdometryStanding) {
  sim::MotionLimits limits;
  sim::Trajectory tr("line", Pose2{300, 275, 0});
  tr.line_to({400, 275}, 0, limits).wait(0.5);
  sim::World world(sim::WorldConfig::noise_free(robot_, 5), tr);
  Localizer loc(LocalizerConfig{}, robot_, renderer_->field(), renderer_->camera(), *db_,
                Pose2{300, 275, 0});
  // A frame with no lines at all (camera covered by a green cloth).
  const cv::Mat blank(renderer_->camera().height_px, renderer_->camera().width_px, CV_8UC3,
                      cv::Scalar(40, 140, 40));
  int frames = 0;
  std::vector<std::pair<LocalizedPose, Pose2>> out;
  sim::SimRunOptions opt;
  opt.render_frames = false;
  sim::run_simulation(
      world, *renderer_, opt,
      [&](const sim::SimWindow& w) { out.emplace_back(loc.on_window(w.window), w.truth); },
      [&](const sim::SimFrame& f) {
        (void)loc.on_image(f.t_ms, blank);
        ++frames;
      });
  ASSERT_GT(frames, 60);
  EXPECT_EQ(loc.stats().accepted, 0);
  // Odometry alone, noise-free world: still right after 1.5 s.
  EXPECT_LT(position_error(out.back().first, out.back().second), 2.0);
  // A frame with no lines is "no measurement" (LineExtractor): reported rejected with its reason
  // and not matched, so it is no evidence of being lost: the last pose carried by odometry stands.
  const auto reports = loc.take_frame_reports();
  ASSERT_FALSE(reports.empty());
  for (const auto& r : reports) {
    EXPECT_EQ(r.outcome, FrameOutcome::kRejected);
    EXPECT_FALSE(r.no_measurement.empty());
  }
  EXPECT_EQ(loc.stats().rejected, frames);
  EXPECT_NE(out.back().first.source, PoseSource::kImage);
  EXPECT_NE(out.back().first.source, PoseSource::kLost);
  EXPECT_FALSE(out.back().first.match_error);  // no frame was matched
}

TEST_F(LocalizerSim, RefusesAmbiguousMatchesWithoutAHeading) {
  // Without a trusted heading the point-symmetric field looks the same from p and its mirror
  // image (centre * 2 - p, yaw + 180): the full mode refuses to pick one, the paper mode picks.
  const Pose2 truth{250, 200, 30};
  const cv::Mat img = renderer_->render(truth, sim::RenderOptions{});
  EncoderWindow w;
  w.t_end_ms = 10.0;
  w.gyro_yaw_deg = 0.0;  // the gyro was never aligned
  LocalizerConfig full;
  full.gyro_yaw_known = false;
  Localizer a(full, robot_, renderer_->field(), renderer_->camera(), *db_);
  (void)a.on_window(w);
  const FrameReport ra = a.on_image(5.0, img);
  EXPECT_EQ(ra.outcome, FrameOutcome::kAmbiguous);
  EXPECT_FALSE(a.has_fix());
  w.t_end_ms = 20.0;
  w.seq = 1;
  EXPECT_EQ(a.on_window(w).source, PoseSource::kNone);
}

TEST_F(LocalizerSim, TheSideGivenDecidesTheTwinAtKickOff) {
  // Issue 15.2: without a heading the point-symmetric field cannot tell p from its twin; the team's
  // side (the colour of the goal it defends) and the kick-off rule (own half, facing the opponent's
  // goal) can. Goals: yellow at x = max, so blue is defended from the x < centre half.
  FieldGeometry field = renderer_->field();
  field.goal.colour_at_x_max = GoalColour::kYellow;
  LocalizerConfig cfg;
  cfg.gyro_yaw_known = false;
  const auto first_fix = [&](const Pose2& truth, std::optional<GoalColour> side) {
    Localizer loc(cfg, robot_, field, renderer_->camera(), *db_);
    if (side) loc.set_side(*side);
    EncoderWindow w;
    w.t_end_ms = 10.0;
    (void)loc.on_window(w);
    const FrameReport r = loc.on_image(5.0, renderer_->render(truth, sim::RenderOptions{}));
    w.t_end_ms = 20.0;
    w.seq = 1;
    const LocalizedPose p = loc.on_window(w);
    std::printf(
        "truth (%.0f, %.0f, %.0f), side %s: %s, pose (%.1f, %.1f, %.1f), decided by side %d\n",
        truth.x_cm, truth.y_cm, truth.yaw_deg, side ? goal_colour_name(*side) : "none",
        frame_outcome_name(r.outcome), p.pose.x_cm, p.pose.y_cm, p.pose.yaw_deg,
        loc.stats().decided_by_side);
    return std::make_pair(r.outcome, p);
  };
  // In the blue half, facing the yellow goal, away from the centre: the twin stands in the other
  // half.
  const Pose2 truth{250, 200, 30};
  EXPECT_EQ(first_fix(truth, std::nullopt).first, FrameOutcome::kAmbiguous);
  const auto [blue_outcome, blue] = first_fix(truth, GoalColour::kBlue);
  EXPECT_EQ(blue_outcome, FrameOutcome::kRelocalized);
  EXPECT_LT(position_error(blue, truth), 3.0);
  EXPECT_LT(std::abs(angle_diff_deg(blue.pose.yaw_deg, truth.yaw_deg)), 2.0);
  // The other side picks the twin: the rule, not the image, decided (a wrong side is a wrong pose).
  const auto [yellow_outcome, yellow] = first_fix(truth, GoalColour::kYellow);
  EXPECT_EQ(yellow_outcome, FrameOutcome::kRelocalized);
  const Eigen::Vector2d twin = 2.0 * field.centre_cm() - truth.position_cm();
  EXPECT_LT((yellow.pose.position_cm() - twin).norm(), 3.0);
  // On the centre spot the position is known and the heading only up to 180 deg: the robot faces
  // the opponent's goal.
  const Pose2 centre{field.centre_cm().x(), field.centre_cm().y(), 10};
  const auto [c_blue_outcome, c_blue] = first_fix(centre, GoalColour::kBlue);
  EXPECT_EQ(c_blue_outcome, FrameOutcome::kRelocalized);
  EXPECT_LT(std::abs(angle_diff_deg(c_blue.pose.yaw_deg, 10.0)), 2.0);
  const auto [c_yellow_outcome, c_yellow] = first_fix(centre, GoalColour::kYellow);
  EXPECT_EQ(c_yellow_outcome, FrameOutcome::kRelocalized);
  EXPECT_LT(std::abs(angle_diff_deg(c_yellow.pose.yaw_deg, 190.0)), 2.0);
  // A field and camera that do not say which goal is which colour: refused, saying what is missing.
  Localizer unknown(cfg, robot_, renderer_->field(), renderer_->camera(), *db_);
  try {
    unknown.set_side(GoalColour::kBlue);
    ADD_FAILURE() << "set_side accepted a field without goal colours";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("colour_at_x_max"), std::string::npos) << e.what();
  }
}

TEST_F(LocalizerSim, ARelativeGyroAlignedAtTheFirstFixKnowsTheHeadingAfterwards) {
  // Issue 15.1/15.2: the board's gyro starts at 0, not aligned with the field (trust kRelative).
  // The first fix (its twin decided by the side) aligns it; a later global search (relocalize)
  // then runs at the gyro's heading and is not ambiguous. With the wheels' heading (kNone) the same
  // search stays ambiguous, and a gyro fault (a window of kNone) forgets the alignment.
  FieldGeometry field = renderer_->field();
  field.goal.colour_at_x_max = GoalColour::kYellow;
  const Pose2 truth{250, 200, 30};
  const cv::Mat img = renderer_->render(truth, sim::RenderOptions{});
  const double gyro_deg = -40.0;  // what the unaligned gyro reads while the robot faces 30 deg
  const auto run = [&](HeadingTrust later_trust) {
    Localizer loc(LocalizerConfig{}, robot_, field, renderer_->camera(), *db_);
    loc.set_side(GoalColour::kBlue);
    EncoderWindow w;
    w.gyro_yaw_deg = gyro_deg;
    w.heading_trust = HeadingTrust::kRelative;
    double t = 10.0;
    const auto window = [&](HeadingTrust trust) {
      w.t_end_ms = t;
      w.heading_trust = trust;
      ++w.seq;
      t += 10.0;
      return loc.on_window(w);
    };
    (void)window(HeadingTrust::kRelative);
    EXPECT_FALSE(loc.heading_known());
    const FrameReport first = loc.on_image(t - 15.0, img);
    const LocalizedPose p = window(HeadingTrust::kRelative);
    EXPECT_EQ(first.outcome, FrameOutcome::kRelocalized);
    EXPECT_EQ(loc.stats().decided_by_side, 1);
    EXPECT_LT(position_error(p, truth), 3.0);
    EXPECT_LT(std::abs(angle_diff_deg(p.pose.yaw_deg, truth.yaw_deg)), 2.0);
    EXPECT_TRUE(loc.heading_known());
    (void)window(later_trust);
    loc.force_global_search();
    const FrameReport again = loc.on_image(t - 15.0, img);
    const LocalizedPose q = window(later_trust);
    std::printf(
        "later trust %s: %s, pose (%.1f, %.1f, %.1f), heading known %d, decided by side %d\n",
        heading_trust_name(later_trust), frame_outcome_name(again.outcome), q.pose.x_cm,
        q.pose.y_cm, q.pose.yaw_deg, loc.heading_known(), loc.stats().decided_by_side);
    return std::make_pair(again, q);
  };
  const auto [gyro_report, gyro_pose] = run(HeadingTrust::kRelative);
  EXPECT_TRUE(gyro_report.global);
  EXPECT_EQ(gyro_report.outcome, FrameOutcome::kRelocalized);  // at the gyro heading: no twin
  EXPECT_LT(position_error(gyro_pose, truth), 3.0);
  const auto [wheel_report, wheel_pose] = run(HeadingTrust::kNone);  // e.g. a gyro fault
  EXPECT_EQ(wheel_report.outcome, FrameOutcome::kAmbiguous);
  EXPECT_EQ(wheel_pose.source, PoseSource::kLost);
}

TEST_F(LocalizerSim, WindowsMustMoveForwardInTime) {
  Localizer loc(LocalizerConfig{}, robot_, renderer_->field(), renderer_->camera(), *db_,
                Pose2{300, 275, 0});
  EncoderWindow w;
  w.seq = 4;
  w.t_end_ms = 10.0;
  (void)loc.on_window(w);
  w.seq = 5;
  try {
    (void)loc.on_window(w);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("seq 5"), std::string::npos) << e.what();
  }
}

TEST_F(LocalizerSim, ResyncAcceptsARestartedTimeBase) {
  Localizer loc(LocalizerConfig{}, robot_, renderer_->field(), renderer_->camera(), *db_,
                Pose2{300, 275, 0});
  EncoderWindow w;
  w.t_end_ms = 1000.0;
  // One window of straight driving: +x by 100 counts on every wheel of eq. (9)'s forward pattern.
  w.counts = {-100, -100, 100, 100};
  const LocalizedPose before = loc.on_window(w);
  EXPECT_GT(before.pose.x_cm, 300.0);
  loc.resync();
  w.t_end_ms = 10.0;  // the board restarted its clock
  w.counts = {0, 0, 0, 0};
  const LocalizedPose after = loc.on_window(w);
  EXPECT_NEAR(after.pose.x_cm, before.pose.x_cm, 1e-9);
  EXPECT_NEAR(after.pose.y_cm, before.pose.y_cm, 1e-9);
}

TEST_F(LocalizerSim, FramesWithoutWindowsAreBoundedAndDropped) {
  Localizer loc(LocalizerConfig{}, robot_, renderer_->field(), renderer_->camera(), *db_,
                Pose2{300, 275, 0});
  BearingScan empty;
  empty.radii_px.assign(360 * 4 * 4, kNoCrossing);
  empty.ray_end_px.assign(360 * 4, kRayHidden);
  for (int i = 0; i < 200; ++i)
    EXPECT_EQ(loc.on_bearings(5.0 + i, empty).outcome, FrameOutcome::kPending);
  EXPECT_EQ(loc.stats().dropped, 80);
  EXPECT_EQ(loc.take_frame_reports().size(), 80u);
}

// The local search reaches floor(range / step) cells each side: at a 20 cm step the default
// fuzzy ranges 0/10/20/30 cm would search 1x1, 1x1, 3x3 and 3x3 points. The localizer refuses
// such a database at construction, naming the range and the step.
TEST_F(LocalizerSim, RefusesFuzzyRangesOffTheDatabaseGrid) {
  const FeatureDb coarse = build_feature_db(renderer_->field(), renderer_->camera(),
                                            GridSpec::covering(renderer_->field(), 20.0), {}, 1);
  try {
    Localizer loc(LocalizerConfig{}, robot_, renderer_->field(), renderer_->camera(), coarse);
    FAIL() << "a 10 cm range on a 20 cm grid was accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    std::printf("refused: %s\n", what.c_str());
    EXPECT_NE(what.find("fuzzy.snap_ranges_cm[1]"), std::string::npos) << what;
    EXPECT_NE(what.find("search range 10 cm"), std::string::npos) << what;
    EXPECT_NE(what.find("grid step 20 cm"), std::string::npos) << what;
  }
  // Ranges that are 0 or whole multiples of 20 cm are fine, in both modes.
  LocalizerConfig ok;
  ok.fuzzy.snap_ranges_cm = {0.0, 20.0, 40.0};
  ok.min_range_cm = 20.0;
  EXPECT_NO_THROW(Localizer(ok, robot_, renderer_->field(), renderer_->camera(), coarse));
  LocalizerConfig paper = LocalizerConfig::paper();
  paper.fuzzy.snap_ranges_cm = {0.0, 20.0, 40.0};
  EXPECT_NO_THROW(Localizer(paper, robot_, renderer_->field(), renderer_->camera(), coarse));
  // kFull's minimum range is searched too; kPaper does not use it.
  ok.min_range_cm = 10.0;
  EXPECT_THROW(Localizer(ok, robot_, renderer_->field(), renderer_->camera(), coarse), ConfigError);
  paper.min_range_cm = 10.0;
  EXPECT_NO_THROW(Localizer(paper, robot_, renderer_->field(), renderer_->camera(), coarse));
}

TEST(LocalizerRanges, WholeMultiplesOfTheStepOnly) {
  GridSpec g;
  g.step_cm = 20.0;
  LocalizerConfig c = LocalizerConfig::paper();
  for (const double bad : {10.0, 30.0, 19.999, 20.001, 5.0}) {
    c.fuzzy.snap_ranges_cm = {0.0, bad};
    EXPECT_THROW(validate_search_ranges(c, g, "test"), ConfigError) << bad;
  }
  for (const double good : {20.0, 40.0, 60.0}) {
    c.fuzzy.snap_ranges_cm = {0.0, good};
    EXPECT_NO_THROW(validate_search_ranges(c, g, "test")) << good;
  }
  // The shipped defaults on the shipped 10 cm grid.
  g.step_cm = 10.0;
  EXPECT_NO_THROW(validate_search_ranges(LocalizerConfig{}, g, "test"));
  // The rule is the search's own: a range the check accepts reaches exactly range / step cells.
  EXPECT_EQ(local_search_reach_cells(30.0, 10.0), 3);
  EXPECT_EQ(local_search_reach_cells(10.0, 20.0), 0);
}

TEST(LocalizerPolicy, PaperModeHasNoneOfTheAdditions) {
  const LocalizerPolicy paper = LocalizerPolicy::of(LocalizerConfig::paper());
  EXPECT_FALSE(paper.search_any_yaw);
  EXPECT_EQ(paper.min_range_cm, 0.0);
  EXPECT_FALSE(paper.cross_check);
  EXPECT_FALSE(paper.correct_yaw);
  EXPECT_FALSE(paper.keep_anchor_on_reject);
  EXPECT_FALSE(paper.detect_lost);
  LocalizerConfig c;
  c.gyro_yaw_known = false;
  c.yaw_correction = false;
  c.min_range_cm = 20.0;
  const LocalizerPolicy full = LocalizerPolicy::of(c);
  EXPECT_TRUE(full.search_any_yaw);
  EXPECT_EQ(full.min_range_cm, 20.0);
  EXPECT_TRUE(full.cross_check);
  EXPECT_FALSE(full.correct_yaw);
  EXPECT_TRUE(full.keep_anchor_on_reject);
  EXPECT_TRUE(full.detect_lost);
  // The mode alone decides: a kPaper config with kFull's knobs set still behaves as printed.
  c.mode = LocalizerMode::kPaper;
  EXPECT_FALSE(LocalizerPolicy::of(c).search_any_yaw);
  EXPECT_EQ(LocalizerPolicy::of(c).min_range_cm, 0.0);
}

}  // namespace
}  // namespace omniloc
