// OpenCV VideoCapture behind FrameSource, on its own thread.
#include "omniloc/daemon_camera.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <opencv2/videoio.hpp>

namespace omniloc::daemon {

struct OpenCvCamera::Capture {
  cv::VideoCapture cap;
};

OpenCvCamera::OpenCvCamera(const std::string& spec, double fps, DaemonClock& clock)
    : spec_(spec), fps_(fps), clock_(clock), capture_(std::make_unique<Capture>()) {
  const bool index = !spec.empty() && std::all_of(spec.begin(), spec.end(),
                                                  [](char c) { return c >= '0' && c <= '9'; });
  bool ok = false;
  if (index) {
    ok = capture_->cap.open(std::stoi(spec), cv::CAP_V4L2);
  } else {
    is_file_ = spec.rfind("/dev/", 0) != 0;
    ok = capture_->cap.open(spec, is_file_ ? cv::CAP_ANY : cv::CAP_V4L2);
  }
  if (!ok || !capture_->cap.isOpened())
    throw std::runtime_error("camera '" + spec + "': OpenCV VideoCapture cannot open it" +
                             (index      ? " (V4L2 device index)"
                              : is_file_ ? " (video file)"
                                         : " (V4L2 device)"));
  if (!is_file_) capture_->cap.set(cv::CAP_PROP_FPS, fps);
  thread_ = std::thread([this] { run(); });
}

OpenCvCamera::~OpenCvCamera() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

// A V4L2 buffer timestamp older than this (or in the future) is not taken: it is not on the
// monotonic clock (some drivers stamp on the wall clock) or not a capture time at all.
constexpr double kMaxBufferAgeMs = 1000.0;

namespace {

using Ms = std::chrono::duration<double, std::milli>;

// A device's frame: CAP_PROP_POS_MSEC is the dequeued buffer's timestamp (OpenCV's V4L2 backend;
// CLOCK_MONOTONIC for uvcvideo and most drivers: the steady clock here), 0 before the first frame.
// A plausible one (up to kMaxBufferAgeMs old) dates the frame; else the handover time does, and
// the daemon subtracts camera_latency_ms.
void stamp_device_frame(CameraFrame& f, double pos_ms, double now_ms) {
  f.handover_ms = now_ms;
  f.t_ms = f.handover_ms;
  f.time_source = "host";  // the daemon subtracts camera_latency_ms
  const double age_ms = Ms(std::chrono::steady_clock::now().time_since_epoch()).count() - pos_ms;
  if (std::isfinite(pos_ms) && pos_ms > 0.0 && age_ms >= -1.0 && age_ms <= kMaxBufferAgeMs) {
    f.t_ms = f.handover_ms - std::max(age_ms, 0.0);
    f.time_source = "buffer";
  }
}

// A file's own times: frame k is stamped and handed over at first_daemon + (pos_k - first_pos),
// until a frame shows the file has none (0, not increasing): then the configured rate paces it
// and frames are stamped when read.
struct FileTimes {
  bool on = true;
  double first_pos_ms = -1.0, first_daemon_ms = 0.0, last_pos_ms = -1.0;

  // Stamps a file's frame read at pos_ms, waiting for its time while the file's times hold.
  void stamp(CameraFrame& f, double pos_ms, DaemonClock& clock, const std::atomic<bool>& stop) {
    const bool has_time =
        std::isfinite(pos_ms) && pos_ms >= 0.0 && (last_pos_ms < 0.0 ? true : pos_ms > last_pos_ms);
    if (on && !has_time) on = false;
    if (on) {
      if (first_pos_ms < 0.0) {
        first_pos_ms = pos_ms;
        first_daemon_ms = clock.now_ms();
      }
      last_pos_ms = pos_ms;
      f.t_ms = first_daemon_ms + (pos_ms - first_pos_ms);
      // Waited on the daemon clock itself, so a frame is never handed over before it was taken
      // (a steady-clock deadline set beside it was 0.08 ms early under a sanitizer).
      for (double left_ms; !stop && (left_ms = f.t_ms - clock.now_ms()) > 0.0;)
        std::this_thread::sleep_for(Ms(std::min(left_ms, 20.0)));
    } else {
      f.t_ms = clock.now_ms();
    }
    f.time_source = "file";
    f.handover_ms = clock.now_ms();
  }
};

}  // namespace

void OpenCvCamera::run() {
  using Steady = std::chrono::steady_clock;
  const auto period = std::chrono::duration<double>(1.0 / fps_);
  auto next = Steady::now();
  FileTimes file{is_file_};
  while (!stop_) {
    cv::Mat frame;
    if (!capture_->cap.read(frame) || frame.empty()) {
      // A file has ended or the device stopped: no more frames. The daemon notices the silence.
      if (is_file_) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    // CAP_PROP_POS_MSEC: for a file, the frame's presentation time; for a V4L2 device, the
    // buffer's timestamp. docs/DAEMON.md "Camera time".
    const double pos_ms = capture_->cap.get(cv::CAP_PROP_POS_MSEC);
    CameraFrame f;
    f.bgr = frame;
    if (is_file_)
      file.stamp(f, pos_ms, clock_, stop_);
    else
      stamp_device_frame(f, pos_ms, clock_.now_ms());
    {
      std::lock_guard lock(mu_);
      latest_ = std::move(f);
    }
    if (is_file_ && !file.on) {  // a file would otherwise be read as fast as the disk goes
      next += std::chrono::duration_cast<Steady::duration>(period);
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
