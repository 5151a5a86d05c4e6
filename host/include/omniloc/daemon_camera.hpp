// omnilocd's real camera: OpenCV VideoCapture on a V4L2 device (index or /dev/videoN) or a video
// file, read by its own thread so that a slow or stalled camera never holds up the encoder windows.
// A frame is stamped with the daemon's (wall) clock when it is read; a file is paced at the
// configured rate and, at its end, stops delivering (the daemon goes odometry-only, as with a
// camera that dies).
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "omniloc/daemon.hpp"

namespace omniloc::daemon {

class OpenCvCamera final : public FrameSource {
 public:
  /// `spec`: all digits -> V4L2 device index; otherwise a device path or video file. `clock` must be
  /// safe to read from another thread (SteadyClock is). Throws std::runtime_error naming `spec` when
  /// it cannot be opened.
  OpenCvCamera(const std::string& spec, double fps, DaemonClock& clock);
  ~OpenCvCamera() override;
  OpenCvCamera(const OpenCvCamera&) = delete;
  OpenCvCamera& operator=(const OpenCvCamera&) = delete;

  std::optional<CameraFrame> poll(double now_ms) override;
  [[nodiscard]] std::string describe() const override { return "OpenCV camera " + spec_; }

 private:
  void run();
  struct Capture;
  std::string spec_;
  double fps_;
  DaemonClock& clock_;
  bool is_file_ = false;
  std::unique_ptr<Capture> capture_;
  std::mutex mu_;
  std::optional<CameraFrame> latest_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace omniloc::daemon
