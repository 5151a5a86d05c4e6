// Recording directories (issue 7 contract): write/read round trip, and clear errors naming the
// file and line for malformed or missing files. Also the error summary used by replay.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <unistd.h>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "config_test_util.hpp"
#include "omniloc/recording.hpp"

namespace omniloc {
namespace {

namespace fs = std::filesystem;

class RecordingFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("omniloc_test_recording_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    meta_.field = "fira-robosot";
    meta_.camera = load_camera("default");
    meta_.robot = load_named_robot_config("default");
    meta_.robot.gear_ratio = 24.0;
    meta_.initial_pose = Pose2{123.5, 234.25, -45.5};
    RecordingOptions png;  // lossless, so that the round trip compares pixels exactly
    png.frame_format = FrameFormat::kPng;
    RecordingWriter w(dir_, meta_, true, png);
    for (int i = 0; i < 5; ++i) {
      EncoderWindow e;
      e.seq = static_cast<std::uint32_t>(100 + i);
      e.t_end_ms = 10.0 * (i + 1);
      e.counts = {i, -2 * i, 300 + i, -70000};
      e.gyro_yaw_deg = -45.5 + 0.25 * i;
      w.add_window(e);
      w.add_truth(e.t_end_ms, Pose2{123.5 + i, 234.25, -45.5 + 0.25 * i});
    }
    for (int i = 0; i < 2; ++i) {
      cv::Mat img(meta_.camera.height_px, meta_.camera.width_px, CV_8UC3,
                  cv::Scalar(10 * i, 100, 50));
      w.add_frame(5.0 + 16.5 * i, img);
    }
    w.close();
  }
  void TearDown() override { fs::remove_all(dir_); }

  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  /// The message of the RecordingError that load_recording throws ("" if none).
  std::string load_error() {
    try {
      (void)load_recording(dir_);
    } catch (const RecordingError& e) {
      return e.what();
    }
    return "";
  }
  void expect_error(const std::string& file, int line, const std::string& needle) {
    const std::string e = load_error();
    const std::string where =
        (dir_ / file).string() + (line > 0 ? ":" + std::to_string(line) + ":" : "");
    EXPECT_NE(e.find(where), std::string::npos) << "want '" << where << "' in: " << e;
    EXPECT_NE(e.find(needle), std::string::npos) << "want '" << needle << "' in: " << e;
  }

  fs::path dir_;
  RecordingMeta meta_;
};

TEST_F(RecordingFiles, RoundTrip) {
  const Recording r = load_recording(dir_);
  EXPECT_EQ(r.meta.field, "fira-robosot");
  EXPECT_TRUE(r.meta.camera == meta_.camera);
  EXPECT_TRUE(r.meta.robot == meta_.robot);
  EXPECT_EQ(r.meta.robot.gear_ratio, 24.0);
  ASSERT_TRUE(r.meta.initial_pose.has_value());
  EXPECT_EQ(r.meta.initial_pose->x_cm, 123.5);
  EXPECT_EQ(r.meta.initial_pose->yaw_deg, -45.5);
  ASSERT_EQ(r.windows.size(), 5u);
  EXPECT_EQ(r.windows[3].seq, 103u);
  EXPECT_EQ(r.windows[3].t_end_ms, 40.0);
  EXPECT_EQ(r.windows[3].counts[0], 3);
  EXPECT_EQ(r.windows[3].counts[1], -6);
  EXPECT_EQ(r.windows[3].counts[2], 303);
  EXPECT_EQ(r.windows[3].counts[3], -70000);
  EXPECT_EQ(r.windows[3].gyro_yaw_deg, -44.75);
  ASSERT_EQ(r.frames.size(), 2u);
  EXPECT_EQ(r.frames[1].t_ms, 21.5);
  EXPECT_EQ(r.frames[1].file, "frames/000001.png");
  const cv::Mat img = load_frame(r, 1);
  EXPECT_EQ(img.at<cv::Vec3b>(10, 10), cv::Vec3b(10, 100, 50));
  ASSERT_EQ(r.truth.size(), 5u);
  EXPECT_EQ(r.truth[4].pose.x_cm, 127.5);
  // truth_at interpolates linearly, yaw the short way.
  const auto t = truth_at(r.truth, 25.0);
  ASSERT_TRUE(t.has_value());
  EXPECT_DOUBLE_EQ(t->x_cm, 125.0);
  EXPECT_DOUBLE_EQ(t->yaw_deg, -45.125);
  EXPECT_FALSE(truth_at(r.truth, 5.0).has_value());
  const std::vector<TruthSample> wrap{{0.0, {0, 0, 170.0}}, {10.0, {0, 0, -170.0}}};
  EXPECT_NEAR(truth_at(wrap, 5.0)->yaw_deg, 180.0, 1e-9);
}

TEST_F(RecordingFiles, WithoutOptionalParts) {
  fs::remove(dir_ / "truth.csv");
  write("meta.json", R"({"field": "fira-robosot",
    "camera": {"width": 640, "height": 480, "center_px": [320, 240], "radius_lut": [[0, 0], [100, 90], [238, 500]],
               "yaw_offset_deg": 0, "mirrored": false},
    "robot": {"wheel_radius_cm": 5, "center_to_wheel_cm": 20, "motor_angle_deg": 45, "gear_ratio": 19,
              "counts_per_rev": 500, "decoding": 4}})");
  const Recording r = load_recording(dir_);
  EXPECT_FALSE(r.meta.initial_pose.has_value());
  EXPECT_TRUE(r.truth.empty());
  EXPECT_EQ(r.meta.camera.radius_lut.size(), 3u);
}

