// `omniloc locate` (issue 13 items 4, 5, 7) run as a user runs it (child process) on frames
// rendered at known poses (the simulator's truth), the goal colours telling a pose from its twin on
// frames with goal-coloured boxes painted where the goals stand (projected through the camera at
// the true pose), the Localizer's global search using the same cue, and the real TKU frame on the
// centre spot (calibrated by `omniloc calibrate`, then located).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc/detail/config_reader.hpp"
#include "omniloc/goals.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/locate.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc/vision.hpp"
#include "omniloc_sim/renderer.hpp"
#include "test_data_path.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

using test::test_data;

/// Runs a command line; returns the exit status, stdout in `out` and stderr in `err`.
int run(const std::string& cmd, const fs::path& dir, std::string& out, std::string& err) {
  const fs::path o = dir / "stdout.txt", e = dir / "stderr.txt";
  const int status = std::system((cmd + " >" + o.string() + " 2>" + e.string()).c_str());
  std::ostringstream so, se;
  so << std::ifstream(o).rdbuf();
  se << std::ifstream(e).rdbuf();
  out = so.str();
  err = se.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Goal paint: BGR colours and the HSV models a calibration would learn from them.
const cv::Vec3b kBlueBgr{190, 70, 20};
const cv::Vec3b kYellowBgr{20, 205, 225};

GoalHsv model_of(const cv::Vec3b& bgr) {
  cv::Mat3b px(1, 1, bgr), hsv;
  cv::cvtColor(px, hsv, cv::COLOR_BGR2HSV);
  const cv::Vec3b h = hsv(0, 0);
  return {static_cast<double>(h[0]), 10.0, std::max(0.0, h[1] - 80.0), std::max(0.0, h[2] - 90.0)};
}

GoalColourModels models(GoalColour at_x_max) {
  GoalColourModels m;
  m.blue = model_of(kBlueBgr);
  m.yellow = model_of(kYellowBgr);
  m.colour_at_x_max = at_x_max;
  return m;
}

/// The frame with each goal box (floor behind the goal line, the field file's width and depth)
/// painted in its colour where the camera sees it from `pose`: what the renderer will draw once
/// it renders goals (a box on the floor is the least a goal shows: its walls stand beyond it).
cv::Mat paint_goals(cv::Mat img, const CameraModel& cam, const FieldGeometry& f, const Pose2& pose,
                    GoalColour at_x_max) {
  const double x_max_line = f.border_cm + f.field_length_cm, cy = f.centre_cm().y(),
               w = f.goal.width_cm / 2.0;
  const cv::Vec3b max_bgr = at_x_max == GoalColour::kBlue ? kBlueBgr : kYellowBgr;
  const cv::Vec3b min_bgr = at_x_max == GoalColour::kBlue ? kYellowBgr : kBlueBgr;
  for (int v = 0; v < img.rows; ++v) {
    for (int u = 0; u < img.cols; ++u) {
      const auto rp = cam.robot_point_of_pixel({u, v});
      if (!rp || std::hypot(u - cam.center_px.x(), v - cam.center_px.y()) < cam.min_radius_px())
        continue;
      const Eigen::Vector2d q = pose * *rp;
      if (std::abs(q.y() - cy) > w) continue;
      if (q.x() >= x_max_line && q.x() <= x_max_line + f.goal.depth_cm)
        img.at<cv::Vec3b>(v, u) = max_bgr;
      if (q.x() <= f.border_cm && q.x() >= f.border_cm - f.goal.depth_cm)
        img.at<cv::Vec3b>(v, u) = min_bgr;
    }
  }
  return img;
}

/// The default camera file with a "vision" block holding the goal models (or none).
void write_camera(const fs::path& path, const std::optional<GoalColourModels>& goals,
                  int width = 0) {
  std::ifstream in(resolve_data_file("cameras", "default"));
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(in);
  if (width > 0) j["width"] = width;
  if (goals) {
    auto hsv = [](const GoalHsv& r) {
      return nlohmann::ordered_json{{"hue", r.hue},
                                    {"hue_half_width", r.hue_half_width},
                                    {"sat_min", r.sat_min},
                                    {"val_min", r.val_min}};
    };
    j["vision"]["goals"]["blue"] = hsv(*goals->blue);
    j["vision"]["goals"]["yellow"] = hsv(*goals->yellow);
    if (goals->colour_at_x_max != GoalColour::kUnknown)
      j["vision"]["goal_colour_at_x_max"] = goal_colour_name(goals->colour_at_x_max);
  }
  std::ofstream(path) << j.dump(2);
}

Pose2 twin_of(const FieldGeometry& f, const Pose2& p) {
  const Eigen::Vector2d m = 2.0 * f.centre_cm() - p.position_cm();
  return {m.x(), m.y(), wrap_deg(p.yaw_deg + 180.0)};
}

double distance_to(const nlohmann::json& j, const Pose2& p) {
  return std::hypot(j["x_cm"].get<double>() - p.x_cm, j["y_cm"].get<double>() - p.y_cm);
}

/// The JSON object of the brief: exactly these keys (plus goal_cue and heading_ambiguous) with
/// these types.
void expect_schema(const nlohmann::json& j) {
  ASSERT_TRUE(j.is_object()) << j;
  for (const char* k : {"x_cm", "y_cm", "yaw_deg", "match_error", "time_ms"})
    EXPECT_TRUE(j.at(k).is_number()) << k << ": " << j;
  EXPECT_TRUE(j.at("accepted").is_boolean()) << j;
  EXPECT_TRUE(j.at("ambiguous").is_boolean()) << j;
  EXPECT_TRUE(j.at("heading_ambiguous").is_boolean()) << j;
  EXPECT_TRUE(j.at("rays_used").is_number_integer()) << j;
  EXPECT_TRUE(j.at("goal_cue").is_string()) << j;
  const auto& t = j.at("twin");
  EXPECT_TRUE(t.is_null() || (t.is_object() && t.at("x_cm").is_number() &&
                              t.at("y_cm").is_number() && t.at("yaw_deg").is_number()))
      << j;
  EXPECT_EQ(j.size(), 11u) << j;
}

class LocateProgram : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("omniloc_test_locate_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    field_ = std::make_unique<FieldGeometry>(load_field("fira-robosot"));
    renderer_ = std::make_unique<sim::OmniRenderer>(*field_, load_camera("default"));
    db_ = std::make_unique<FeatureDb>(
        build_feature_db(*field_, renderer_->camera(), GridSpec::covering(*field_, 10.0)));
    save_feature_db(*db_,
                    (dir_ / "db.bin").string());  // every run loads it (--db) instead of building
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_);
    renderer_.reset();
    db_.reset();
    field_.reset();
  }
  /// Runs `omniloc locate IMAGE --camera CAM --db db.bin --json EXTRA`, parses its one JSON line.
  static nlohmann::json locate_json(const fs::path& image, const fs::path& camera,
                                    const std::string& extra, int& rc) {
    std::string out, err;
    rc = run(std::string(OMNILOC_CLI_PATH) + " locate " + image.string() + " --camera " +
                 camera.string() + " --db " + (dir_ / "db.bin").string() + " --json " + extra,
             dir_, out, err);
    std::printf("locate %s %s -> rc %d: %s", image.filename().c_str(), extra.c_str(), rc,
                out.c_str());
    if (!err.empty()) std::printf("  stderr: %s", err.c_str());
    try {
      return nlohmann::json::parse(out);
    } catch (const std::exception&) {
      ADD_FAILURE() << "not one JSON object: " << out << err;
      return {};
    }
  }
  static fs::path write_frame(const std::string& name, const cv::Mat& img) {
    const fs::path p = dir_ / name;
    cv::imwrite(p.string(), img);
    return p;
  }
  static fs::path dir_;
  static std::unique_ptr<FieldGeometry> field_;
  static std::unique_ptr<sim::OmniRenderer> renderer_;
  static std::unique_ptr<FeatureDb> db_;
};
fs::path LocateProgram::dir_;
std::unique_ptr<FieldGeometry> LocateProgram::field_;
std::unique_ptr<sim::OmniRenderer> LocateProgram::renderer_;
std::unique_ptr<FeatureDb> LocateProgram::db_;

