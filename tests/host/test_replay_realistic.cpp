// A recording whose camera carries only today's keys (width, height, center_px, radius_lut,
// yaw_offset_deg, mirrored, mask; no "vision" block) replays: a short simulated drive rendered by
// the REALISTIC renderer (a true camera that is not the recording's camera model: a hyperbolic
// mirror, tilted, with rods; walls, people, robots, the ball, goals, vignetting, noise, JPEG) with
// the light changing during the run (a seeded smooth exposure curve, and the ceiling lights drawn
// anew per frame), recorded, its meta.json reduced to today's camera keys, then replayed with
// replay_recording and with `omniloc replay`. The extraction must estimate the carpet and the line
// contrast from the frames and follow the light; the poses it accepts are checked against the
// simulator's truth. A few frames inside the recording are black or blown out to white: each is
// "no measurement" (odometry stands), never an image pose.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "omniloc/recording.hpp"
#include "omniloc_sim/record_sim.hpp"
#include "omniloc_sim/renderer.hpp"
#include "run_command.hpp"
#include "same_poses.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

// The keys a camera block has today (camera_keys() less "description", "calibration" and "vision").
const std::set<std::string> kTodaysKeys = {"width",          "height",   "center_px", "radius_lut",
                                           "yaw_offset_deg", "mirrored", "mask"};

// The camera a team has without running `omniloc calibrate`: the mirror's nominal mapping (the true
// mirror is tilted 1.5 deg, the model is radially symmetric), the body and the three rods as mast
// sectors in its mask.
CameraModel team_camera(const sim::TrueOptics& optics) {
  CameraModel cam = sim::nominal_camera(optics);
  cam.masts.clear();
  for (const sim::MirrorRod& rod : optics.rods) {
    // Image angle = bearing + yaw offset (not mirrored); the rod is widest in angle at the body.
    const double half_deg = rad_to_deg(std::atan2(0.5 * rod.width_px + 1.0, cam.body_radius_px));
    cam.masts.push_back({wrap_deg(rod.image_angle_deg - optics.yaw_offset_deg), half_deg});
  }
  cam.vision = VisionModel{};
  return cam;
}

struct BadFrame {
  double t_ms = 0.0;
  const char* what = "";
};