TEST_F(RecordingFiles, CsvErrorsNameFileAndLine) {
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n10,0,1,2,3,4,0.5\n20,1,1,2,x3,4,0.5\n");
  expect_error("encoders.csv", 3,
               "column 'c3': must be an integer in [-2147483648, 2147483647] (got 'x3')");
  // Through the shared strict parser: a count beyond int32, 1.0 for a count, "-1" for seq.
  write("encoders.csv",
        "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n10,0,1,2,3,4,0.5\n20,1,1,2,3000000000,4,0.5\n");
  expect_error("encoders.csv", 3,
               "column 'c3': must be an integer in [-2147483648, 2147483647] (got '3000000000')");
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n10,0,1.0,2,3,4,0.5\n");
  expect_error("encoders.csv", 2, "column 'c1': must be an integer");
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n10,-1,1,2,3,4,0.5\n");
  expect_error("encoders.csv", 2, "column 'seq': must be an integer in [0, 4294967295] (got '-1')");
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n1e999,0,1,2,3,4,0.5\n");
  expect_error("encoders.csv", 2, "column 't_ms': must be a finite number");
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n10,0,1,2,3,4,0.5\n20,1,1,2,3,4\n");
  expect_error("encoders.csv", 3, "expected 7 columns, got 6");
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4\n");
  expect_error("encoders.csv", 1, "header must be 't_ms,seq,c1,c2,c3,c4,gyro_yaw_deg'");
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n10,0,1,2,3,4,0.5\n10,1,1,2,3,4,0.5\n");
  expect_error("encoders.csv", 3, "times must increase");
  write("encoders.csv", "t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg\n10,0,1,2,3,4,nan\n");
  expect_error("encoders.csv", 2, "column 'gyro_yaw_deg': not finite");
  write("encoders.csv", "");
  expect_error("encoders.csv", 1, "empty file");
  fs::remove(dir_ / "encoders.csv");
  expect_error("encoders.csv", 0, "no such file");
}

TEST_F(RecordingFiles, CameraAndTruthErrors) {
  write("camera.csv", "t_ms,file\n5,frames/000000.png\n21.5,frames/missing.png\n");
  expect_error("camera.csv", 3, "image 'frames/missing.png' does not exist");
  write("camera.csv", "t_ms,file\n5,\n");
  expect_error("camera.csv", 2, "column 'file': empty");
  write("camera.csv", "t_ms,file\n5,frames/000000.png\n21.5,frames/000001.png\n");
  write("truth.csv", "t_ms,x_cm,y_cm,yaw_deg\n10,1,2,3\n20,1,2.5.0,3\n");
  expect_error("truth.csv", 3, "column 'y_cm': must be a finite number");
  // A frame whose size is not the camera's.
  write("truth.csv", "t_ms,x_cm,y_cm,yaw_deg\n10,1,2,3\n");
  cv::imwrite((dir_ / "frames/000001.png").string(), cv::Mat(10, 20, CV_8UC3, cv::Scalar(0, 0, 0)));
  const Recording r = load_recording(dir_);
  try {
    (void)load_frame(r, 1);
    FAIL() << "no error";
  } catch (const RecordingError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find((dir_ / "camera.csv").string() + ":3:"), std::string::npos) << s;
    EXPECT_NE(s.find("is 20 x 10, the camera is 640 x 480"), std::string::npos) << s;
  }
}

