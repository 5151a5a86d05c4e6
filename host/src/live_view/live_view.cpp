// The live view's state (live_view.hpp): what the observer callbacks copy, and the JSON and the
// overlay image the server hands out.
#include "omniloc/live_view.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omniloc/goals.hpp"
#include "omniloc/locate.hpp"

namespace omniloc::live {

namespace {

double steady_ms() {
  return std::chrono::duration<double, std::milli>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

bool has_pose(daemon::DaemonStatus s) {
  return s != daemon::DaemonStatus::kNoBoard && s != daemon::DaemonStatus::kStarting;
}

// JSON has no NaN or infinity: those become null.
nlohmann::ordered_json number(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

double round_to(double v, double step) {
  return std::round(v / step) * step;
}

}  // namespace

LiveState::LiveState(const daemon::DaemonModels& models, LiveViewOptions options)
    : models_(models),
      options_(std::move(options)),
      extractor_(std::make_unique<LineExtractor>(models.camera)) {}

LiveState::~LiveState() = default;

void LiveState::attach(daemon::DaemonObserver& observer) {
  observer.on_pose = [this, next = std::move(observer.on_pose)](const daemon::PoseEvent& e) {
    if (next) next(e);
    on_pose(e);
  };
  observer.on_frame = [this, next = std::move(observer.on_frame)](const daemon::CameraFrame& f) {
    if (next) next(f);
    on_frame(f);
  };
  observer.on_status = [this, next = std::move(observer.on_status)](const std::string& line) {
    if (next) next(line);
    on_status(line);
  };
}

void LiveState::on_pose(const daemon::PoseEvent& e) {
  std::string text = daemon::pose_json(e.message);
  const std::lock_guard lock(mutex_);
  pose_ = e.message;
  pose_text_ = std::move(text);
  have_pose_ = true;
  ++poses_;
  const double t = e.message.t_ms;
  if (has_pose(e.message.status) &&
      (path_.empty() || t - path_.back().t_ms >= options_.path_step_ms || t < path_.back().t_ms))
    path_.push_back({t, e.message.x_cm, e.message.y_cm});
  while (!path_.empty() &&
         (path_.front().t_ms < t - options_.path_s * 1000.0 || path_.front().t_ms > t))
    path_.pop_front();
  if (e.message.match_error &&
      (errors_.empty() || t - errors_.back().t_ms >= options_.error_step_ms ||
       t < errors_.back().t_ms))
    errors_.push_back({t, *e.message.match_error});
  while (!errors_.empty() &&
         (errors_.front().t_ms < t - options_.error_history_s * 1000.0 || errors_.front().t_ms > t))
    errors_.pop_front();
}

void LiveState::on_frame(const daemon::CameraFrame& f) {
  {
    const std::lock_guard lock(mutex_);
    ++frames_;
    if (f.bgr.empty() || (frame_t_ms_ && f.t_ms >= *frame_t_ms_ &&
                          f.t_ms - *frame_t_ms_ < options_.frame_keep_period_ms))
      return;
  }
  cv::Mat copy = f.bgr.clone();  // outside the lock: the server may be reading the previous one
  const std::lock_guard lock(mutex_);
  frame_ = std::move(copy);
  frame_t_ms_ = f.t_ms;
  ++frame_seq_;
  frame_pose_ = pose_;
  frame_has_pose_ = have_pose_ && has_pose(pose_.status);
}

void LiveState::on_status(const std::string& line) {
  const std::lock_guard lock(mutex_);
  status_line_ = line;
}

std::string LiveState::pose_json() const {
  const std::lock_guard lock(mutex_);
  return pose_text_;
}

std::string LiveState::status_json() const {
  const std::lock_guard lock(mutex_);
  nlohmann::ordered_json j;
  j["line"] = status_line_;
  j["poses"] = poses_;
  j["frames"] = frames_;
  return j.dump();
}

std::string LiveState::state_json() const {
  nlohmann::ordered_json j;
  const std::lock_guard lock(mutex_);
  j["pose"] =
      have_pose_ ? nlohmann::ordered_json::parse(pose_text_) : nlohmann::ordered_json(nullptr);
  j["has_pose"] = have_pose_ && has_pose(pose_.status);
  auto& path = j["path"] = nlohmann::ordered_json::array();
  for (const auto& p : path_)
    path.push_back({round_to(p.t_ms, 0.1), round_to(p.x_cm, 0.01), round_to(p.y_cm, 0.01)});
  auto& errors = j["errors"] = nlohmann::ordered_json::array();
  for (const auto& e : errors_)
    errors.push_back({round_to(e.t_ms, 0.1), number(round_to(e.error, 0.001))});
  j["e_th"] = models_.localizer.e_th;
  j["status_line"] = status_line_;
  j["poses"] = poses_;
  j["frames"] = frames_;
  nlohmann::ordered_json frame;
  frame["t_ms"] = frame_t_ms_ ? number(*frame_t_ms_) : nlohmann::ordered_json(nullptr);
  frame["seq"] = frame_seq_;
  frame["overlay_t_ms"] = encoded_ > 0 ? number(overlay_t_ms_) : nlohmann::ordered_json(nullptr);
  frame["usable"] = overlay_report_.usable;
  frame["reason"] = overlay_report_.reason;
  frame["rays_seen"] = overlay_report_.rays_seen;
  frame["crossings"] = overlay_report_.crossings;
  j["frame"] = frame;
  return j.dump();
}

std::string LiveState::field_json() const {
  const FieldGeometry& f = models_.field;
  nlohmann::ordered_json j;
  j["name"] = f.name;
  j["total_x_cm"] = f.total_x_cm();
  j["total_y_cm"] = f.total_y_cm();
  j["field_length_cm"] = f.field_length_cm;
  j["field_width_cm"] = f.field_width_cm;
  j["border_cm"] = f.border_cm;
  j["line_width_cm"] = f.line_width_cm;
  auto& seg = j["segments"] = nlohmann::ordered_json::array();
  for (const auto& s : f.segments) seg.push_back({s.a_cm.x(), s.a_cm.y(), s.b_cm.x(), s.b_cm.y()});
  auto& arcs = j["arcs"] = nlohmann::ordered_json::array();
  for (const auto& a : f.arcs)
    arcs.push_back({a.centre_cm.x(), a.centre_cm.y(), a.radius_cm, a.start_deg, a.end_deg});
  auto& discs = j["discs"] = nlohmann::ordered_json::array();
  for (const auto& d : f.discs) discs.push_back({d.centre_cm.x(), d.centre_cm.y(), d.radius_cm});
  // The goal boxes behind the goal lines, as locate_overlay draws them: [x of the goal line, x of
  // the back, y of one post, y of the other].
  auto& goals = j["goals"] = nlohmann::ordered_json::array();
  const double cy = f.centre_cm().y(), w = f.goal.width_cm / 2.0;
  for (const double x : {f.border_cm, f.border_cm + f.field_length_cm}) {
    const double back = x < f.centre_cm().x() ? x - f.goal.depth_cm : x + f.goal.depth_cm;
    goals.push_back({x, back, cy - w, cy + w});
  }
  return j.dump();
}

bool LiveState::refresh_overlay() {
  cv::Mat bgr;
  daemon::PoseMessage pose;
  bool with_pose = false;
  std::uint64_t seq = 0;
  double t_ms = 0.0;
  {
    const std::lock_guard lock(mutex_);
    if (!frame_t_ms_) return false;
    if (overlay_wall_ms_ && (frame_seq_ == overlay_seq_ ||
                             steady_ms() - *overlay_wall_ms_ < options_.frame_min_period_ms))
      return true;
    bgr = frame_;  // shares the pixels; on_frame replaces frame_, never writes into it
    pose = frame_pose_;
    with_pose = frame_has_pose_;
    seq = frame_seq_;
    t_ms = *frame_t_ms_;
  }
  // The frame as the localizer sees it (its line extraction, the goal observation), drawn by the
  // overlay `omniloc locate --overlay` makes, with the field model at the daemon's pose.
  ExtractionReport report;
  BearingScan bearings;
  try {
    bearings = extractor_->extract(bgr, models_.localizer.scan_rays_per_degree, &report);
  } catch (const std::invalid_argument& e) {
    report.usable = false;
    report.reason = e.what();
  }
  const GoalObservation goals =
      observe_goals(bgr, models_.camera, models_.field, goal_colour_models(models_.camera.vision));
  SingleFrameResult result;
  if (with_pose) {
    result.pose = Pose2{pose.x_cm, pose.y_cm, pose.yaw_deg};
    result.match.cell = 0;  // "a result": the overlay draws the field model at result.pose
  }
  LocateOverlayInput in;
  in.bearings = bearings.radii_px.empty() ? nullptr : &bearings;
  in.result = &result;
  in.goals = &goals;
  cv::Mat overlay = locate_overlay(bgr, models_.camera, models_.field, in);
  const std::lock_guard lock(mutex_);
  overlay_ = std::move(overlay);
  overlay_seq_ = seq;
  overlay_wall_ms_ = steady_ms();
  overlay_t_ms_ = t_ms;
  overlay_report_ = report;
  png_.reset();
  jpeg_.reset();
  ++encoded_;
  return true;
}

std::shared_ptr<const std::vector<unsigned char>> LiveState::encoded(bool png) {
  const std::lock_guard encode(encode_mutex_);
  if (!refresh_overlay()) return nullptr;
  cv::Mat overlay;
  {
    const std::lock_guard lock(mutex_);
    if (const auto& have = png ? png_ : jpeg_) return have;
    overlay = overlay_;  // replaced, never written, by refresh_overlay (under encode_mutex_ too)
  }
  auto bytes = std::make_shared<std::vector<unsigned char>>();
  if (png)
    cv::imencode(".png", overlay, *bytes, {cv::IMWRITE_PNG_COMPRESSION, 1});
  else
    cv::imencode(".jpg", overlay, *bytes, {cv::IMWRITE_JPEG_QUALITY, 90});
  const std::lock_guard lock(mutex_);
  (png ? png_ : jpeg_) = bytes;
  return bytes;
}

std::shared_ptr<const std::vector<unsigned char>> LiveState::frame_png() {
  return encoded(true);
}

std::shared_ptr<const std::vector<unsigned char>> LiveState::frame_jpeg() {
  return encoded(false);
}

std::uint64_t LiveState::frames_encoded() const {
  const std::lock_guard lock(mutex_);
  return encoded_;
}

}  // namespace omniloc::live
