// The daemon's live view (live_view.hpp, docs/DAEMON.md "Live view"):
// - LiveState in-process: the path and error histories thinned and trimmed as documented, the
//   pose endpoint is the datagram's text, the overlay image is locate_overlay's drawing (the one
//   `omniloc locate --overlay` makes) of the frame, made again only for a newer frame and not
//   more often than its period;
// - LiveViewServer over a socket (a client written here, not cpp-httplib's): every endpoint, 404,
//   a port in use refused by name;
// - omnilocd-sim --http PORT as a program: the JSON pose near the simulator's truth (truth.csv),
//   then headless Chromium loads the page and its screenshot is checked pixel by pixel: the pose
//   marker where the daemon's poses put it on the drawn carpet, the path, and the camera panel
//   showing the overlay's colours (rays, crossings, field model).
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/daemon.hpp"
#include "omniloc/field.hpp"
#include "omniloc/goals.hpp"
#include "omniloc/live_view.hpp"
#include "omniloc/localizer.hpp"
#include "omniloc/locate.hpp"
#include "omniloc/recording.hpp"
#include "omniloc_sim/renderer.hpp"
#include "temp_dir.hpp"
#include "udp_receiver.hpp"

namespace {

namespace fs = std::filesystem;
using namespace omniloc;
using namespace omniloc::live;
using Json = nlohmann::json;

daemon::DaemonModels small_models() {
  daemon::DaemonModels m;
  m.field = load_field("fira-robosot");
  m.camera = load_camera("default");
  m.localizer = load_localizer_config("default");
  return m;  // no database: the live view never matches
}

daemon::PoseEvent pose_at(double t_ms, double x_cm, double y_cm, std::optional<double> error) {
  daemon::PoseEvent e;
  e.message.seq = static_cast<std::uint64_t>(t_ms / 10.0);
  e.message.t_ms = t_ms;
  e.message.x_cm = x_cm;
  e.message.y_cm = y_cm;
  e.message.yaw_deg = 30.0;
  e.message.source = "integrated";
  e.message.match_error = error;
  e.message.uncertainty_cm = 1.5;
  e.message.uncertainty_yaw_deg = 0.4;
  e.message.status = daemon::DaemonStatus::kOk;
  return e;
}

int count_colour(const cv::Mat& bgr, cv::Rect r, cv::Vec3b want, int tol = 0,
                 cv::Point2d* centroid = nullptr) {
  int n = 0;
  double sx = 0, sy = 0;
  r &= cv::Rect(0, 0, bgr.cols, bgr.rows);
  for (int y = r.y; y < r.y + r.height; ++y)
    for (int x = r.x; x < r.x + r.width; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      if (std::abs(p[0] - want[0]) <= tol && std::abs(p[1] - want[1]) <= tol &&
          std::abs(p[2] - want[2]) <= tol) {
        ++n;
        sx += x;
        sy += y;
      }
    }
  if (centroid != nullptr && n > 0) *centroid = {sx / n, sy / n};
  return n;
}

// Pixels of a hue (degrees, 0..360) within tol_deg, saturation >= s_min and value >= v_min
// (0..255): the overlay's colours as they survive JPEG's chroma subsampling (the hue stays, the
// saturation drops on 1 px marks).
int count_hue(const cv::Mat& bgr, cv::Rect r, double hue_deg, double tol_deg, int s_min,
              int v_min) {
  r &= cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (r.empty()) return 0;
  cv::Mat hsv;
  cv::cvtColor(bgr(r), hsv, cv::COLOR_BGR2HSV_FULL);  // hue 0..255 for 0..360 deg
  int n = 0;
  for (int y = 0; y < hsv.rows; ++y)
    for (int x = 0; x < hsv.cols; ++x) {
      const cv::Vec3b p = hsv.at<cv::Vec3b>(y, x);
      const double h = p[0] * 360.0 / 256.0;
      const double d = std::fabs(std::remainder(h - hue_deg, 360.0));
      if (d <= tol_deg && p[1] >= s_min && p[2] >= v_min) ++n;
    }
  return n;
}

// The overlay's colours (locate.hpp: rays grey, crossings magenta, field model yellow), BGR.
const cv::Vec3b kRayGrey{110, 110, 110}, kCrossingMagenta{255, 0, 255}, kModelYellow{0, 255, 255};

TEST(LiveState, PathErrorsAndPoseTextFollowTheDatagrams) {
  const auto models = small_models();
  LiveState s(models);
  EXPECT_EQ(s.pose_json(), "");
  EXPECT_EQ(s.frame_png(), nullptr);
  EXPECT_TRUE(Json::parse(s.state_json())["pose"].is_null());
  daemon::PoseEvent last;
  for (int i = 1; i <= 300; ++i) {  // 3 s of 10 ms windows
    last = pose_at(10.0 * i, 200.0 + i * 0.5, 100.0 + i * 0.25, i * 0.01);
    s.on_pose(last);
  }
  s.on_status("t=3.0s ok pose=(350.0,175.0,30.0)");
  EXPECT_EQ(s.pose_json(), daemon::pose_json(last.message));
  const Json j = Json::parse(s.state_json());
  EXPECT_EQ(j["pose"]["seq"], last.message.seq);
  EXPECT_TRUE(j["has_pose"].get<bool>());
  EXPECT_EQ(j["status_line"], "t=3.0s ok pose=(350.0,175.0,30.0)");
  EXPECT_EQ(j["e_th"], models.localizer.e_th);
  // A path point every 50 ms (10, 60, ..., 2960 ms) and an error every 100 ms (10, 110, ..., 2910).
  ASSERT_EQ(j["path"].size(), 60u);
  EXPECT_EQ(j["path"][0][0], 10.0);
  EXPECT_EQ(j["path"][0][1], 200.5);
  EXPECT_EQ(j["path"][59][0], 2960.0);
  EXPECT_NEAR(j["path"][59][2].get<double>(), 100.0 + 296 * 0.25, 1e-9);
  ASSERT_EQ(j["errors"].size(), 30u);
  EXPECT_NEAR(j["errors"][29][1].get<double>(), 2.91, 1e-9);
  // 20 s of path, 30 s of errors are kept.
  for (int i = 301; i <= 4000; ++i) s.on_pose(pose_at(10.0 * i, 300.0, 200.0, 1.0));
  const Json k = Json::parse(s.state_json());
  EXPECT_GE(k["path"][0][0].get<double>(), 40000.0 - 20000.0);
  EXPECT_LE(k["path"].size(), 401u);
  EXPECT_GE(k["errors"][0][0].get<double>(), 40000.0 - 30000.0);
  // A pose without a fix (starting) is not put on the path, and the page is told there is none.
  auto starting = pose_at(40010.0, 0.0, 0.0, std::nullopt);
  starting.message.status = daemon::DaemonStatus::kStarting;
  s.on_pose(starting);
  EXPECT_FALSE(Json::parse(s.state_json())["has_pose"].get<bool>());
  EXPECT_EQ(Json::parse(s.status_json())["poses"], 4001);
}

TEST(LiveState, FrameIsTheLocateOverlayAtThePoseMadeOnlyForANewerFrameAndAtMostAtItsRate) {
  const auto models = small_models();
  const Pose2 truth{375.0, 275.0, 0.0};
  const cv::Mat bgr = sim::render_omni(models.field, models.camera, truth, {});
  LiveViewOptions never_again;
  never_again.frame_min_period_ms = 1e12;
  LiveState s(models, never_again);
  s.on_pose(pose_at(990.0, truth.x_cm, truth.y_cm, 1.0));
  daemon::CameraFrame f{1000.0, bgr};
  s.on_frame(f);
  const auto png = s.frame_png();
  ASSERT_NE(png, nullptr);
  const cv::Mat got = cv::imdecode(*png, cv::IMREAD_COLOR);
  ASSERT_EQ(got.cols, models.camera.width_px);
  ASSERT_EQ(got.rows, models.camera.height_px);
  // The same drawing `omniloc locate --overlay` makes, from the same extraction, at the pose.
  LineExtractor extractor(models.camera);
  const BearingScan bearings = extractor.extract(bgr, models.localizer.scan_rays_per_degree);
  const GoalObservation goals =
      observe_goals(bgr, models.camera, models.field, goal_colour_models(models.camera.vision));
  SingleFrameResult r;
  r.pose = Pose2{truth.x_cm, truth.y_cm, 30.0};  // the pose the live state was given (yaw 30)
  r.match.cell = 0;
  const cv::Mat want = locate_overlay(bgr, models.camera, models.field, {&bearings, &r, &goals});
  EXPECT_EQ(cv::norm(got, want, cv::NORM_INF), 0.0);
  // The JPEG the page shows: the same overlay (not drawn again), within JPEG's loss.
  const auto jpeg = s.frame_jpeg();
  ASSERT_NE(jpeg, nullptr);
  EXPECT_EQ(s.frame_jpeg(), jpeg);
  EXPECT_EQ(s.frames_encoded(), 1u);
  const cv::Mat got_jpeg = cv::imdecode(*jpeg, cv::IMREAD_COLOR);
  ASSERT_EQ(got_jpeg.size(), want.size());
  const double jpeg_err = cv::norm(got_jpeg, want, cv::NORM_L1) / (want.total() * 3.0);
  const cv::Rect whole(0, 0, want.cols, want.rows);
  const int magenta_png = count_hue(want, whole, 300, 20, 60, 100),
            magenta_jpeg = count_hue(got_jpeg, whole, 300, 20, 60, 100);
  const int yellow_png = count_hue(want, whole, 60, 12, 60, 150),
            yellow_jpeg = count_hue(got_jpeg, whole, 60, 12, 60, 150);
  std::printf(
      "JPEG %zu bytes, PNG %zu bytes; JPEG mean abs error %.2f / 255; magenta-hue pixels %d (PNG "
      "%d), "
      "yellow-hue %d (PNG %d)\n",
      jpeg->size(), png->size(), jpeg_err, magenta_jpeg, magenta_png, yellow_jpeg, yellow_png);
  EXPECT_LT(jpeg_err, 20.0);
  EXPECT_GT(magenta_jpeg, magenta_png / 2);
  EXPECT_GT(yellow_jpeg, yellow_png / 3);  // thin yellow on green carpet: the hue drifts greenwards
  EXPECT_EQ(count_hue(bgr, whole, 300, 20, 60, 100), 0)
      << "the rendered frame has no magenta of its own";
  const cv::Rect all(0, 0, got.cols, got.rows);
  const int magenta = count_colour(got, all, kCrossingMagenta),
            yellow = count_colour(got, all, kModelYellow);
  std::printf("overlay: %d crossing pixels, %d field-model pixels\n", magenta, yellow);
  EXPECT_GT(magenta, 100);
  EXPECT_GT(yellow, 300);
  EXPECT_EQ(count_colour(bgr, all, kCrossingMagenta), 0)
      << "the rendered frame has no overlay colours of its own";
  const Json fr = Json::parse(s.state_json())["frame"];
  EXPECT_EQ(fr["seq"], 1);
  EXPECT_TRUE(fr["usable"].get<bool>());
  EXPECT_GT(fr["crossings"].get<int>(), 20);
  // A frame 50 ms later is not even copied (kept at most every 100 ms); one 200 ms later is, but
  // the period has not passed: the same image again.
  s.on_frame({1050.0, bgr});
  EXPECT_EQ(Json::parse(s.state_json())["frame"]["seq"], 1);
  s.on_frame({1200.0, bgr});
  EXPECT_EQ(Json::parse(s.state_json())["frame"]["seq"], 2);
  EXPECT_EQ(s.frame_png(), png);
  EXPECT_EQ(s.frames_encoded(), 1u);
  // With no period: made again for a newer frame, not for the same one.
  LiveViewOptions always;
  always.frame_min_period_ms = 0.0;
  LiveState t(models, always);
  t.on_frame({1000.0, bgr});
  const auto a = t.frame_png();
  EXPECT_EQ(t.frame_png(), a);
  t.on_frame({1100.0, bgr});
  EXPECT_NE(t.frame_png(), a);
  EXPECT_EQ(t.frames_encoded(), 2u);
  // Without a fix the field model is not drawn (no yellow), the rays still are.
  const cv::Mat nofix = cv::imdecode(*t.frame_png(), cv::IMREAD_COLOR);
  EXPECT_EQ(count_colour(nofix, all, kModelYellow), 0);
  EXPECT_GT(count_colour(nofix, all, kCrossingMagenta), 100);
}

// --- HTTP, with a client of our own ---

struct HttpReply {
  int status = 0;
  std::string headers;
  std::string body;
};

std::optional<HttpReply> http_get(int port, const std::string& path) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return std::nullopt;
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return std::nullopt;
  }
  const std::string req =
      "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  if (::send(fd, req.data(), req.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(req.size())) {
    ::close(fd);
    return std::nullopt;
  }
  std::string all;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    all.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  const auto end = all.find("\r\n\r\n");
  if (all.rfind("HTTP/1.1 ", 0) != 0 || end == std::string::npos) return std::nullopt;
  HttpReply r;
  r.status = std::atoi(all.c_str() + 9);
  r.headers = all.substr(0, end);
  r.body = all.substr(end + 4);
  return r;
}

