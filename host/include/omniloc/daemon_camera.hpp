// omnilocd's real camera: OpenCV VideoCapture on a V4L2 device (index or /dev/videoN) or a video
// file, read by its own thread so that a slow or stalled camera never holds up the encoder windows.
// A device's frame is stamped with the V4L2 buffer timestamp when OpenCV gives a plausible one
// (time_source "buffer"), else with the daemon clock when it is read ("host": the daemon subtracts
// camera_latency_ms); a file's frames carry the file's own times ("file") and are handed over at
// them (at the configured rate if the file has none); at its end a file stops delivering (the
// daemon goes odometry-only, as with a camera that dies). docs/DAEMON.md "Camera time".
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
  /// `spec`: all digits -> V4L2 device index; otherwise a device path or video file. `clock` must
  /// be safe to read from another thread (SteadyClock is). Throws std::runtime_error naming `spec`
  /// when it cannot be opened.
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