// Issue 37 (hostile input): a truncated JPEG frame was decoded with libjpeg's "Premature end of
// JPEG file" on stderr, naming no file, and the grey-filled rest replayed as if seen. The replay's
// frames go through read_image_file, which refuses it naming the line of camera.csv and the file.
TEST_F(RecordingFiles, ATruncatedJpegFrameIsRefusedNamingTheFile) {
  std::vector<unsigned char> jpg;
  cv::imencode(".jpg", cv::Mat(480, 640, CV_8UC3, cv::Scalar(10, 100, 50)), jpg);
  const fs::path frame = dir_ / "frames" / "000001.jpg";
  std::ofstream(frame, std::ios::binary)
      .write(reinterpret_cast<const char*>(jpg.data()),
             static_cast<std::streamsize>(jpg.size() / 2));
  write("camera.csv", "t_ms,file\n5,frames/000000.png\n21.5,frames/000001.jpg\n");
  const Recording r = load_recording(dir_);
  try {
    (void)load_frame(r, 1);
    FAIL() << "a truncated JPEG frame was read";
  } catch (const RecordingError& e) {
    const std::string s = e.what();
    EXPECT_NE(s.find((dir_ / "camera.csv").string() + ":3: cannot read image: " + frame.string() +
                     ": truncated JPEG"),
              std::string::npos)
        << s;
  }
}

TEST_F(RecordingFiles, MetaErrorsNameTheFileAndFieldPath) {
  const std::string meta = (dir_ / "meta.json").string();
  const std::string robot =
      R"("robot": {"wheel_radius_cm": 5, "center_to_wheel_cm": 20, "motor_angle_deg": 45, "gear_ratio": 19, "counts_per_rev": 500, "decoding": 4})";
  const std::string camera =
      R"("camera": {"width": 640, "height": 480, "center_px": [320, 240], "radius_lut": [[0, 0], [238, 500]], "yaw_offset_deg": 0, "mirrored": false})";
  const std::string pose = R"("initial_pose": {"x_cm": 1, "y_cm": 2, "yaw_deg": 0})";
  const std::string good =
      "{\"field\": \"fira-robosot\", " + camera + ", " + robot + ", " + pose + "}";
  write("meta.json", good);
  EXPECT_EQ(load_error(), "");
  struct Case {
    std::string json;
    std::string path;
    std::string why;
  };
  using test::replaced;
  const Case cases[] = {
      {"{\"field\": \"fira-robosot\", " + camera + "}", "robot", "missing (required)"},
      {replaced(good, "\"decoding\": 4", "\"decoding\": 3"), "robot.decoding",
       "must be 1, 2 or 4 (got 3)"},
      {replaced(good, "\"y_cm\": 2", "\"y_cm\": \"a\""), "initial_pose.y_cm",
       "must be a number, not a string"},
      {replaced(good, "\"y_cm\": 2", "\"y_cm\": 2, \"z_cm\": 0"), "initial_pose.z_cm",
       "unknown key"},
      {replaced(good, "\"y_cm\": 2", "\"y_cm\": NaN"), "initial_pose.y_cm", "not valid JSON"},
      {replaced(good, "\"y_cm\": 2", "\"y_cm\": 1e400"), "initial_pose.y_cm",
       "number out of range"},
      {replaced(good, "[238, 500]", "[238, 500], [230, 600]"), "camera.radius_lut[2]",
       "strictly increasing"},
      {replaced(good, "\"width\": 640", "\"width\": 640.5"), "camera.width", "must be an integer"},
      {replaced(good, "\"mirrored\": false", "\"mirrored\": 0"), "camera.mirrored",
       "must be true or false"},
      {replaced(good, "\"counts_per_rev\": 500", "\"counts_per_rev\": -500"),
       "robot.counts_per_rev", "(got -500)"},
      {"{\"field\": \"fira-robosot\", " + robot + "}", "camera", "missing (required)"},
      {replaced(good, "\"field\": \"fira-robosot\"", "\"field\": \"\""), "field",
       "must name a geometry"},
      {replaced(good, "\"field\": \"fira-robosot\"", "\"field\": 3"), "field", "must be a string"},
      {replaced(good, "\"field\": \"fira-robosot\"", "\"field\": \"a\", \"field\": \"b\""), "field",
       "duplicate key"},
      {good.substr(0, good.size() - 1) + ", \"extra\": 1}", "extra", "unknown key"},
      {"{\"field\": ", "field", "not valid JSON"},
  };
  for (const Case& c : cases) {
    write("meta.json", c.json);
    const std::string e = load_error();
    EXPECT_EQ(e.rfind(meta + ":" + c.path + ": ", 0), 0u) << "json: " << c.json << "\n got: " << e;
    EXPECT_NE(e.find(c.why), std::string::npos)
        << "want '" << c.why << "'\n json: " << c.json << "\n got: " << e;
  }
  fs::remove(dir_ / "meta.json");
  EXPECT_EQ(load_error(), meta + ": no such file");
  fs::create_directories(dir_ / "meta.json");
  EXPECT_EQ(load_error(), meta + ": is a directory, not a JSON file");
}

