// The daemon's live view (docs/DAEMON.md "Live view"): with `http_port` set, omnilocd and
// omnilocd-sim serve one web page (everything inline, no internet needed) that shows the field
// with the current pose, its 1-sigma uncertainty and the recent path; the latest camera frame with
// the rays, crossings, carpet boundary and the field model at the pose (locate_overlay, the drawing
// `omniloc locate --overlay` makes); the match error over time; and the status line. The page polls
// JSON endpoints and the frame.
//
// LiveState is fed by the daemon's observer callbacks (attach() chains onto a DaemonObserver, as
// the ROS 2 attachment does) and read by the server's threads: a mutex guards a small snapshot, the
// callbacks only copy (a frame at most every 100 ms), and the costly part (line extraction,
// overlay, encoding) runs in the server's thread when the frame is asked for, at most once per
// frame_min_period_ms (5 Hz): requests in between get the last image again.
//
// LiveViewServer is the HTTP server (cpp-httplib) in its own thread, four worker threads, and a
// waiting room: a connection that has sent nothing yet waits there (one thread polls them all,
// bounded in number and time), not in a worker, so idle connections cannot keep the page from
// being served. In a build without cpp-httplib it throws at construction, saying so.
//
//   GET /            the page (text/html)
//   GET /pose.json   the last pose datagram, exactly as sent over UDP (503 before the first)
//   GET /status.json {"line": last status line, "poses": datagrams seen, "frames": frames seen}
//   GET /state.json  what the page polls: pose, path, match errors, status line, frame info, e_th
//   GET /field.json  the field model: carpet size, segments, arcs, discs, goals (cm)
//   GET /frame.jpg   the latest camera frame with the overlay, JPEG (what the page shows; 503
//   before
//                    the first frame)
//   GET /frame.png   the same, PNG (lossless: the overlay's exact colours)
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "omniloc/daemon.hpp"
#include "omniloc/vision.hpp"

namespace omniloc::live {

struct LiveViewOptions {
  std::string address = "127.0.0.1";  ///< dotted IPv4 address to listen on
  int port = 0;  ///< TCP port; 0: any free port (LiveViewServer::port() says which)
  double frame_min_period_ms = 200.0;  ///< the overlay image is made at most this often (wall time)
  /// a camera frame is copied at most this often (daemon time)
  double frame_keep_period_ms = 100.0;
  double path_s = 20.0;           ///< the path shown: this many seconds of daemon time ...
  double path_step_ms = 50.0;     ///< ... a point every this many ms
  double error_history_s = 30.0;  ///< match errors shown: this many seconds, ...
  double error_step_ms = 100.0;   ///< ... one every this many ms
  /// Connections that have sent nothing yet wait apart from the workers, this many at most (the
  /// oldest is closed for a new one), each for first_byte_timeout_ms at most.
  int max_waiting_connections = 256;
  int first_byte_timeout_ms = 5000;
};

/// What the page shows; every method is thread-safe.
class LiveState {
 public:
  /// `models` must outlive the state (field, camera and localizer config are read from it).
  LiveState(const daemon::DaemonModels& models, LiveViewOptions options = {});
  ~LiveState();
  LiveState(const LiveState&) = delete;
  LiveState& operator=(const LiveState&) = delete;

  /// Chains on_pose, on_frame and on_status onto `observer` (callbacks already there run first).
  /// The state must outlive the daemon's run.
  void attach(daemon::DaemonObserver& observer);

  void on_pose(const daemon::PoseEvent& event);
  void on_frame(const daemon::CameraFrame& frame);
  void on_status(const std::string& line);

  /// The last datagram's text (daemon::pose_json), empty before the first.
  [[nodiscard]] std::string pose_json() const;
  [[nodiscard]] std::string status_json() const;
  [[nodiscard]] std::string state_json() const;
  [[nodiscard]] std::string field_json() const;
  /// The latest frame with the overlay as JPEG (quality 90, what the page shows: ~1 ms to encode)
  /// or PNG (lossless, the overlay's exact colours: ~30 ms), null before the first frame. The
  /// overlay is drawn again only when a newer frame is there and frame_min_period_ms has passed
  /// since the last one; each format is encoded at most once per overlay.
  [[nodiscard]] std::shared_ptr<const std::vector<unsigned char>> frame_jpeg();
  [[nodiscard]] std::shared_ptr<const std::vector<unsigned char>> frame_png();
  /// How many overlays have been drawn (tests: the rate bound).
  [[nodiscard]] std::uint64_t frames_encoded() const;

  /// The page (HTML, CSS and JavaScript in one document).
  [[nodiscard]] static std::string_view page_html();

 private:
  struct PathPoint {
    double t_ms, x_cm, y_cm;
  };
  struct ErrorPoint {
    double t_ms, error;
  };
  const daemon::DaemonModels& models_;
  LiveViewOptions options_;
  mutable std::mutex mutex_;  // guards everything below up to encode_mutex_
  bool have_pose_ = false;
  daemon::PoseMessage pose_;
  std::string pose_text_;
  std::uint64_t poses_ = 0;
  std::deque<PathPoint> path_;
  std::deque<ErrorPoint> errors_;
  std::string status_line_;
  std::uint64_t frames_ = 0;  // frames seen
  cv::Mat frame_;             // the last frame kept (a copy; never written after it is kept)
  std::optional<double> frame_t_ms_;  // none: no frame kept yet
  std::uint64_t frame_seq_ = 0;       // frames kept
  daemon::PoseMessage frame_pose_;    // the pose when it was kept
  bool frame_has_pose_ = false;
  // The last overlay, what it was made from, and its encodings (made on demand).
  cv::Mat overlay_;
  std::uint64_t overlay_seq_ = 0;          // frame_seq_ it was drawn from (0: none yet)
  std::optional<double> overlay_wall_ms_;  // steady clock when drawn (none: no overlay yet)
  std::uint64_t encoded_ = 0;
  ExtractionReport overlay_report_;
  double overlay_t_ms_ = 0.0;
  std::shared_ptr<const std::vector<unsigned char>> png_, jpeg_;
  std::mutex encode_mutex_;  // one overlay and encoding at a time (the extractor has state)
  /// Under encode_mutex_: draws the overlay again if due; false before the first frame.
  bool refresh_overlay();
  std::shared_ptr<const std::vector<unsigned char>> encoded(bool png);
  std::unique_ptr<LineExtractor> extractor_;
};

/// The HTTP server for a LiveState, in a thread of its own.
class LiveViewServer {
 public:
  /// Listens on options.address:options.port. Throws std::runtime_error naming the address and
  /// port when it cannot (port in use, bad address), or when omniloc was built without cpp-httplib.
  LiveViewServer(LiveState& state, const LiveViewOptions& options);
  ~LiveViewServer();
  LiveViewServer(const LiveViewServer&) = delete;
  LiveViewServer& operator=(const LiveViewServer&) = delete;

  /// The port it listens on.
  [[nodiscard]] int port() const;
  /// False in a build without cpp-httplib.
  [[nodiscard]] static bool available();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace omniloc::live