TEST(ReplayRealistic, TodaysCameraKeysReplayWithTheLightChanging) {
  const char* env = std::getenv("OMNILOC_SEED");
  const std::uint64_t seed = env ? std::strtoull(env, nullptr, 0) : 4711;
  std::printf("seed %llu (set OMNILOC_SEED to repeat another)\n",
              static_cast<unsigned long long>(seed));
  const fs::path dir =
      fs::temp_directory_path() / ("omniloc_test_replay_realistic_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const FieldGeometry field = load_field("fira-robosot");
  const sim::TrueOptics optics;
  const sim::RealisticRenderer renderer(field, optics);
  const CameraModel camera = team_camera(optics);
  const RobotConfig robot = load_named_robot_config("default");

  // The drive: across the half, a turn, back towards the centre (~4 s, 100 Hz windows, 30 Hz
  // frames).
  const Pose2 start{230.0, 190.0, 20.0};
  auto trajectory = [&] {
    sim::Trajectory tr("replay realistic", start);
    tr.line_to({330.0, 250.0}, 60.0, sim::MotionLimits{})
        .line_to({400.0, 330.0}, 120.0, sim::MotionLimits{})
        .wait(0.1);
    return tr;
  };
  // The light: exposure exp(a sin(2 pi t / T + phase)), a and phase seeded: the frame's brightness
  // swings between about 0.6x and 1.6x over the run.
  std::mt19937_64 rng(seed);
  const double amp = std::uniform_real_distribution<double>(0.4, 0.5)(rng);
  const double phase = std::uniform_real_distribution<double>(0.0, 2.0 * M_PI)(rng);
  const double period_ms = 3000.0;
  auto exposure = [&](double t_ms) {
    return std::exp(amp * std::sin(2.0 * M_PI * t_ms / period_ms + phase));
  };
  std::printf("exposure exp(%.3f sin(2 pi t / %.0f ms + %.3f)): %.2f .. %.2f\n", amp, period_ms,
              phase, std::exp(-amp), std::exp(amp));

  // The room (walls, robots, people, furniture) is built once at the start; the ceiling lights and
  // the sensor noise are drawn per frame (the options' seed advances per frame).
  const sim::RenderOptions base = sim::realistic(seed);
  const sim::Scene scene = sim::realistic_scene(field, start, base);
  std::vector<BadFrame> bad;
  std::vector<sim::SimFrame>
      frame_truth;  // each frame's time and true pose (truth.csv has the windows')
  int frame_index = 0;
  double lowest = 10.0, highest = 0.0;
  const sim::FrameRender render = [&](double t_ms, const Pose2& truth,
                                      const sim::RenderOptions& options) {
    ++frame_index;
    frame_truth.push_back({t_ms, truth, cv::Mat()});
    if (frame_index == 40 || frame_index == 41) {  // the lens covered: black
      bad.push_back({t_ms, "black"});
      return cv::Mat(optics.height_px, optics.width_px, CV_8UC3, cv::Scalar::all(0));
    }
    if (frame_index == 70) {  // the sensor saturated: white
      bad.push_back({t_ms, "white"});
      return cv::Mat(optics.height_px, optics.width_px, CV_8UC3, cv::Scalar::all(255));
    }
    sim::RenderOptions o = options;
    const double g = frame_index == 90
                         ? 12.0
                         : exposure(t_ms);  // frame 90: blown out, all but the darkest clipped
    if (frame_index == 90)
      bad.push_back({t_ms, "blown out (exposure x12)"});
    else {
      lowest = std::min(lowest, g);
      highest = std::max(highest, g);
    }
    o.realism.look.colour_cast = cv::Vec3f(1.0f, 1.0f, 1.0f) * static_cast<float>(g);
    return renderer.render(truth, o, scene);
  };
  sim::SimRunOptions opt;
  opt.render = base;
  opt.frame_period_ms = 1000.0 / 30.0;
  {
    sim::World world(sim::WorldConfig::default_noise(robot, seed), trajectory());
    sim::record_simulation(dir / "rec", world, camera, render, opt, "fira-robosot", std::nullopt);
  }
  std::printf("exposure over the run's frames: %.2f .. %.2f\n", lowest, highest);
  ASSERT_EQ(bad.size(), 4u);

  // meta.json's camera block: today's keys only (the writer adds the "vision" defaults; drop them).
  {
    const fs::path meta = dir / "rec" / "meta.json";
    nlohmann::json j = nlohmann::json::parse(std::ifstream(meta));
    nlohmann::json& cam = j.at("camera");
    for (auto it = cam.begin(); it != cam.end();) {
      if (kTodaysKeys.count(it.key()) == 0) {
        std::printf("meta.json camera: key \"%s\" removed\n", it.key().c_str());
        it = cam.erase(it);
      } else {
        ++it;
      }
    }
    std::ofstream(meta) << j.dump(2) << "\n";
  }
  const Recording rec = load_recording(dir / "rec");
  {
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "rec" / "meta.json"));
    std::set<std::string> keys;
    for (const auto& [k, v] : j.at("camera").items()) keys.insert(k);
    EXPECT_EQ(keys, kTodaysKeys);
  }
  EXPECT_FALSE(rec.meta.camera.vision.carpet_hsv.has_value());
  EXPECT_FALSE(rec.meta.camera.vision.line_contrast.has_value());
  ASSERT_GE(rec.frames.size(), 95u);
  ASSERT_EQ(rec.truth.size(), rec.windows.size());
  std::printf("recorded %zu windows, %zu frames (JPEG)\n", rec.windows.size(), rec.frames.size());

  const FieldGeometry rec_field = recording_field(rec);
  const fs::path db_file = dir / "features.db";
  const FeatureDb db =
      load_or_build_feature_db(rec_field, rec.meta.camera, db_file, [](const std::string&) {});
  const ReplayResult r = replay_recording(rec, LocalizerConfig{}, rec_field, db);
  ASSERT_EQ(r.poses.size(), rec.windows.size());
  ASSERT_EQ(r.frames.size(), rec.frames.size());

  // Every frame's outcome against the truth at its time.
  auto is_bad = [&](double t_ms) {
    return std::find_if(bad.begin(), bad.end(),
                        [&](const BadFrame& b) { return std::abs(b.t_ms - t_ms) < 0.01; });
  };
  int measured = 0, accepted = 0, no_measurement = 0, good_frames = 0;
  double worst_cm = 0.0, sum_cm = 0.0;
  std::vector<double> errors;
  std::string first_reason;
  for (const FrameReport& f : r.frames) {
    const auto b = is_bad(f.t_ms);
    if (b != bad.end()) {
      std::printf("%s frame at %.1f ms: %s, \"%s\"\n", b->what, f.t_ms,
                  frame_outcome_name(f.outcome), f.no_measurement.c_str());
      EXPECT_FALSE(f.no_measurement.empty())
          << b->what << " frame at " << f.t_ms << " ms was measured";
      EXPECT_NE(f.outcome, FrameOutcome::kAccepted) << b->what;
      EXPECT_NE(f.outcome, FrameOutcome::kRelocalized) << b->what;
      continue;
    }
    ++good_frames;
    if (!f.no_measurement.empty()) {
      std::printf("  no measurement at %.1f ms (exposure %.2f): %s\n", f.t_ms, exposure(f.t_ms),
                  f.no_measurement.c_str());
      ++no_measurement;
      if (first_reason.empty()) first_reason = f.no_measurement;
      continue;
    }
    ++measured;
    if (f.outcome != FrameOutcome::kAccepted && f.outcome != FrameOutcome::kRelocalized) continue;
    ++accepted;
    const auto t =
        std::find_if(frame_truth.begin(), frame_truth.end(),
                     [&](const sim::SimFrame& s) { return std::abs(s.t_ms - f.t_ms) < 0.01; });
    ASSERT_NE(t, frame_truth.end()) << f.t_ms;
    const double e =
        std::hypot(f.position_cm.x() - t->truth.x_cm, f.position_cm.y() - t->truth.y_cm);
    worst_cm = std::max(worst_cm, e);
    sum_cm += e;
    errors.push_back(e);
    if (e > 10.0)
      std::printf("  accepted %.1f cm off at %.1f ms (%s, E %.2f)\n", e, f.t_ms,
                  frame_outcome_name(f.outcome), f.error);
    EXPECT_LT(e, 20.0) << "frame at " << f.t_ms << " ms accepted " << e << " cm off";
  }
  const double share = static_cast<double>(accepted) / static_cast<double>(good_frames);
  std::printf(
      "frames: %d good (+%zu bad), %d measured, %d no measurement%s%s; %d accepted as image "
      "measurements (%.1f %%), "
      "error mean %.2f max %.2f cm\n",
      good_frames, bad.size(), measured, no_measurement, first_reason.empty() ? "" : " (first: ",
      first_reason.empty() ? "" : (first_reason + ")").c_str(), accepted, 100.0 * share,
      accepted ? sum_cm / accepted : 0.0, worst_cm);
  if (!errors.empty()) {
    const ErrorSummary es = summarize_errors(errors);
    std::printf("accepted frames' error: median %.2f p95 %.2f cm\n", es.median, es.p95);
  }
  EXPECT_GE(share, 0.80);
  EXPECT_LT(accepted ? sum_cm / accepted : 1e9, 6.0);

  // A bad frame never gives the window it lands in an image pose (one frame per window at 30 Hz).
  for (const BadFrame& b : bad) {
    const auto w = std::find_if(r.poses.begin(), r.poses.end(),
                                [&](const LocalizedPose& p) { return p.t_ms >= b.t_ms; });
    ASSERT_NE(w, r.poses.end());
    EXPECT_NE(w->source, PoseSource::kImage) << b.what << " frame at " << b.t_ms << " ms";
  }

  // The poses with a fix, against truth.csv.
  ASSERT_TRUE(r.position_error_cm.has_value());
  std::printf(
      "replay_recording: %zu poses (%zu without a fix), position error mean %.2f median %.2f p95 "
      "%.2f max %.2f cm; "
      "yaw mean %.2f max %.2f deg; stats: %d frames, %d accepted, %d rejected, %d ambiguous, %d "
      "global searches\n",
      r.poses.size(), r.poses_without_fix, r.position_error_cm->mean, r.position_error_cm->median,
      r.position_error_cm->p95, r.position_error_cm->max, r.yaw_error_deg->mean,
      r.yaw_error_deg->max, r.stats.frames, r.stats.accepted, r.stats.rejected, r.stats.ambiguous,
      r.stats.global_searches);
  EXPECT_LT(r.position_error_cm->mean, 6.0);
  EXPECT_LT(r.position_error_cm->max, 20.0);
  EXPECT_LE(r.poses_without_fix, 10u);

  // `omniloc replay`, the program users run, on the same recording: the library's poses.
  std::string output;
  const int rc =
      test::run_command(std::string(OMNILOC_CLI_PATH) + " replay " + (dir / "rec").string() +
                            " --out " + (dir / "poses.csv").string() + " --db " + db_file.string(),
                        dir / "cli.log", output);
  ASSERT_EQ(rc, 0) << output;
  std::printf("omniloc replay:\n%s", output.c_str());
  test::expect_same_poses(read_poses_csv(dir / "poses.csv"), r.poses);
  if (HasFatalFailure()) return;
  EXPECT_NE(output.find("accepted " + std::to_string(r.stats.accepted) + ","), std::string::npos)
      << output;
  const auto without = std::count_if(r.frames.begin(), r.frames.end(), [](const FrameReport& f) {
    return !f.no_measurement.empty();
  });
  EXPECT_NE(output.find("frames with no measurement " + std::to_string(without) + " "),
            std::string::npos)
      << output;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omniloc