TEST_F(RecordingFiles, MetaWriteReadsBackEveryKeyAndEscapesStrings) {
  RecordingMeta m;
  m.field = "C:\\fields\\my \"special\" field.json";  // a path with '\' and '"'
  m.camera.width_px = 800;
  m.camera.height_px = 600;
  m.camera.center_px = {401.5,
                        298.1};  // 298.1 has no exact binary value: written with enough digits
  m.camera.radius_lut = {{0.0, 0.0}, {100.0 / 3.0, 90.0}, {250.0, 450.0}};
  m.camera.yaw_offset_deg = -2.5;
  m.camera.mirrored = true;
  m.camera.body_radius_px = 12.5;
  m.camera.masts = {{90.0, 3.0}, {-45.5, 0.5}};
  m.robot.wheel_radius_cm = 4.5;
  m.robot.center_to_wheel_cm = 18.25;
  m.robot.motor_angle_deg = 30.0;
  m.robot.gear_ratio = 14.0;
  m.robot.counts_per_rev = 512;
  m.robot.decoding = 2;
  m.initial_pose = Pose2{1.0 / 3.0, -7.25, 179.5};
  const fs::path p = dir_ / "meta2.json";
  write_meta(p, m);
  // The text is valid JSON whose field string is the path itself (read with nlohmann directly).
  const auto json = test::read_json(p);
  EXPECT_EQ(json["field"].get<std::string>(), m.field);
  EXPECT_EQ(test::keys_of(json),
            (std::vector<std::string>{"field", "camera", "robot", "initial_pose"}));
  // The robot block holds the recording contract's six keys, as it always did.
  EXPECT_EQ(test::keys_of(json["robot"]),
            (std::vector<std::string>{"wheel_radius_cm", "center_to_wheel_cm", "motor_angle_deg",
                                      "gear_ratio", "counts_per_rev", "decoding"}));
  const RecordingMeta r = read_meta(p);
  EXPECT_EQ(r.field, m.field);
  EXPECT_TRUE(r.camera == m.camera);
  EXPECT_TRUE(r.robot == m.robot);
  ASSERT_TRUE(r.initial_pose.has_value());
  EXPECT_EQ(r.initial_pose->x_cm, 1.0 / 3.0);
  EXPECT_EQ(r.initial_pose->y_cm, -7.25);
  EXPECT_EQ(r.initial_pose->yaw_deg, 179.5);
  // Without an initial pose the key is left out.
  m.initial_pose.reset();
  write_meta(p, m);
  EXPECT_FALSE(test::read_json(p).contains("initial_pose"));
  EXPECT_FALSE(read_meta(p).initial_pose.has_value());
}

