// OpenCV VideoCapture behind FrameSource, on its own thread.
#include "omniloc/daemon_camera.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include <opencv2/videoio.hpp>

namespace omniloc::daemon {

struct OpenCvCamera::Capture {
  cv::VideoCapture cap;
};

OpenCvCamera::OpenCvCamera(const std::string& spec, double fps, DaemonClock& clock)
    : spec_(spec), fps_(fps), clock_(clock), capture_(std::make_unique<Capture>()) {
  const bool index = !spec.empty() && std::all_of(spec.begin(), spec.end(), [](char c) { return c >= '0' && c <= '9'; });
  bool ok = false;
  if (index) {
    ok = capture_->cap.open(std::stoi(spec), cv::CAP_V4L2);
  } else {
    is_file_ = spec.rfind("/dev/", 0) != 0;
    ok = capture_->cap.open(spec, is_file_ ? cv::CAP_ANY : cv::CAP_V4L2);
  }
  if (!ok || !capture_->cap.isOpened())
    throw std::runtime_error("camera '" + spec + "': OpenCV VideoCapture cannot open it" +
                             (index ? " (V4L2 device index)" : is_file_ ? " (video file)" : " (V4L2 device)"));
  if (!is_file_) capture_->cap.set(cv::CAP_PROP_FPS, fps);
  thread_ = std::thread([this] { run(); });
}

OpenCvCamera::~OpenCvCamera() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void OpenCvCamera::run() {
  const auto period = std::chrono::duration<double>(1.0 / fps_);
  auto next = std::chrono::steady_clock::now();
  while (!stop_) {
    cv::Mat frame;
    if (!capture_->cap.read(frame) || frame.empty()) {
      // A file has ended or the device stopped: no more frames. The daemon notices the silence.
      if (is_file_) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    const double t = clock_.now_ms();
    {
      std::lock_guard lock(mu_);
      latest_ = CameraFrame{t, frame};
    }
    if (is_file_) {  // a file would otherwise be read as fast as the disk goes
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
      std::this_thread::sleep_until(next);
    }
  }
}

std::optional<CameraFrame> OpenCvCamera::poll(double now_ms) {
  std::lock_guard lock(mu_);
  if (!latest_ || latest_->t_ms > now_ms) return std::nullopt;
  std::optional<CameraFrame> out = std::move(latest_);
  latest_.reset();
  return out;
}

}  // namespace omniloc::daemon
