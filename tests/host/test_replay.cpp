// Replay end to end: a short simulated run recorded to a REC_DIR (record_simulation), replayed
// with replay_recording; the poses must equal those of the same localizer run live on the same
// simulation (PNG is lossless), and the error figures must agree with the truth file.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "omniloc/recording.hpp"
#include "omniloc_sim/record_sim.hpp"
#include "same_poses.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

TEST(Replay, RecordedSimulationReplaysLikeTheLiveRun) {
  const std::uint64_t seed = 21;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const fs::path dir =
      fs::temp_directory_path() /
      ("omniloc_test_replay_" + std::to_string(::getpid()) + "_" + std::to_string(seed));
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
    RecordingOptions png;  // lossless: the replay must equal the live run exactly
    png.frame_format = FrameFormat::kPng;
    sim::record_simulation(dir, world, renderer, opt, "fira-robosot", std::nullopt, png);
  }
  const Recording rec = load_recording(dir);
  ASSERT_GT(rec.frames.size(), 50u);
  ASSERT_EQ(rec.truth.size(), rec.windows.size());

  // The database through the cache helper: built and saved once, then loaded.
  const fs::path cache = dir / "cache" / feature_db_cache_name(field, camera);
  std::string log1, log2;
  const FeatureDb built =
      load_or_build_feature_db(field, camera, cache, [&](const std::string& s) { log1 = s; });
  const FeatureDb db =
      load_or_build_feature_db(field, camera, cache, [&](const std::string& s) { log2 = s; });
  EXPECT_NE(log1.find("built and saved"), std::string::npos) << log1;
  EXPECT_NE(log2.find("loaded from"), std::string::npos) << log2;
  EXPECT_EQ(built.features, db.features);

  // A --db path that holds something else is never overwritten; a damaged database is rebuilt.
  const fs::path notes = dir / "notes.txt";
  std::ofstream(notes) << "my notes\n";
  EXPECT_THROW((void)load_or_build_feature_db(field, camera, notes, {}), std::runtime_error);
  EXPECT_EQ(fs::file_size(notes), 9u) << "the file was overwritten";
  EXPECT_THROW((void)load_or_build_feature_db(field, camera, dir, {}), std::runtime_error)
      << "a directory";
  {
    std::fstream damage(cache, std::ios::binary | std::ios::in | std::ios::out);
    damage.seekp(1000);
    damage.put('\x7f');
  }
  std::string log3;
  (void)load_or_build_feature_db(field, camera, cache, [&](const std::string& s) { log3 = s; });
  EXPECT_NE(log3.find("unusable"), std::string::npos) << log3;

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
    e.push_back(std::hypot(r.poses[k].pose.x_cm - rec.truth[k].pose.x_cm,
                           r.poses[k].pose.y_cm - rec.truth[k].pose.y_cm));
  }
  std::sort(e.begin(), e.end());
  EXPECT_EQ(r.position_error_cm->count, e.size());
  EXPECT_NEAR(r.position_error_cm->max, e.back(), 1e-9);
  std::printf(
      "replay: %zu poses, position error mean %.2f median %.2f p95 %.2f max %.2f cm; yaw max %.2f "
      "deg\n",
      r.poses.size(), r.position_error_cm->mean, r.position_error_cm->median,
      r.position_error_cm->p95, r.position_error_cm->max, r.yaw_error_deg->max);
  EXPECT_LT(r.position_error_cm->mean, 3.0);
  EXPECT_LT(r.position_error_cm->max, 15.0);
  EXPECT_LT(r.yaw_error_deg->max, 1.0);
  EXPECT_LE(r.poses_without_fix,
            3u);  // the first frame (t = 5 ms) gives the fix at the first window

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

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