TEST_F(RecordingFiles, PosesCsvRoundTrip) {
  const fs::path p = dir_ / "poses.csv";
  PosesCsvWriter w(p);
  LocalizedPose a;
  a.t_ms = 10.0;
  a.pose = {1.5, 2.25, -3.125};
  a.source = PoseSource::kNone;
  w.write(a);
  LocalizedPose b = a;
  b.t_ms = 20.0;
  b.source = PoseSource::kIntegrated;
  b.match_error = 7.5;
  b.search_range_cm = 20.0;
  w.write(b);
  LocalizedPose c = b;  // an image result of a global search: no search range
  c.t_ms = 30.0;
  c.match_error = 3.25;
  c.search_range_cm.reset();
  w.write(c);
  w.close();
  std::ifstream in(p);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "t_ms,x_cm,y_cm,yaw_deg,source,match_error,search_range_cm");
  const auto rows = read_poses_csv(p);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].source, PoseSource::kNone);
  EXPECT_FALSE(rows[0].match_error);  // written "inf"
  EXPECT_FALSE(rows[0].search_range_cm);
  EXPECT_EQ(rows[1].source, PoseSource::kIntegrated);
  EXPECT_EQ(rows[1].pose.yaw_deg, -3.125);
  EXPECT_EQ(rows[1].match_error, 7.5);
  EXPECT_EQ(rows[1].search_range_cm, 20.0);
  EXPECT_EQ(rows[2].match_error, 3.25);
  EXPECT_FALSE(rows[2].search_range_cm);  // written -1
}

// Issue 16 item 4: reusing a record dir silently replaced the previous recording and left its old
// PNGs behind. Now an existing recording is refused; with overwrite it is removed, frames included.
TEST_F(RecordingFiles, AnExistingRecordingIsRefusedUnlessToldAndThenCleanedOut) {
  const std::string e = test::error_of([&] { RecordingWriter w(dir_, meta_, false); });
  EXPECT_EQ(e.rfind(dir_.string() + ": exists and is not empty", 0), 0u) << e;
  EXPECT_TRUE(fs::exists(dir_ / "frames" / "000001.png")) << "the old recording was touched";
  EXPECT_EQ(load_recording(dir_).frames.size(), 2u);
  // A directory with someone's files and no meta.json is refused even with overwrite.
  const fs::path other = dir_.string() + "_other";
  fs::create_directories(other);
  std::ofstream(other / "notes.txt") << "mine";
  RecordingOptions over;
  over.overwrite = true;
  EXPECT_NE(test::error_of([&] {
              RecordingWriter w(other, meta_, false, over);
            }).find("holds no recording"),
            std::string::npos);
  EXPECT_TRUE(fs::exists(other / "notes.txt"));
  fs::remove_all(other);
  {
    RecordingWriter w(dir_, meta_, false, over);
    cv::Mat img(meta_.camera.height_px, meta_.camera.width_px, CV_8UC3, cv::Scalar(1, 2, 3));
    w.add_frame(1.0, img);
    w.close();
  }
  EXPECT_FALSE(fs::exists(dir_ / "frames" / "000000.png")) << "old frames left behind";
  EXPECT_FALSE(fs::exists(dir_ / "frames" / "000001.png"));
  EXPECT_FALSE(fs::exists(dir_ / "truth.csv")) << "the old truth would score the new run";
  EXPECT_TRUE(fs::exists(dir_ / "frames" / "000000.jpg"));
  const Recording r = load_recording(dir_);
  EXPECT_EQ(r.frames.size(), 1u);
  EXPECT_TRUE(r.windows.empty());
  // An empty directory is a new one.
  const fs::path empty = dir_.string() + "_empty";
  fs::create_directories(empty);
  EXPECT_NO_THROW({
    RecordingWriter w(empty, meta_, false);
    w.close();
  });
  fs::remove_all(empty);
}