TEST_F(LocateProgram, RenderedFramesAtAKnownHeadingLocateWithinAFewCm) {
  const fs::path cam = dir_ / "cam.json";
  write_camera(cam, std::nullopt);
  const Pose2 poses[] = {{200, 150, 30}, {480, 330, -75}, {600, 120, 160}};
  for (std::size_t i = 0; i < std::size(poses); ++i) {
    sim::RenderOptions opt;  // sensor noise, blur and a lighting gradient
    opt.seed = 11 + i;
    const fs::path img =
        write_frame("known" + std::to_string(i) + ".png", renderer_->render(poses[i], opt));
    int rc = -1;
    const nlohmann::json j =
        locate_json(img, cam, "--yaw-deg " + std::to_string(poses[i].yaw_deg), rc);
    EXPECT_EQ(rc, 0);
    expect_schema(j);
    if (!j.is_object()) continue;
    EXPECT_LT(distance_to(j, poses[i]), 5.0) << j;
    EXPECT_NEAR(j["yaw_deg"].get<double>(), poses[i].yaw_deg, 1e-9) << "a given heading is kept";
    EXPECT_TRUE(j["accepted"].get<bool>()) << j;
    EXPECT_FALSE(j["ambiguous"].get<bool>()) << j;
    EXPECT_GT(j["rays_used"].get<int>(), 300) << j;
  }
}

