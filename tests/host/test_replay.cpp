// Replay end to end: a short simulated run recorded to a REC_DIR (record_simulation), replayed
// with replay_recording; the poses must equal those of the same localizer run live on the same
// simulation (PNG is lossless), and the error figures must agree with the truth file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

#include "omniloc/recording.hpp"
#include "omniloc_sim/record_sim.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

TEST(Replay, RecordedSimulationReplaysLikeTheLiveRun) {
  const std::uint64_t seed = 21;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const fs::path dir = fs::temp_directory_path() / ("omniloc_test_replay_" + std::to_string(::getpid()) + "_" + std::to_string(seed));
  fs::remove_all(dir);
  const FieldGeometry field = load_field("fira-robosot");
  const CameraModel camera = load_camera("default");
  const RobotConfig robot = load_named_robot_config("default");
  sim::OmniRenderer renderer(field, camera);
  auto trajectory = [] {
    sim::Trajectory tr("replay", Pose2{250, 200, 10});
    tr.line_to({330, 240}, 40, sim::MotionLimits{}).wait(0.1);
    return tr;
  };
  sim::SimRunOptions opt;
  opt.render.seed = seed;
  {
    sim::World world(sim::WorldConfig::default_noise(robot, seed), trajectory());
    sim::record_simulation(dir, world, renderer, opt, "fira-robosot", std::nullopt);
  }
  const Recording rec = load_recording(dir);
  ASSERT_GT(rec.frames.size(), 50u);
  ASSERT_EQ(rec.truth.size(), rec.windows.size());

  // The database through the cache helper: built and saved once, then loaded.
  const fs::path cache = dir / "cache" / feature_db_cache_name(field, camera);
  std::string log1, log2;
  const FeatureDb built = load_or_build_feature_db(field, camera, cache, [&](const std::string& s) { log1 = s; });
  const FeatureDb db = load_or_build_feature_db(field, camera, cache, [&](const std::string& s) { log2 = s; });
  EXPECT_NE(log1.find("built and saved"), std::string::npos) << log1;
  EXPECT_NE(log2.find("loaded from"), std::string::npos) << log2;
  EXPECT_EQ(built.features, db.features);

  const ReplayResult r = replay_recording(rec, LocalizerConfig{}, field, db);
  ASSERT_EQ(r.poses.size(), rec.windows.size());

  // Live run of the same simulation.
  sim::World world(sim::WorldConfig::default_noise(robot, seed), trajectory());
  Localizer live(LocalizerConfig{}, robot, field, camera, db);
  const sim::LocalizedRun run = sim::localize_simulation(world, renderer, opt, live);
  ASSERT_EQ(run.poses.size(), r.poses.size());
  double worst_diff = 0.0;
  for (std::size_t k = 0; k < r.poses.size(); ++k) {
    EXPECT_EQ(r.poses[k].source, run.poses[k].source) << k;
    worst_diff = std::max(worst_diff, std::hypot(r.poses[k].pose.x_cm - run.poses[k].pose.x_cm,
                                                 r.poses[k].pose.y_cm - run.poses[k].pose.y_cm));
  }
  EXPECT_LT(worst_diff, 1e-3);
  EXPECT_EQ(r.stats.accepted, live.stats().accepted);

  // Error figures, recomputed here from truth.csv (window ends are truth rows).
  ASSERT_TRUE(r.position_error_cm.has_value());
  std::vector<double> e;
  for (std::size_t k = 0; k < r.poses.size(); ++k) {
    if (r.poses[k].source == PoseSource::kNone) continue;
    ASSERT_EQ(rec.truth[k].t_ms, r.poses[k].t_ms);
    e.push_back(std::hypot(r.poses[k].pose.x_cm - rec.truth[k].pose.x_cm, r.poses[k].pose.y_cm - rec.truth[k].pose.y_cm));
  }
  std::sort(e.begin(), e.end());
  EXPECT_EQ(r.position_error_cm->count, e.size());
  EXPECT_NEAR(r.position_error_cm->max, e.back(), 1e-9);
  std::printf("replay: %zu poses, position error mean %.2f median %.2f p95 %.2f max %.2f cm; yaw max %.2f deg\n",
              r.poses.size(), r.position_error_cm->mean, r.position_error_cm->median, r.position_error_cm->p95,
              r.position_error_cm->max, r.yaw_error_deg->max);
  EXPECT_LT(r.position_error_cm->mean, 3.0);
  EXPECT_LT(r.position_error_cm->max, 15.0);
  EXPECT_LT(r.yaw_error_deg->max, 1.0);
  EXPECT_LE(r.poses_without_fix, 3u);  // the first frame (t = 5 ms) gives the fix at the first window

  // poses.csv written and read back.
  {
    PosesCsvWriter w(dir / "poses.csv");
    for (const auto& p : r.poses) w.write(p);
    w.close();
  }
  const auto back = read_poses_csv(dir / "poses.csv");
  ASSERT_EQ(back.size(), r.poses.size());
  EXPECT_NEAR(back.back().pose.x_cm, r.poses.back().pose.x_cm, 1e-3);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omniloc