// Issue 16 item 3: writes were unchecked (fprintf), "write failed" came only at the end and the CSV
// was cut mid-row. With a file size limit (RLIMIT_FSIZE, SIGXFSZ ignored: write(2) then fails with
// EFBIG, as on a full disk with ENOSPC) the failing write throws at once, naming the file and the
// reason, the file keeps whole rows only, and the writer refuses further rows.
TEST_F(RecordingFiles, AFailingWriteStopsTheRecordingWithWholeRowsOnly) {
  fs::remove_all(dir_);
  RecordingWriter w(dir_, meta_, false);
  struct rlimit old {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto previous = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit tiny = old;
  tiny.rlim_cur = 1000;  // bytes per file: encoders.csv fills after ~20 rows
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &tiny), 0);
  std::string error;
  int rows = 0;
  for (; rows < 1000 && error.empty(); ++rows) {
    EncoderWindow e;
    e.seq = static_cast<std::uint32_t>(rows);
    e.t_end_ms = 10.0 * (rows + 1);
    e.counts = {123456, -123456, 7, 8};
    try {
      w.add_window(e);
    } catch (const RecordingError& x) {
      error = x.what();
    }
  }
  std::string frame_error = test::error_of([&] {
    w.add_frame(
        1.0, cv::Mat(meta_.camera.height_px, meta_.camera.width_px, CV_8UC3, cv::Scalar(1, 2, 3)));
  });
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &old), 0);
  std::signal(SIGXFSZ, previous);
  std::printf("stopped after %d rows: %s\n", rows, error.c_str());
  EXPECT_EQ(error, (dir_ / "encoders.csv").string() + ": write failed (File too large)");
  EXPECT_LT(rows, 1000);
  EXPECT_NE(frame_error.find("recording stopped after an error"), std::string::npos) << frame_error;
  // The file ends with a whole row and reads back: every row written before the failure.
  std::ifstream in(dir_ / "encoders.csv", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(read_encoders_csv(dir_ / "encoders.csv").size(), static_cast<std::size_t>(rows - 1));
}

// Issue 16 item 5: meta.json stored --field as given (a relative path broke replay from another
// folder). It now embeds the geometry; recording_field uses it, and an older recording naming a
// path relative to itself still replays. An initial pose of 1e9 cm is refused (item 6).
TEST_F(RecordingFiles, MetaEmbedsTheFieldAndReplaysWithoutItsFile) {
  fs::remove_all(dir_);
  RecordingMeta m = meta_;
  m.field = "fields/does-not-exist.json";
  m.field_geometry = load_field("fira-robosot").spec;
  {
    RecordingWriter w(dir_, m, false);
    w.close();
  }
  const Recording r = load_recording(dir_);
  ASSERT_TRUE(r.meta.field_geometry.has_value());
  EXPECT_TRUE(*r.meta.field_geometry == *m.field_geometry);
  const FieldGeometry f = recording_field(r);
  EXPECT_EQ(f.fingerprint(), load_field("fira-robosot").fingerprint());
  // An old recording: a relative path, the file beside the recording, replay from elsewhere.
  fs::remove_all(dir_);
  RecordingMeta old = meta_;
  old.field = "my-field.json";
  {
    RecordingWriter w(dir_, old, false);
    w.close();
  }
  fs::copy_file(resolve_data_file("fields", "fira-robosot"), dir_ / "my-field.json");
  EXPECT_EQ(recording_field(load_recording(dir_)).fingerprint(), f.fingerprint());
  // The initial pose must be on the carpet (100 cm margin).
  fs::remove_all(dir_);
  RecordingMeta far = m;
  far.initial_pose = Pose2{1e9, 100.0, 0.0};
  {
    RecordingWriter w(dir_, far, false);
    w.close();
  }
  const std::string e = test::error_of([&] { (void)load_recording(dir_); });
  EXPECT_NE(e.find("meta.json:initial_pose.x_cm: must lie on the carpet of field 'fira-robosot'"),
            std::string::npos)
      << e;
}

TEST(ErrorSummary, HandComputed) {
  // 1..20: mean 10.5, median (10 + 11) / 2, p95 = the 19th value (nearest rank ceil(0.95 * 20)).
  std::vector<double> v;
  for (int i = 20; i >= 1; --i) v.push_back(i);
  const ErrorSummary s = summarize_errors(v);
  EXPECT_EQ(s.count, 20u);
  EXPECT_DOUBLE_EQ(s.mean, 10.5);
  EXPECT_DOUBLE_EQ(s.median, 10.5);
  EXPECT_DOUBLE_EQ(s.p95, 19.0);
  EXPECT_DOUBLE_EQ(s.max, 20.0);
  const ErrorSummary one = summarize_errors({3.0, 1.0, 2.0});
  EXPECT_DOUBLE_EQ(one.median, 2.0);
  EXPECT_DOUBLE_EQ(one.p95, 3.0);
  EXPECT_THROW((void)summarize_errors({}), std::invalid_argument);
}

}  // namespace
}  // namespace omniloc