int free_tcp_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return 0;
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

TEST(LiveViewServer, ServesThePageAndEveryEndpoint) {
  if (!LiveViewServer::available())
    GTEST_SKIP() << "built without cpp-httplib (libcpp-httplib-dev): no live view";
  const auto models = small_models();
  LiveState s(models);
  LiveViewServer server(s, {});
  ASSERT_GT(server.port(), 0);
  // Before any pose or frame: 503 for the pose and the frame, the rest answer.
  EXPECT_EQ(http_get(server.port(), "/pose.json")->status, 503);
  EXPECT_EQ(http_get(server.port(), "/frame.png")->status, 503);
  EXPECT_EQ(http_get(server.port(), "/frame.jpg")->status, 503);
  EXPECT_EQ(http_get(server.port(), "/state.json")->status, 200);
  const auto last = pose_at(1000.0, 375.0, 275.0, 1.0);
  s.on_pose(last);
  s.on_status("t=1.0s ok");
  s.on_frame({1000.0, sim::render_omni(models.field, models.camera, {375.0, 275.0, 30.0}, {})});

  const auto page = http_get(server.port(), "/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->headers.find("text/html"), std::string::npos);
  EXPECT_EQ(page->body, LiveState::page_html());
  for (const char* id : {"id=\"field\"", "id=\"camera\"", "id=\"errors\"", "id=\"status\""})
    EXPECT_NE(page->body.find(id), std::string::npos) << id;
  // Everything inline: nothing fetched from elsewhere (no CDN, works without internet).
  for (const char* outside : {"http://", "https://", "src=\"//", "<link"})
    EXPECT_EQ(page->body.find(outside), std::string::npos) << outside;

  const auto pose = http_get(server.port(), "/pose.json");
  EXPECT_EQ(pose->status, 200);
  EXPECT_NE(pose->headers.find("application/json"), std::string::npos);
  EXPECT_EQ(pose->body, daemon::pose_json(last.message));
  const Json st = Json::parse(http_get(server.port(), "/status.json")->body);
  EXPECT_EQ(st["line"], "t=1.0s ok");
  EXPECT_EQ(st["poses"], 1);
  const Json state = Json::parse(http_get(server.port(), "/state.json")->body);
  EXPECT_EQ(state["pose"]["x_cm"], 375.0);
  const Json field = Json::parse(http_get(server.port(), "/field.json")->body);
  EXPECT_EQ(field["segments"].size(), models.field.segments.size());
  EXPECT_EQ(field["arcs"].size(), models.field.arcs.size());
  EXPECT_EQ(field["total_x_cm"], 750.0);
  EXPECT_EQ(field["total_y_cm"], 550.0);
  const auto png = http_get(server.port(), "/frame.png");
  EXPECT_EQ(png->status, 200);
  EXPECT_NE(png->headers.find("image/png"), std::string::npos);
  const cv::Mat img = cv::imdecode(std::vector<unsigned char>(png->body.begin(), png->body.end()),
                                   cv::IMREAD_COLOR);
  EXPECT_EQ(img.cols, 640);
  EXPECT_GT(count_colour(img, {0, 0, img.cols, img.rows}, kCrossingMagenta), 100);
  const auto jpg = http_get(server.port(), "/frame.jpg");
  EXPECT_EQ(jpg->status, 200);
  EXPECT_NE(jpg->headers.find("image/jpeg"), std::string::npos);
  EXPECT_EQ(
      cv::imdecode(std::vector<unsigned char>(jpg->body.begin(), jpg->body.end()), cv::IMREAD_COLOR)
          .cols,
      640);
  EXPECT_EQ(http_get(server.port(), "/nothing-here")->status, 404);

  // The same port again is refused, naming it.
  LiveViewOptions same;
  same.port = server.port();
  try {
    LiveViewServer second(s, same);
    ADD_FAILURE() << "a second server on port " << server.port() << " started";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":" + std::to_string(server.port())), std::string::npos)
        << e.what();
    std::printf("refused: %s\n", e.what());
  }
}