TEST_F(LocateProgram, WithoutAHeadingTheTwinIsAmbiguousUnlessTheGoalColoursTell) {
  const Pose2 truth{520, 380, -120};
  const Pose2 twin = twin_of(*field_, truth);
  sim::RenderOptions opt;
  opt.seed = 5;
  const cv::Mat plain = renderer_->render(truth, opt);
  const cv::Mat painted =
      paint_goals(plain.clone(), renderer_->camera(), *field_, truth, GoalColour::kBlue);
  const fs::path plain_png = write_frame("plain.png", plain),
                 painted_png = write_frame("goals.png", painted);
  const fs::path no_colours = dir_ / "cam-plain.json", blue_max = dir_ / "cam-blue.json",
                 yellow_max = dir_ / "cam-yellow.json";
  write_camera(no_colours, std::nullopt);
  write_camera(blue_max, models(GoalColour::kBlue));
  write_camera(yellow_max, models(GoalColour::kYellow));
  int rc = -1;
  // 1. No colour models: the lines fit pose and twin alike -> ambiguous, not accepted, exit 0.
  const nlohmann::json a = locate_json(painted_png, no_colours, "", rc);
  EXPECT_EQ(rc, 0);
  expect_schema(a);
  EXPECT_TRUE(a["ambiguous"].get<bool>()) << a;
  EXPECT_FALSE(a["accepted"].get<bool>()) << a;
  ASSERT_TRUE(a["twin"].is_object()) << a;
  const double d_pose = std::min(distance_to(a, truth), distance_to(a, twin));
  const double d_twin = std::min(distance_to(a["twin"], truth), distance_to(a["twin"], twin));
  EXPECT_LT(d_pose, 5.0) << a;
  EXPECT_LT(d_twin, 5.0) << a;
  // 2. Colour models, but the frame shows no goal colour: still ambiguous (weak evidence).
  const nlohmann::json b = locate_json(plain_png, blue_max, "", rc);
  EXPECT_EQ(rc, 0);
  EXPECT_TRUE(b["ambiguous"].get<bool>()) << b;
  EXPECT_FALSE(b["accepted"].get<bool>()) << b;
  EXPECT_NE(b["goal_cue"].get<std::string>().find("weak"), std::string::npos) << b;
  // 3. Colour models and painted goals: the true pose, accepted, the twin reported.
  const nlohmann::json c =
      locate_json(painted_png, blue_max, "--overlay " + (dir_ / "overlay.png").string(), rc);
  EXPECT_EQ(rc, 0);
  expect_schema(c);
  EXPECT_FALSE(c["ambiguous"].get<bool>()) << c;
  EXPECT_TRUE(c["accepted"].get<bool>()) << c;
  EXPECT_LT(distance_to(c, truth), 5.0) << c;
  EXPECT_LT(std::abs(angle_diff_deg(c["yaw_deg"].get<double>(), truth.yaw_deg)), 1.0) << c;
  ASSERT_TRUE(c["twin"].is_object()) << c;
  EXPECT_LT(distance_to(c["twin"], twin), 5.0) << c;
  const cv::Mat ov = cv::imread((dir_ / "overlay.png").string());
  EXPECT_EQ(ov.cols, 640);
  EXPECT_GT(cv::norm(ov, painted, cv::NORM_L1), 0.0) << "the overlay draws on the frame";
  // 4. The camera says yellow is at x = max: the same frame now fits the twin.
  const nlohmann::json d = locate_json(painted_png, yellow_max, "", rc);
  EXPECT_FALSE(d["ambiguous"].get<bool>()) << d;
  EXPECT_LT(distance_to(d, twin), 5.0) << d;
  // 5. The camera has the models but not the side; the field file says blue is at x = max.
  const fs::path models_only = dir_ / "cam-models.json", field_blue = dir_ / "field-blue.json";
  write_camera(models_only, models(GoalColour::kUnknown));
  {
    std::ifstream in(resolve_data_file("fields", "fira-robosot"));
    nlohmann::ordered_json f = nlohmann::ordered_json::parse(in);
    f["goal"]["colour_at_x_max"] = "blue";
    std::ofstream(field_blue) << f.dump(2);
  }
  const nlohmann::json e = locate_json(painted_png, models_only, "", rc);
  EXPECT_TRUE(e["ambiguous"].get<bool>()) << "the side unknown: " << e;
  const nlohmann::json g =
      locate_json(painted_png, models_only, "--field " + field_blue.string(), rc);
  EXPECT_FALSE(g["ambiguous"].get<bool>()) << g;
  EXPECT_LT(distance_to(g, truth), 5.0) << g;
}

