// The robot daemon's real I/O without hardware: SteadyClock, and OpenCvCamera on a video file this
// test writes with OpenCV (frames of known grey levels), as omnilocd reads a camera that is a file.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "omniloc/daemon.hpp"
#include "omniloc/daemon_camera.hpp"

namespace {

using namespace omniloc::daemon;
namespace fs = std::filesystem;

struct TempDir {
  fs::path path =
      fs::temp_directory_path() / ("omniloc_test_daemon_io_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

TEST(SteadyClock, StartsAtZeroNeverGoesBackAndWaitsAtLeastAsLongAsAsked) {
  SteadyClock clock;
  const double t0 = clock.now_ms();
  EXPECT_GE(t0, 0.0);
  EXPECT_LT(t0, 1000.0) << "0 at construction";
  double last = t0;
  for (int i = 0; i < 10'000; ++i) {
    const double t = clock.now_ms();
    ASSERT_GE(t, last);
    last = t;
  }
  const double before = clock.now_ms();
  clock.wait_ms(5.0);
  EXPECT_GE(clock.now_ms() - before, 5.0);  // a sleep never returns early
  const double before0 = clock.now_ms();
  clock.wait_ms(0.0);
  clock.wait_ms(-3.0);  // nothing to wait for
  EXPECT_GE(clock.now_ms(), before0);
}

/// Grey level of frame i: far enough apart that JPEG cannot blur one into the next.
int level(int i) {
  return 20 + 20 * i;
}

TEST(OpenCvCamera, ReadsAVideoFileInOrderStampedWithItsOwnTimesThenStops) {
  TempDir dir;
  const fs::path video = dir.path / "grey.avi";
  constexpr int kFrames = 10;
  {
    cv::VideoWriter w(video.string(), cv::CAP_OPENCV_MJPEG,
                      cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 30.0, cv::Size(64, 48));
    ASSERT_TRUE(w.isOpened()) << "OpenCV's own MJPEG writer must be available";
    for (int i = 0; i < kFrames; ++i) w.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(level(i))));
  }
  SteadyClock clock;
  OpenCvCamera camera(video.string(), 100.0, clock);
  EXPECT_NE(camera.describe().find("grey.avi"), std::string::npos);
  std::vector<CameraFrame> frames;
  double last_new_ms = clock.now_ms();
  while (clock.now_ms() - last_new_ms < 1000.0) {  // a file ends: silence
    if (auto f = camera.poll(clock.now_ms())) {
      frames.push_back(std::move(*f));
      last_new_ms = clock.now_ms();
    }
    clock.wait_ms(1.0);
  }
  ASSERT_GE(frames.size(), 3u) << "at 30 fps and a poll every millisecond most frames arrive";
  EXPECT_LE(frames.size(), static_cast<std::size_t>(kFrames));
  int last_index = -1;
  double last_t = -1.0;
  for (const auto& f : frames) {
    ASSERT_EQ(f.bgr.cols, 64);
    ASSERT_EQ(f.bgr.rows, 48);
    const double mean = cv::mean(f.bgr)[0];
    const int index = static_cast<int>(std::lround((mean - 20.0) / 20.0));
    EXPECT_NEAR(mean, level(index), 4.0);
    EXPECT_GT(index, last_index) << "frames come in file order, none twice";
    EXPECT_GT(f.t_ms, last_t);
    EXPECT_EQ(f.time_source, "file");
    // The file's own times (written at 30 fps), not the 100 fps the camera was opened with.
    if (last_index >= 0) EXPECT_NEAR(f.t_ms - last_t, (index - last_index) * 1000.0 / 30.0, 0.01);
    EXPECT_GE(f.handover_ms, f.t_ms - 1e-6);
    EXPECT_LE(f.t_ms, clock.now_ms());
    last_index = index;
    last_t = f.t_ms;
  }
  EXPECT_FALSE(camera.poll(clock.now_ms()).has_value());
}

TEST(OpenCvCamera, RefusesWhatItCannotOpenNamingIt) {
  TempDir dir;
  SteadyClock clock;
  const fs::path not_video = dir.path / "notes.txt";
  std::ofstream(not_video) << "not a video\n";
  for (const std::string& spec : {(dir.path / "missing.avi").string(), not_video.string()}) {
    try {
      OpenCvCamera camera(spec, 30.0, clock);
      ADD_FAILURE() << spec << " opened";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("camera '" + spec + "'"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