// A TCP connection to the server that sends nothing (yet).
int idle_connection(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd >= 0 && ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) return fd;
  if (fd >= 0) ::close(fd);
  return -1;
}

// Still open from the server's side: nothing to read and no end of stream (recv would block).
bool still_open(int fd) {
  char c = 0;
  return ::recv(fd, &c, 1, MSG_DONTWAIT) < 0 && (errno == EAGAIN || errno == EWOULDBLOCK);
}

// Idle connections (opened, nothing sent) must not starve the page: with 40 of them open, more than
// the workers, the page still answers (http_get gives up after 5 s: a hang guard) while every one
// of them is still open, i.e. before any idle wait ran out; one that then sends its request late is
// served too. Beyond max_waiting_connections, the oldest idle ones are closed, never the page.
TEST(LiveViewServer, IdleConnectionsDoNotStarveThePage) {
  if (!LiveViewServer::available())
    GTEST_SKIP() << "built without cpp-httplib (libcpp-httplib-dev): no live view";
  const auto models = small_models();
  LiveState s(models);
  LiveViewServer server(s, {});
  std::vector<int> idle;
  for (int i = 0; i < 40; ++i) idle.push_back(idle_connection(server.port()));
  for (const int fd : idle) ASSERT_GE(fd, 0);
  const auto page = http_get(server.port(), "/");
  ASSERT_TRUE(page) << "no page with 40 idle connections open";
  EXPECT_EQ(page->status, 200);
  int open = 0;
  for (const int fd : idle) open += still_open(fd) ? 1 : 0;
  EXPECT_EQ(open, 40) << "the page came only after idle connections were dropped";
  const std::string req =
      "GET /status.json HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  ASSERT_EQ(::send(idle[0], req.data(), req.size(), MSG_NOSIGNAL),
            static_cast<ssize_t>(req.size()));
  timeval tv{5, 0};
  ::setsockopt(idle[0], SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  char buf[32] = {};
  EXPECT_GT(::recv(idle[0], buf, sizeof buf - 1, 0), 12);
  EXPECT_EQ(std::string(buf).rfind("HTTP/1.1 200", 0), 0u) << buf;
  for (const int fd : idle) ::close(fd);

  // The bound: 8 waiting at most; 12 opened, the first 4 are closed by the server.
  LiveViewOptions small;
  small.max_waiting_connections = 8;
  LiveViewServer bounded(s, small);
  std::vector<int> many;
  for (int i = 0; i < 12; ++i) many.push_back(idle_connection(bounded.port()));
  for (int i = 0; i < 12; ++i) {
    char c = 0;
    ::setsockopt(many[i], SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    if (i < 4)
      EXPECT_EQ(::recv(many[i], &c, 1, 0), 0) << "idle connection " << i << " not closed";
    else
      EXPECT_TRUE(still_open(many[i])) << "idle connection " << i;
  }
  // The page still answers (its own connection waits too, and takes an idle one's place).
  const auto page2 = http_get(bounded.port(), "/");
  ASSERT_TRUE(page2);
  EXPECT_EQ(page2->status, 200);
  for (int i = 0; i < 12; ++i) {
    ::close(many[i]);
  }
}

// --- omnilocd-sim --http, and the page in a browser ---

class Child {
 public:
  Child(const std::vector<std::string>& args, const fs::path& log) {
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> argv;
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
  }
  ~Child() {
    if (pid_ > 0 && !done_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  /// SIGTERM, then its exit status (-1: killed after 10 s).
  int stop() {
    ::kill(pid_, SIGTERM);
    for (int i = 0; i < 200; ++i) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        done_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return -1;
  }
  [[nodiscard]] bool running() {
    int status = 0;
    if (done_ || ::waitpid(pid_, &status, WNOHANG) == pid_) done_ = true;
    return !done_;
  }

 private:
  pid_t pid_ = -1;
  bool done_ = false;
};

std::string read_text(const fs::path& p) {
  std::string s;
  if (FILE* f = std::fopen(p.c_str(), "rb")) {
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) s.append(buf, n);
    std::fclose(f);
  }
  return s;
}

std::string find_chromium() {
  for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"})
    if (::access(p, X_OK) == 0) return p;
  return {};
}

double dist_to_segment(cv::Point2d p, cv::Point2d a, cv::Point2d b) {
  const cv::Point2d ab = b - a;
  const double len2 = ab.dot(ab);
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  const cv::Point2d q = a + t * ab;
  return std::hypot(p.x - q.x, p.y - q.y);
}

TEST(OmnilocdSimLiveView, PageShowsThePoseOnTheFieldAndTheCameraOverlay) {
  if (!LiveViewServer::available())
    GTEST_SKIP() << "built without cpp-httplib (libcpp-httplib-dev): no live view";
  const int seed = 3;
  std::printf("seed %d\n", seed);
  omniloc::test::TempDir dir("live_view");
  omniloc::test::UdpReceiver rx;
  const int port = free_tcp_port();
  ASSERT_GT(port, 0);
  const fs::path rec = dir.path / "rec";
  Child daemon(
      {OMNILOCD_SIM_PATH, "--trajectory", "circle", "--seed", std::to_string(seed),
       "--status-period-s", "0.5", "--udp-port", std::to_string(rx.port()), "--control-port", "0",
       "--record-dir", rec.string(), "--http", std::to_string(port)},
      dir.path / "daemon.log");
  // Until the daemon has a fix, a frame, a status line and 1.5 s of path (30 points: the path check
  // below counts its pixels; the page now answers at once, no longer after a worker freed up, so
  // it shows the path as it is then) (simulated time runs at 0.2-0.4x).
  Json state;
  for (int i = 0; i < 600; ++i) {
    ASSERT_TRUE(daemon.running()) << read_text(dir.path / "daemon.log");
    const auto r = http_get(port, "/state.json");
    if (r && r->status == 200) {
      state = Json::parse(r->body);
      if (state["has_pose"].get<bool>() && state["pose"]["status"] == "ok" &&
          state["frame"]["seq"].get<int>() > 0 &&
          !state["status_line"].get<std::string>().empty() && state["path"].size() >= 30)
        break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_TRUE(state.contains("has_pose") && state["has_pose"].get<bool>())
      << read_text(dir.path / "daemon.log");
  EXPECT_NE(read_text(dir.path / "daemon.log")
                .find("live view on http://127.0.0.1:" + std::to_string(port) + "/"),
            std::string::npos);
  const auto pose_reply = http_get(port, "/pose.json");
  ASSERT_TRUE(pose_reply && pose_reply->status == 200);
  const Json pose = Json::parse(pose_reply->body);
  const Json status = Json::parse(http_get(port, "/status.json")->body);
  EXPECT_NE(status["line"].get<std::string>().find("pose=("), std::string::npos) << status.dump();
  const auto frame = http_get(port, "/frame.png");
  ASSERT_TRUE(frame && frame->status == 200);
  const cv::Mat frame_img = cv::imdecode(
      std::vector<unsigned char>(frame->body.begin(), frame->body.end()), cv::IMREAD_COLOR);
  EXPECT_EQ(frame_img.cols, 640);
  const auto jpeg = http_get(port, "/frame.jpg");
  ASSERT_TRUE(jpeg && jpeg->status == 200);
  EXPECT_EQ(cv::imdecode(std::vector<unsigned char>(jpeg->body.begin(), jpeg->body.end()),
                         cv::IMREAD_COLOR)
                .rows,
            480);

  // The browser: headless Chromium renders the page and takes a screenshot.
  const std::string chromium = find_chromium();
  bool shot = false;
  const fs::path png = LIVE_VIEW_SCREENSHOT;
  double t_before = 0, t_after = 0;
  Json after;
  if (!chromium.empty()) {
    fs::create_directories(png.parent_path());
    fs::remove(png);
    t_before = Json::parse(http_get(port, "/pose.json")->body)["t_ms"].get<double>();
    const std::string cmd =
        "HOME=" + dir.path.string() + " timeout 60 " + chromium +
        " --headless --no-sandbox --disable-gpu --hide-scrollbars --no-first-run"
        " --user-data-dir=" +
        (dir.path / "chromium").string() +
        " --window-size=1280,800 --virtual-time-budget=3000 --screenshot=" + png.string() +
        " http://127.0.0.1:" + std::to_string(port) + "/ >" + (dir.path / "chromium.log").string() +
        " 2>&1";
    const int rc = std::system(cmd.c_str());
    after = Json::parse(http_get(port, "/state.json")->body);
    t_after = after["pose"]["t_ms"].get<double>();
    EXPECT_EQ(rc, 0) << read_text(dir.path / "chromium.log");
    shot = fs::exists(png);
    EXPECT_TRUE(shot) << read_text(dir.path / "chromium.log");
  }
  ASSERT_EQ(daemon.stop(), 0) << read_text(dir.path / "daemon.log");

  // The JSON pose against the simulator's truth at its time.
  const Recording recording = load_recording(rec);
  const auto truth = truth_at(recording.truth, pose["t_ms"].get<double>());
  ASSERT_TRUE(truth);
  const double err = std::hypot(pose["x_cm"].get<double>() - truth->x_cm,
                                pose["y_cm"].get<double>() - truth->y_cm);
  std::printf("/pose.json t=%.0f ms (%.1f, %.1f) vs truth (%.1f, %.1f): %.2f cm\n",
              pose["t_ms"].get<double>(), pose["x_cm"].get<double>(), pose["y_cm"].get<double>(),
              truth->x_cm, truth->y_cm, err);
  EXPECT_LT(err, 10.0);
  EXPECT_EQ(pose["status"], "ok");
  if (chromium.empty())
    GTEST_SKIP() << "chromium not found (scripts/deps.sh installs it): the JSON endpoints passed, "
                    "the page's screenshot was not checked";
  if (!shot) return;

  // The screenshot. The carpet (#2e7d32) gives the page's field-to-pixel map: its bounding box is
  // the carpet, [0, 750] x [0, 550] cm, y up.
  const cv::Mat img = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_EQ(img.cols, 1280);
  ASSERT_EQ(img.rows, 800);
  const cv::Rect field_panel(0, 30, 620, 460), camera_panel(625, 35, 650, 490);
  int x0 = img.cols, x1 = -1, y0 = img.rows, y1 = -1;
  for (int y = field_panel.y; y < field_panel.y + field_panel.height; ++y)
    for (int x = field_panel.x; x < field_panel.x + field_panel.width; ++x)
      if (img.at<cv::Vec3b>(y, x) == cv::Vec3b(0x32, 0x7d, 0x2e)) {
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
  ASSERT_GT(x1, x0) << "no carpet drawn";
  const double sx = (x1 - x0 + 1) / 750.0, sy = (y1 - y0 + 1) / 550.0;
  std::printf("carpet drawn at x %d..%d, y %d..%d: %.3f x %.3f px/cm\n", x0, x1, y0, y1, sx, sy);
  EXPECT_NEAR(sx, sy, 0.01) << "the field is not drawn to scale";
  EXPECT_GT(sx, 0.5);
  auto to_px = [&](double x_cm, double y_cm) {
    return cv::Point2d(x0 + x_cm * sx, y1 + 1 - y_cm * sy);
  };
  // The pose marker (#ff1744): on the daemon's path between the poses fetched just before and just
  // after the browser ran (the page drew one of them), within 3 px (about 4 cm).
  cv::Point2d marker;
  const int marker_px = count_colour(img, field_panel, {0x44, 0x17, 0xff}, 12, &marker);
  ASSERT_GT(marker_px, 40) << "no pose marker";
  std::vector<cv::Point2d> poses;
  double worst_truth_cm = 0;
  for (const auto& p : after["path"]) {
    const double t = p[0].get<double>();
    if (t < t_before - 100.0 || t > t_after + 100.0) continue;
    poses.push_back(to_px(p[1].get<double>(), p[2].get<double>()));
    if (const auto tr = truth_at(recording.truth, t))
      worst_truth_cm = std::max(
          worst_truth_cm, std::hypot(p[1].get<double>() - tr->x_cm, p[2].get<double>() - tr->y_cm));
  }
  ASSERT_GE(poses.size(), 2u);
  double best = 1e9;
  for (std::size_t i = 1; i < poses.size(); ++i)
    best = std::min(best, dist_to_segment(marker, poses[i - 1], poses[i]));
  std::printf(
      "marker (%d px) at (%.1f, %.1f) px: %.2f px from the daemon's path between t=%.0f and %.0f "
      "ms "
      "(%zu points, at most %.2f cm from truth)\n",
      marker_px, marker.x, marker.y, best, t_before, t_after, poses.size(), worst_truth_cm);
  EXPECT_LT(best, 3.0);
  EXPECT_LT(worst_truth_cm, 10.0);
  EXPECT_GT(count_colour(img, field_panel, {0xff, 0xe5, 0x00}, 10), 20) << "no path (#00e5ff)";
  // The 2-sigma circle (#ffd600, hue 50 deg) around the marker, drawn at least 1 px in radius (a
  // tracked pose's sigma is a few tenths of a cm: under a pixel at this scale); its outline is
  // about 2 pi r pixels, at least 4.
  const double sigma_cm = after["pose"]["uncertainty_cm"].get<double>();
  const double radius_px = std::max(1.0, 2.0 * sigma_cm * sx);
  const cv::Rect around(static_cast<int>(marker.x) - 12, static_cast<int>(marker.y) - 12, 25, 25);
  const int ring = count_hue(img, around, 50, 8, 150, 200);
  std::printf("2-sigma circle: %d px around the marker (sigma %.2f cm, radius %.1f px)\n", ring,
              sigma_cm, radius_px);
  EXPECT_GE(ring, std::min(5, static_cast<int>(std::floor(4.0 * radius_px))))
      << "no uncertainty circle";
  EXPECT_EQ(count_hue(img, field_panel & cv::Rect(0, 0, 1280, static_cast<int>(marker.y) - 40), 50,
                      8, 150, 200),
            0)
      << "the circle's colour away from the marker";
  // The camera panel shows the overlay: grey rays, magenta crossings, the yellow field model; none
  // of these in the field panel.
  // (The page shows the JPEG: grey within a tolerance, the marks by their hue.)
  const int grey = count_colour(img, camera_panel, kRayGrey, 12),
            magenta = count_hue(img, camera_panel, 300, 20, 60, 100),
            yellow = count_hue(img, camera_panel, 60, 12, 60, 150);
  std::printf("camera panel: %d ray, %d crossing, %d field-model pixels; screenshot %s\n", grey,
              magenta, yellow, png.c_str());
  EXPECT_GT(grey, 200);
  EXPECT_GT(magenta, 50);
  EXPECT_GT(yellow, 200);
  // The marker's antialiased edge over the cyan path can blend to a magenta hue (one such pixel
  // seen at the marker's rim, BGR (143, 106, 152)): the marker's neighbourhood is not a crossing.
  EXPECT_EQ(count_hue(img, field_panel, 300, 20, 60, 100) -
                count_hue(img, field_panel & around, 300, 20, 60, 100),
            0);
}

// The robot's own daemon (no simulator) serves the page too: without a board, no pose, no frame,
// the status says so; a port already in use stops it at start-up with the port named.
TEST(OmnilocdLiveView, RobotDaemonServesTheViewWithoutABoardAndRefusesAPortInUse) {
  if (!LiveViewServer::available())
    GTEST_SKIP() << "built without cpp-httplib (libcpp-httplib-dev): no live view";
  omniloc::test::TempDir dir("live_view_robot");
  omniloc::test::UdpReceiver rx;
  const int port = free_tcp_port();
  Child daemon({OMNILOCD_PATH, "--camera", "none", "--status-period-s", "0.2", "--udp-port",
                std::to_string(rx.port()), "--control-port", "0", "--http", std::to_string(port)},
               dir.path / "daemon.log");
  Json state;
  for (int i = 0; i < 300; ++i) {
    ASSERT_TRUE(daemon.running()) << read_text(dir.path / "daemon.log");
    const auto r = http_get(port, "/state.json");
    if (r && r->status == 200) {
      state = Json::parse(r->body);
      if (!state["pose"].is_null() && !state["status_line"].get<std::string>().empty()) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (read_text(dir.path / "daemon.log").find("board open") != std::string::npos)
    GTEST_SKIP() << "a real omniloc board is plugged in";
  ASSERT_FALSE(state["pose"].is_null()) << read_text(dir.path / "daemon.log");
  EXPECT_EQ(state["pose"]["status"], "no_board");
  EXPECT_FALSE(state["has_pose"].get<bool>());
  EXPECT_EQ(state["path"].size(), 0u);
  EXPECT_NE(state["status_line"].get<std::string>().find("no_board"), std::string::npos)
      << state.dump();
  EXPECT_EQ(http_get(port, "/frame.png")->status, 503);
  EXPECT_EQ(http_get(port, "/")->status, 200);
  // A second daemon on the same port: exit 1, the address and port named.
  std::string out;
  const int rc = std::system((std::string(OMNILOCD_PATH) +
                              " --camera none --duration-s 1 --control-port 0 --udp-port " +
                              std::to_string(rx.port()) + " --http " + std::to_string(port) + " >" +
                              (dir.path / "second.log").string() + " 2>&1")
                                 .c_str());
  out = read_text(dir.path / "second.log");
  EXPECT_EQ(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, 1) << out;
  EXPECT_NE(out.find("omnilocd: error: live view: http://127.0.0.1:" + std::to_string(port) +
                     "/: cannot listen"),
            std::string::npos)
      << out;
  EXPECT_EQ(daemon.stop(), 0) << read_text(dir.path / "daemon.log");
}

}  // namespace