TEST_F(LocateProgram, UnreadableImageAndCameraOfAnotherSizeExitOne) {
  const fs::path cam = dir_ / "cam.json", wide = dir_ / "cam-800.json", junk = dir_ / "junk.png";
  write_camera(cam, std::nullopt);
  write_camera(wide, std::nullopt, 800);
  std::ofstream(junk) << "not an image";
  std::string out, err;
  const std::string exe = std::string(OMNILOC_CLI_PATH) + " locate ";
  EXPECT_EQ(run(exe + junk.string() + " --camera " + cam.string() + " --json", dir_, out, err), 1);
  EXPECT_NE(err.find("cannot read image"), std::string::npos) << err;
  EXPECT_EQ(
      run(exe + (dir_ / "missing.png").string() + " --camera " + cam.string(), dir_, out, err), 1);
  EXPECT_NE(err.find("cannot read image"), std::string::npos) << err;
  const fs::path img = write_frame("size.png", renderer_->render({300, 200, 0}, sim::noise_free()));
  EXPECT_EQ(run(exe + img.string() + " --camera " + wide.string() + " --json", dir_, out, err), 1);
  EXPECT_NE(err.find("is 640 x 480 px but camera"), std::string::npos) << err;
  EXPECT_NE(err.find("800 x 480"), std::string::npos) << err;

  // Issue (hostile input): a PNG whose IHDR says 20000 x 20000 px (the same bytes otherwise) was
  // decoded (1.2 GB for locate, 5.5 GB and bad_alloc for calibrate) before its size was checked.
  // Both programs refuse it from the header, at once, naming the file and its size.
  std::string bytes;
  {
    std::ifstream in(img, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    bytes = ss.str();
  }
  ASSERT_GT(bytes.size(), 24u);
  for (int i = 0; i < 2; ++i) {  // IHDR width, height: 20000 = 0x00004E20, big-endian
    const std::size_t at = 16 + 4 * static_cast<std::size_t>(i);
    bytes[at] = 0;
    bytes[at + 1] = 0;
    bytes[at + 2] = '\x4e';
    bytes[at + 3] = '\x20';
  }
  const fs::path huge = dir_ / "huge.png";
  std::ofstream(huge, std::ios::binary) << bytes;
  const std::string want =
      huge.string() + ": PNG image of 20000 x 20000 px, more than the 4096 x 4096 px";
  EXPECT_EQ(run(exe + huge.string() + " --camera " + cam.string(), dir_, out, err), 1);
  EXPECT_NE(err.find("omniloc locate: error: cannot read image: " + want), std::string::npos)
      << err;
  EXPECT_EQ(run(std::string(OMNILOC_CLI_PATH) + " calibrate " + huge.string() + " --out " +
                    (dir_ / "huge-cam.json").string(),
                dir_, out, err),
            1);
  EXPECT_NE(err.find("omniloc calibrate: error: cannot read image: " + want), std::string::npos)
      << err;
  // Usage errors are 2: a heading that is not a number, no camera.
  EXPECT_EQ(
      run(exe + img.string() + " --camera " + cam.string() + " --yaw-deg 12x", dir_, out, err), 2);
  EXPECT_EQ(
      run(exe + img.string() + " --camera " + cam.string() + " --yaw-deg nan", dir_, out, err), 2);
  EXPECT_EQ(run(exe + img.string(), dir_, out, err), 2);
  EXPECT_EQ(run(exe + "--help", dir_, out, err), 0);
  EXPECT_NE(out.find("Usage: omniloc locate [OPTIONS] IMAGE"), std::string::npos) << out;
  for (const char* option :
       {"--camera", "--field", "--yaw-deg", "--db", "--config", "--overlay", "--json"})
    EXPECT_NE(out.find(option), std::string::npos) << option << "\n" << out;
}

// Issue 37 (hostile input): a truncated JPEG was located with libjpeg's "Premature end of JPEG
// file" printed without the file's name (the missing rows grey). locate and calibrate refuse it,
// exit 1, naming the file, and libjpeg never gets to print its warning.
TEST_F(LocateProgram, ATruncatedJpegIsRefusedNamingTheFile) {
  const fs::path cam = dir_ / "cam.json";
  write_camera(cam, std::nullopt);
  std::vector<unsigned char> jpg;
  cv::imencode(".jpg", renderer_->render({300, 200, 0}, sim::noise_free()), jpg);
  const fs::path cut = dir_ / "cut.jpg";
  std::ofstream(cut, std::ios::binary)
      .write(reinterpret_cast<const char*>(jpg.data()),
             static_cast<std::streamsize>(jpg.size() / 2));
  const std::string want = cut.string() + ": truncated JPEG";
  std::string out, err;
  EXPECT_EQ(run(std::string(OMNILOC_CLI_PATH) + " locate " + cut.string() + " --camera " +
                    cam.string() + " --yaw-deg 0",
                dir_, out, err),
            1);
  EXPECT_NE(err.find("omniloc locate: error: cannot read image: " + want), std::string::npos)
      << err;
  EXPECT_EQ(err.find("Premature end"), std::string::npos) << err;
  EXPECT_EQ(run(std::string(OMNILOC_CLI_PATH) + " calibrate " + cut.string() + " --out " +
                    (dir_ / "cut-cam.json").string(),
                dir_, out, err),
            1);
  EXPECT_NE(err.find("omniloc calibrate: error: cannot read image: " + want), std::string::npos)
      << err;
  EXPECT_EQ(err.find("Premature end"), std::string::npos) << err;
}

// The Localizer's own global search (no trusted heading) takes the same cue: with the goal colours
// it relocalizes at the true pose where it refused the twin before.
TEST_F(LocateProgram, LocalizerWithoutAHeadingRelocalizesByTheGoalColours) {
  const Pose2 truth{250, 200, 30};
  const cv::Mat img = paint_goals(renderer_->render(truth, sim::RenderOptions{}),
                                  renderer_->camera(), *field_, truth, GoalColour::kYellow);
  LocalizerConfig config;
  config.gyro_yaw_known = false;
  const RobotConfig robot = load_named_robot_config("default");
  EncoderWindow w;
  w.t_end_ms = 10.0;
  Localizer blind(config, robot, *field_, renderer_->camera(), *db_);
  (void)blind.on_window(w);
  EXPECT_EQ(blind.on_image(5.0, img).outcome, FrameOutcome::kAmbiguous)
      << "no colour models: refused";
  Localizer seeing(config, robot, *field_, renderer_->camera(), *db_);
  seeing.set_goal_colours(models(GoalColour::kYellow));
  (void)seeing.on_window(w);
  const FrameReport r = seeing.on_image(5.0, img);
  EXPECT_EQ(r.outcome, FrameOutcome::kRelocalized);
  EXPECT_LT((r.position_cm - truth.position_cm()).norm(), 5.0) << r.position_cm.transpose();
  // The heading of the search without one: estimate_yaw at the best grid point, within its 2 deg
  // step.
  EXPECT_LT(std::abs(angle_diff_deg(r.yaw_deg, truth.yaw_deg)), 2.0) << r.yaw_deg;
}

// No copy: the Localizer's global search is locate_frame, so both give the same pose and error
// on the same scan (here at a known heading, and without one).
TEST_F(LocateProgram, LocalizerGlobalSearchIsLocateFrame) {
  const Pose2 truth{430, 190, 75};
  const cv::Mat img = renderer_->render(truth, sim::RenderOptions{});
  const RobotConfig robot = load_named_robot_config("default");
  for (const bool yaw_known : {true, false}) {
    LocalizerConfig config;
    config.gyro_yaw_known = yaw_known;
    Localizer loc(config, robot, *field_, renderer_->camera(), *db_);
    EncoderWindow w;
    w.t_end_ms = 10.0;
    w.gyro_yaw_deg = truth.yaw_deg;
    (void)loc.on_window(w);
    const FrameReport r = loc.on_image(5.0, img);
    // The same line extraction the Localizer runs on its first frame.
    const BearingScan bearings =
        LineExtractor(renderer_->camera()).extract(img, config.scan_rays_per_degree);
    const SingleFrameResult s =
        locate_frame(config, *field_, renderer_->camera(), *db_, bearings,
                     yaw_known ? std::optional<double>(truth.yaw_deg) : std::nullopt, nullptr);
    EXPECT_TRUE(r.global);
    EXPECT_EQ(r.position_cm, s.match.position_cm);
    EXPECT_EQ(r.yaw_deg, s.pose.yaw_deg);
    EXPECT_EQ(r.error, s.match.error);
    EXPECT_EQ(r.outcome == FrameOutcome::kRelocalized, s.accepted) << frame_outcome_name(r.outcome);
  }
}

TEST(GoalColours, GoalHsvWrapsTheHueAndTheVisionBlockIsValidated) {
  const GoalHsv red{175, 10, 100, 50};
  EXPECT_TRUE(red.contains(3, 200, 200));
  EXPECT_TRUE(red.contains(170, 200, 200));
  EXPECT_FALSE(red.contains(20, 200, 200));
  EXPECT_FALSE(red.contains(175, 99, 200));
  // The camera's "vision" block as the camera reader reads it, seen through goal_colour_models.
  auto read_vision = [](const std::string& text) {
    const auto doc = config::parse_json_text(text, "cam.json");
    VisionModel v;
    config::read_keys(doc.root(), vision_keys(), v);
    v.validate(doc.root().origin());
    return goal_colour_models(v);
  };
  const GoalColourModels m = read_vision(
      R"({"goals": {"blue": {"hue": 110, "hue_half_width": 12, "sat_min": 90, "val_min": 40}}, "goal_colour_at_x_max": "blue"})");
  ASSERT_TRUE(m.blue.has_value());
  EXPECT_EQ(m.blue->hue, 110);
  EXPECT_EQ(m.blue->sat_min, 90);
  EXPECT_FALSE(m.yellow.has_value());
  EXPECT_EQ(m.colour_at_x_max, GoalColour::kBlue);
  EXPECT_EQ(m.cue, GoalCueConfig{});
  EXPECT_EQ(read_vision(R"({"goal_cue": {"min_pixels": 12}})").cue.min_pixels, 12);
  auto error_of = [&](const std::string& text) {
    try {
      (void)read_vision(text);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(
      error_of(
          R"({"goals": {"blue": {"hue": 200, "hue_half_width": 12, "sat_min": 90, "val_min": 40}}})")
          .find("cam.json:goals.blue.hue: must be an OpenCV hue in [0, 180) (got 200)"),
      std::string::npos)
      << error_of(R"({"goals": {"blue": {"hue": 200}}})");
  EXPECT_NE(error_of(R"({"goals": {"red": {}}})").find("cam.json:goals.red"), std::string::npos)
      << error_of(R"({"goals": {"red": {}}})");
  EXPECT_NE(error_of(R"({"goal_colour_at_x_max": "green"})").find("cam.json:goal_colour_at_x_max"),
            std::string::npos)
      << error_of(R"({"goal_colour_at_x_max": "green"})");
  EXPECT_NE(error_of(R"({"goal_cue": {"min_margin": 0}})")
                .find("cam.json:goal_cue.min_margin: must be in (0, 1]"),
            std::string::npos)
      << error_of(R"({"goal_cue": {"min_margin": 0}})");
}

TEST(GoalColours, FieldFileWinsOverTheCamerasLearntColour) {
  FieldGeometry f = load_field("fira-robosot");
  const GoalColourModels m = models(GoalColour::kBlue);
  EXPECT_EQ(goal_colour_at_x_max(f, m), GoalColour::kBlue);
  f.goal.colour_at_x_max = GoalColour::kYellow;
  EXPECT_EQ(goal_colour_at_x_max(f, m), GoalColour::kYellow);
}

// Item 7: the real frame. `omniloc calibrate` on it (centre spot, heading unknown) must converge
// below 2 px (as test_calibration checks), and `omniloc locate` with that camera must return the
// centre spot within 10 cm (either twin: there both lie on the spot) and accept it. This needs the
// new line extraction and match error (other branches); until they land the match error on this
// frame is several times E_TH and the test fails, as it should: nothing here is tuned to it.
TEST(LocateRealFrame, TkuCentreSpotCalibratedThenLocated) {
  const fs::path frame = test_data("tku-robosot-centre-spot.png");
  ASSERT_FALSE(frame.empty()) << "tests/data/tku-robosot-centre-spot.png not found";
  const fs::path dir =
      fs::temp_directory_path() / ("omniloc_test_locate_real_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path cam = dir / "tku-camera.json";
  std::string out, err;
  ASSERT_EQ(run(std::string(OMNILOC_CLI_PATH) + " calibrate " + frame.string() +
                    " --pose 375,275 --mirrored no --out " + cam.string(),
                dir, out, err),
            0)
      << out << err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("residual rms ([0-9.]+) px"))) << out;
  const double rms_px = std::stod(m[1]);
  std::printf("calibrate: residual rms %.2f px\n", rms_px);
  EXPECT_LT(rms_px, 2.0);
  const int rc = run(std::string(OMNILOC_CLI_PATH) + " locate " + frame.string() + " --camera " +
                         cam.string() + " --json --overlay " + (dir / "overlay.png").string(),
                     dir, out, err);
  std::printf("locate on the real frame -> rc %d: %s", rc, out.c_str());
  EXPECT_EQ(rc, 0) << err;
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(out)) << out << err;
  expect_schema(j);
  EXPECT_LT(distance_to(j, {375.0, 275.0, 0.0}), 10.0) << j;
  EXPECT_TRUE(j["accepted"].get<bool>()) << j;
  // On the centre spot the twin stands on the same spot, facing the other way: the position is
  // known, the heading only up to 180 deg (no side is known for this frame).
  EXPECT_FALSE(j["ambiguous"].get<bool>()) << j;
  if (j["heading_ambiguous"].get<bool>()) {
    EXPECT_LT(distance_to(j["twin"], {375.0, 275.0, 0.0}), 10.0) << j;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omniloc