/// Runs `omniloc replay ARGS` as a child process (the program users run), stdout and stderr to
/// files; `prefix` goes before it on the shell's line.
int run_replay_command(const std::string& args, const fs::path& out, const fs::path& err,
                       const std::string& prefix = "") {
  const std::string cmd = prefix + std::string(OMNILOC_CLI_PATH) + " replay " + args + " >" +
                          out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// A short simulated straight drive recorded to DIR/rec (seed printed), for the command tests: a
/// fresh DIR (removed first), the drive from `start` to `to`, turning to `yaw_deg`, then 0.1 s
/// still.
fs::path record_straight_drive(const std::string& name, std::uint64_t seed, const Pose2& start,
                               const Eigen::Vector2d& to, double yaw_deg) {
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const fs::path dir = fs::temp_directory_path() /
                       ("omniloc_test_replay_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const RobotConfig robot = load_named_robot_config("default");
  sim::OmniRenderer renderer(load_field("fira-robosot"), load_camera("default"));
  sim::SimRunOptions opt;
  opt.render.seed = seed;
  sim::Trajectory tr("replay " + name, start);
  tr.line_to(to, yaw_deg, sim::MotionLimits{}).wait(0.1);
  sim::World world(sim::WorldConfig::default_noise(robot, seed), tr);
  sim::record_simulation(dir / "rec", world, renderer, opt, "fira-robosot", std::nullopt);
  return dir;
}

// The `omniloc replay` program itself: the poses it writes equal the library's replay of the same
// recording, its summary prints the library's error figures, and a malformed encoders.csv line is
// refused with the file and line named and a non-zero exit.
TEST(ReplayCommand, WritesTheLibrarysPosesAndNamesABadLine) {
  const fs::path dir = record_straight_drive("command", 22, Pose2{420, 300, -20}, {480, 250}, 30);
  const FieldGeometry field = load_field("fira-robosot");
  const CameraModel camera = load_camera("default");
  const fs::path db_file = dir / "features.db";
  const FeatureDb db = load_or_build_feature_db(field, camera, db_file, [](const std::string&) {});
  const Recording rec = load_recording(dir / "rec");
  const ReplayResult lib = replay_recording(rec, LocalizerConfig{}, field, db);
  ASSERT_TRUE(lib.position_error_cm.has_value());

  const std::string common = " --db " + db_file.string();
  ASSERT_EQ(
      run_replay_command((dir / "rec").string() + " --out " + (dir / "poses.csv").string() + common,
                         dir / "stdout.txt", dir / "stderr.txt"),
      0)
      << read_text(dir / "stderr.txt");
  const auto poses = read_poses_csv(dir / "poses.csv");
  test::expect_same_poses(poses, lib.poses);
  if (HasFatalFailure()) return;
  const std::string out = read_text(dir / "stdout.txt");
  char expected[64];
  std::snprintf(expected, sizeof expected, "mean %7.2f  median %7.2f", lib.position_error_cm->mean,
                lib.position_error_cm->median);
  EXPECT_NE(out.find(std::string("position error   ") + expected), std::string::npos) << out;
  std::printf("omniloc replay: %zu poses equal the library's; summary: %s\n", poses.size(),
              expected);

  // Line 5 of encoders.csv (the header is line 1) made unreadable.
  const fs::path enc = dir / "rec" / "encoders.csv";
  std::ifstream in(enc);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  in.close();
  ASSERT_GT(lines.size(), 5u);
  lines[4] = "40.000,4,12,x13,14,15,0.0";
  {
    std::ofstream o(enc);
    for (const auto& l : lines) o << l << "\n";
  }
  EXPECT_EQ(
      run_replay_command((dir / "rec").string() + common, dir / "stdout.txt", dir / "stderr.txt"),
      1);
  const std::string err = read_text(dir / "stderr.txt");
  EXPECT_NE(err.find(enc.string() + ":5:"), std::string::npos) << err;
  std::printf("malformed line refused: %s", err.c_str());
  fs::remove_all(dir);
}

// Issue (hostile input): `omniloc replay --db` on a full disk aborted although the database it had
// just built was in memory, and left a partial file at --db that then blocked the path ("not
// overwriting it"). Now it warns, naming the file and the error, replays all the same (the poses of
// a run with the cache saved), and leaves nothing at the path. The disk fills up as a file size
// limit of 1 MiB (prlimit --fsize, binding root too; SIGXFSZ ignored, so write() fails part-way
// with EFBIG as a full disk's does with ENOSPC): the 5.9 MB database does not fit, poses.csv does.
TEST(ReplayCommand, AFullDiskForTheDatabaseCacheWarnsAndReplaysAnyway) {
  if (std::system("command -v prlimit > /dev/null") != 0) GTEST_SKIP() << "no prlimit";
  const fs::path dir = record_straight_drive("full-disk", 24, Pose2{300, 250, 15}, {340, 270}, 30);
  const fs::path db = dir / "cache" / "features.db";
  const std::string args = (dir / "rec").string() + " --db " + db.string() + " --out ";
  EXPECT_EQ(run_replay_command(args + (dir / "full.csv").string(), dir / "stdout.txt",
                               dir / "stderr.txt", "trap '' XFSZ; prlimit --fsize=1048576 "),
            0);
  const std::string err = read_text(dir / "stderr.txt");
  EXPECT_NE(err.find("warning: no cached database: built, but not saved (" + db.string() +
                     ": write failed: " + std::strerror(EFBIG)),
            std::string::npos)
      << err;
  std::printf("%s", err.substr(0, err.find('\n') + 1).c_str());
  EXPECT_FALSE(fs::exists(db));
  EXPECT_TRUE(fs::is_empty(db.parent_path())) << fs::directory_iterator(db.parent_path())->path();
  // With room on the disk: the cache saved, the same poses.
  EXPECT_EQ(run_replay_command(args + (dir / "room.csv").string(), dir / "stdout.txt",
                               dir / "stderr.txt"),
            0)
      << read_text(dir / "stderr.txt");
  EXPECT_TRUE(fs::exists(db));
  EXPECT_FALSE(read_text(dir / "room.csv").empty());
  EXPECT_EQ(read_text(dir / "full.csv"), read_text(dir / "room.csv"));
  fs::remove_all(dir);
}

// Issue (hostile input): one window of encoders.csv whose gyro_yaw_deg is 1e6, -400, 3600 or
// 1e300 replayed with exit 0 and no warning, the next poses 10-34 cm and up to 110 deg off while
// marked image or integrated. The localizer's GyroYawGuard drops such a yaw (the window's heading
// from the wheels), the replay warns with the window's seq and the count, and the poses stay
// within 2 cm / 1 deg of the clean run's.
TEST(ReplayCommand, AnImplausibleGyroYawIsDroppedWarnedAndDoesNotMoveThePoses) {
  const fs::path dir = record_straight_drive("gyro", 23, Pose2{300, 250, 30}, {400, 300}, 40);
  const FieldGeometry field = load_field("fira-robosot");
  const CameraModel camera = load_camera("default");
  const fs::path db_file = dir / "features.db";
  const FeatureDb db = load_or_build_feature_db(field, camera, db_file, [](const std::string&) {});
  const Recording clean = load_recording(dir / "rec");
  const ReplayResult base = replay_recording(clean, LocalizerConfig{}, field, db);
  ASSERT_GT(clean.windows.size(), 100u);
  EXPECT_EQ(base.stats.gyro_yaw_dropped, 0);
  const std::size_t k = clean.windows.size() / 2;  // moving, with fixes before and after
  // The four values (beyond +-360), and a plausible angle 90 deg from the last (a jump).
  const double jump = wrap_deg(clean.windows[k - 1].gyro_yaw_deg + 90.0);
  for (const double bad : {1e6, -400.0, 3600.0, 1e300, jump}) {
    Recording rec = clean;
    rec.windows[k].gyro_yaw_deg = bad;
    ReplaySettings settings;
    std::vector<std::string> warnings;
    settings.warn = [&](const std::string& w) { warnings.push_back(w); };
    const ReplayResult r = replay_recording(rec, LocalizerConfig{}, field, db, {}, settings);
    ASSERT_EQ(warnings.size(), 1u) << "gyro_yaw_deg " << bad;
    const std::string want =
        "encoders.csv: window seq " + std::to_string(rec.windows[k].seq) + ": gyro_yaw_deg ";
    EXPECT_NE(warnings[0].find(want), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("(1 window(s) dropped so far)"), std::string::npos) << warnings[0];
    EXPECT_EQ(r.stats.gyro_yaw_dropped, 1);
    ASSERT_TRUE(r.poses[k].gyro_yaw_dropped.has_value());
    ASSERT_EQ(r.poses.size(), base.poses.size());
    double worst_cm = 0.0, worst_deg = 0.0;
    for (std::size_t i = k; i < r.poses.size(); ++i) {
      worst_cm = std::max(worst_cm, distance_cm(r.poses[i].pose, base.poses[i].pose));
      worst_deg =
          std::max(worst_deg, std::abs(yaw_difference_deg(r.poses[i].pose, base.poses[i].pose)));
    }
    std::printf(
        "gyro_yaw_deg %g at seq %u: %s; after it at most %.3f cm, %.3f deg from the clean "
        "run\n",
        bad, rec.windows[k].seq, warnings[0].c_str(), worst_cm, worst_deg);
    EXPECT_LT(worst_cm, 2.0) << bad;
    EXPECT_LT(worst_deg, 1.0) << bad;
  }

  // The program: exit 0, the warning on stderr names the file and the window, the count on stdout.
  const fs::path enc = dir / "rec" / "encoders.csv";
  std::ifstream in(enc);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  in.close();
  std::string& line = lines[k + 1];  // the header is line 1
  line = line.substr(0, line.rfind(',')) + ",1e6";
  {
    std::ofstream o(enc);
    for (const auto& l : lines) o << l << "\n";
  }
  ASSERT_EQ(run_replay_command((dir / "rec").string() + " --db " + db_file.string(),
                               dir / "stdout.txt", dir / "stderr.txt"),
            0);
  const std::string err = read_text(dir / "stderr.txt");
  EXPECT_NE(
      err.find("omniloc replay: warning: " + enc.string() + ": window seq " +
               std::to_string(clean.windows[k].seq) + ": gyro_yaw_deg 1e+06 is outside +-360 deg"),
      std::string::npos)
      << err;
  const std::string out = read_text(dir / "stdout.txt");
  EXPECT_NE(out.find("gyro yaw dropped as implausible in 1 window(s)"), std::string::npos) << out;
  fs::remove_all(dir);
}

std::uintmax_t directory_bytes(const fs::path& dir) {
  std::uintmax_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) n += e.file_size();
  return n;
}

// Issue 16 item 8: a PNG recording costs ~12-22 MB/s. The JPEG frame store (the default, quality
// 95) must cost at most 3 MB/s at 30 Hz, 640 x 480, with the replayed poses within 0.5 cm of the
// PNG recording's. The same simulated run (same seed, same rendered frames) is recorded both ways
// and replayed; sizes are of the whole directory (frames, CSVs, meta.json) per second of recording.
TEST(FrameStore, JpegCostsAtMost3MBPerSecondAndReplaysWithinHalfACentimetreOfPng) {
  const std::uint64_t seed = 8;
  std::printf("seed %llu\n", static_cast<unsigned long long>(seed));
  const fs::path dir =
      fs::temp_directory_path() / ("omniloc_test_framestore_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const FieldGeometry field = load_field("fira-robosot");
  const CameraModel camera = load_camera("default");
  ASSERT_EQ(camera.width_px, 640);
  ASSERT_EQ(camera.height_px, 480);
  const RobotConfig robot = load_named_robot_config("default");
  sim::OmniRenderer renderer(field, camera);
  sim::SimRunOptions opt;
  opt.render.seed = seed;
  opt.frame_period_ms = 1000.0 / 30.0;
  const auto record = [&](const fs::path& to, FrameFormat format) {
    sim::Trajectory tr("framestore", Pose2{250, 200, 10});
    tr.line_to({350, 260}, 50, sim::MotionLimits{}).wait(0.1);
    sim::World world(sim::WorldConfig::default_noise(robot, seed), std::move(tr));
    RecordingOptions ro;
    ro.frame_format = format;
    sim::record_simulation(to, world, renderer, opt, "fira-robosot", std::nullopt, ro);
  };
  record(dir / "png", FrameFormat::kPng);
  record(dir / "jpeg", FrameFormat::kJpeg);
  const Recording png = load_recording(dir / "png");
  const Recording jpeg = load_recording(dir / "jpeg");
  ASSERT_EQ(png.windows.size(), jpeg.windows.size());
  ASSERT_EQ(png.frames.size(), jpeg.frames.size());
  const double seconds =
      (png.windows.back().t_end_ms - png.windows.front().t_end_ms + 10.0) / 1000.0;
  const double png_mb_s = static_cast<double>(directory_bytes(dir / "png")) / 1e6 / seconds;
  const double jpeg_mb_s = static_cast<double>(directory_bytes(dir / "jpeg")) / 1e6 / seconds;
  const FeatureDb db = build_feature_db(field, camera, GridSpec::covering(field, 10.0));
  const ReplayResult a = replay_recording(png, LocalizerConfig{}, field, db);
  const ReplayResult b = replay_recording(jpeg, LocalizerConfig{}, field, db);
  ASSERT_EQ(a.poses.size(), b.poses.size());
  double worst_cm = 0.0, worst_yaw = 0.0;
  for (std::size_t i = 0; i < a.poses.size(); ++i) {
    worst_cm = std::max(worst_cm, std::hypot(a.poses[i].pose.x_cm - b.poses[i].pose.x_cm,
                                             a.poses[i].pose.y_cm - b.poses[i].pose.y_cm));
    worst_yaw =
        std::max(worst_yaw, std::abs(wrap_deg(a.poses[i].pose.yaw_deg - b.poses[i].pose.yaw_deg)));
  }
  std::printf(
      "%.2f s at 30 Hz 640 x 480 (%zu frames): PNG %.2f MB/s, JPEG q95 %.2f MB/s (%.1fx smaller); "
      "replayed poses JPEG vs PNG: max %.3f cm, %.3f deg over %zu poses\n",
      seconds, png.frames.size(), png_mb_s, jpeg_mb_s, png_mb_s / jpeg_mb_s, worst_cm, worst_yaw,
      a.poses.size());
  ASSERT_TRUE(a.position_error_cm && b.position_error_cm);
  std::printf("error vs truth: PNG mean %.2f max %.2f cm, JPEG mean %.2f max %.2f cm\n",
              a.position_error_cm->mean, a.position_error_cm->max, b.position_error_cm->mean,
              b.position_error_cm->max);
  EXPECT_LE(jpeg_mb_s, 3.0);
  EXPECT_LE(worst_cm, 0.5);
  EXPECT_GT(png_mb_s, 3.0) << "the PNG store is the one that was too large";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omniloc
