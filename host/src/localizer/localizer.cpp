// The integration localizer: Fig. 15's flow on Fig. 16's timeline (see localizer.hpp).
#include "omniloc/localizer.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace omniloc {

namespace {

Pose2 lerp_pose(const Pose2& a, const Pose2& b, double f) {
  return {a.x_cm + f * (b.x_cm - a.x_cm), a.y_cm + f * (b.y_cm - a.y_cm),
          wrap_deg(a.yaw_deg + f * angle_diff_deg(b.yaw_deg, a.yaw_deg))};
}

double distance_cm(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return (a - b).norm(); }

Eigen::Vector2d xy(const Pose2& p) { return {p.x_cm, p.y_cm}; }

}  // namespace

Localizer::Localizer(const LocalizerConfig& config, const RobotConfig& robot, const FieldGeometry& field,
                     const CameraModel& camera, const FeatureDb& db, std::optional<Pose2> initial_pose)
    : config_(config), robot_(robot), field_(field), camera_(camera), db_(db), odometry_(robot) {
  validate_localizer_config(config_, "localizer config");
  if (db.field_fingerprint != field.fingerprint() || db.camera_fingerprint != camera.fingerprint())
    throw std::invalid_argument("Localizer: the feature database was built for another field or camera");
  match_options_.refinement = config_.refinement;
  if (initial_pose) {
    odometry_.reset(*initial_pose, 0.0, 0.0);
    state_ = State::kTracking;
    anchor_ = {true, 0.0, *initial_pose, *initial_pose, kNoError};
    last_good_ = true;
  }
  last_pose_.pose = initial_pose.value_or(Pose2{});
  last_pose_.source = initial_pose ? PoseSource::kIntegrated : PoseSource::kNone;
}

bool Localizer::covered(double t_ms) const { return !history_.empty() && history_.back().window.t_end_ms >= t_ms; }

Pose2 Localizer::odometry_pose_at(double t_ms, double* speed_cm_per_s, double* sigma_xy_cm) const {
  if (history_.empty()) {
    if (speed_cm_per_s) *speed_cm_per_s = 0.0;
    if (sigma_xy_cm) *sigma_xy_cm = odometry_.estimate().sigma_xy_cm;
    return odometry_.estimate().pose;
  }
  // Last entry at or before t (history is sorted by time); before the first window the odometry
  // stands at its origin, which the first window's start shares.
  auto after = std::upper_bound(history_.begin(), history_.end(), t_ms,
                                [](double t, const HistoryEntry& e) { return t < e.window.t_end_ms; });
  const OdometryEstimate* lo = nullptr;
  const OdometryEstimate* hi = nullptr;
  double t_lo = 0.0, t_hi = 0.0;
  if (after == history_.begin()) {
    const OdometryEstimate& e = history_.front().odometry.estimate();
    if (speed_cm_per_s) *speed_cm_per_s = e.speed_cm_per_s;
    if (sigma_xy_cm) *sigma_xy_cm = e.sigma_xy_cm;
    return e.pose;  // the start is at rest or the history is too short: no better estimate
  }
  lo = &std::prev(after)->odometry.estimate();
  t_lo = std::prev(after)->window.t_end_ms;
  if (after == history_.end()) {
    if (speed_cm_per_s) *speed_cm_per_s = lo->speed_cm_per_s;
    if (sigma_xy_cm) *sigma_xy_cm = lo->sigma_xy_cm;
    return lo->pose;
  }
  hi = &after->odometry.estimate();
  t_hi = after->window.t_end_ms;
  const double f = (t_ms - t_lo) / (t_hi - t_lo);
  if (speed_cm_per_s) *speed_cm_per_s = hi->speed_cm_per_s;  // the window that contains t
  if (sigma_xy_cm) *sigma_xy_cm = lo->sigma_xy_cm + f * (hi->sigma_xy_cm - lo->sigma_xy_cm);
  return lerp_pose(lo->pose, hi->pose, f);
}

void Localizer::reset_origin_at(double t_ms, const Pose2& pose, double sigma_xy_cm, double sigma_yaw_deg) {
  ++stats_.origin_resets;
  last_reset_ms_ = t_ms;
  if (history_.empty()) {
    odometry_.reset(pose, sigma_xy_cm, sigma_yaw_deg);
    return;
  }
  // Reset at the last window k ending at or before t, shifted back by the odometry's own motion
  // from t_k to t, then re-integrate the windows after k: the result is applied at the image time.
  auto after = std::upper_bound(history_.begin(), history_.end(), t_ms,
                                [](double t, const HistoryEntry& e) { return t < e.window.t_end_ms; });
  auto k = after == history_.begin() ? history_.begin() : std::prev(after);
  const Pose2 at_t = odometry_pose_at(t_ms, nullptr, nullptr);
  const Pose2 at_k = k->odometry.estimate().pose;
  const Pose2 origin{pose.x_cm - (at_t.x_cm - at_k.x_cm), pose.y_cm - (at_t.y_cm - at_k.y_cm),
                     wrap_deg(pose.yaw_deg - angle_diff_deg(at_t.yaw_deg, at_k.yaw_deg))};
  Odometry o = k->odometry;
  o.reset(origin, sigma_xy_cm, sigma_yaw_deg);
  k->odometry = o;
  for (auto it = std::next(k); it != history_.end(); ++it) {
    o.update(it->window);
    it->odometry = o;
  }
  odometry_ = o;
}

void Localizer::set_anchor(double t_ms, const Pose2& pose, double error) {
  anchor_.valid = true;
  anchor_.t_ms = t_ms;
  anchor_.pose = pose;
  anchor_.odometry_at_t = odometry_pose_at(t_ms, nullptr, nullptr);
  anchor_.error = error;
}

void Localizer::trim_history() {
  if (history_.empty()) return;
  const double keep_from = history_.back().window.t_end_ms - config_.history_ms;
  while (history_.size() > 2 && history_[1].window.t_end_ms < keep_from) {
    history_.pop_front();
    trimmed_ = true;
  }
}

LocalizedPose Localizer::on_window(const EncoderWindow& window) {
  if (!history_.empty() && !(window.t_end_ms > history_.back().window.t_end_ms)) {
    std::ostringstream os;
    os << "Localizer: encoder window seq " << window.seq << " at t=" << window.t_end_ms
       << " ms does not come after the previous one (seq " << history_.back().window.seq << " at t="
       << history_.back().window.t_end_ms << " ms)";
    throw std::invalid_argument(os.str());
  }
  odometry_.update(window);
  history_.push_back({window, odometry_});
  applied_this_window_ = false;
  while (!pending_.empty() && covered(pending_.front().t_ms)) {
    PendingFrame f = std::move(pending_.front());
    pending_.pop_front();
    reports_.push_back(process(f.t_ms, f.bearings));
  }
  trim_history();
  last_pose_ = make_pose(window);
  return last_pose_;
}

FrameReport Localizer::on_image(double t_ms, const cv::Mat& bgr) {
  return on_bearings(t_ms, scan_image_bearings(bgr, camera_, config_.scan_rays_per_degree));
}

FrameReport Localizer::on_bearings(double t_ms, BearingScan bearings) {
  if (!std::isfinite(t_ms)) throw std::invalid_argument("Localizer: frame time is not finite");
  if (!covered(t_ms)) {
    // Keep frames in time order; a frame older than a waiting one is still fine to queue.
    auto pos = std::upper_bound(pending_.begin(), pending_.end(), t_ms,
                                [](double t, const PendingFrame& f) { return t < f.t_ms; });
    pending_.insert(pos, PendingFrame{t_ms, std::move(bearings)});
    if (pending_.size() > kMaxPending) {
      FrameReport dropped;
      dropped.t_ms = pending_.front().t_ms;
      dropped.outcome = FrameOutcome::kDropped;
      reports_.push_back(dropped);
      pending_.pop_front();
      ++stats_.frames;
      ++stats_.dropped;
    }
    FrameReport r;
    r.t_ms = t_ms;
    return r;
  }
  FrameReport r = process(t_ms, bearings);
  reports_.push_back(r);
  return r;
}

void Localizer::resync() {
  const Pose2 pose = last_pose_.pose;
  const double sigma = last_pose_.sigma_xy_cm;
  odometry_ = Odometry(robot_);
  odometry_.reset(pose, sigma, last_pose_.sigma_yaw_deg);
  history_.clear();
  pending_.clear();
  trimmed_ = false;
  anchor_.valid = false;
  last_reset_ms_ = -1e300;
  last_check_ms_ = -1e300;
  disagree_run_ = 0;
}

std::vector<FrameReport> Localizer::take_frame_reports() {
  std::vector<FrameReport> out;
  out.swap(reports_);
  return out;
}

FrameReport Localizer::process(double t_ms, const BearingScan& bearings) {
  FrameReport rep;
  rep.t_ms = t_ms;
  ++stats_.frames;
  if (trimmed_ && t_ms < history_.front().window.t_end_ms) {
    rep.outcome = FrameOutcome::kDropped;
    ++stats_.dropped;
    return rep;
  }
  const bool full = config_.mode == LocalizerMode::kFull;
  double speed = 0.0, odo_sigma = 0.0;
  const Pose2 odo = odometry_pose_at(t_ms, &speed, &odo_sigma);
  rep.speed_cm_per_s = speed;
  // Prediction: the last good image carried forward by odometry (the output), else odometry.
  Pose2 predicted = odo;
  double predicted_sigma = odo_sigma;
  if (anchor_.valid) {
    predicted.x_cm = anchor_.pose.x_cm + (odo.x_cm - anchor_.odometry_at_t.x_cm);
    predicted.y_cm = anchor_.pose.y_cm + (odo.y_cm - anchor_.odometry_at_t.y_cm);
    const double moved = distance_cm(xy(odo), xy(anchor_.odometry_at_t));
    predicted_sigma = std::hypot(config_.image_sigma_cm, robot_.odometry_noise_fraction * moved);
  }
  const double yaw = odo.yaw_deg;  // gyro heading (the odometry's yaw follows the gyro)
  const Scan scan = rotate_to_field(bearings, yaw);

  auto refine = [&](MatchResult& m, const Scan& s) {
    if (config_.refinement != Refinement::kNone && m.cell >= 0) interpolate_match(db_, s, m);
    if (config_.refinement == Refinement::kRayCast && m.cell >= 0) refine_match(field_, camera_, s, m, match_options_);
  };
  // With ray-cast refinement the error is judged at the refined position: the error surface is
  // so steep that a grid point 5 cm away from the robot often scores above E_TH.
  auto judged_error = [&](const MatchResult& m) {
    return config_.refinement == Refinement::kRayCast ? m.refined_error : m.error;
  };
  auto relocalize = [&](const Eigen::Vector2d& p, double yaw_deg, double error) {
    const Pose2 pose{p.x(), p.y(), yaw_deg};
    reset_origin_at(t_ms, pose, config_.image_sigma_cm, config_.image_sigma_yaw_deg);
    set_anchor(t_ms, pose, error);
    state_ = State::kTracking;
    bad_run_ = 0;
    disagree_run_ = 0;
    last_good_ = true;
    applied_this_window_ = true;
    last_image_ms_ = t_ms;
    ++stats_.relocalizations;
    rep.outcome = FrameOutcome::kRelocalized;
  };
  // A global search: at the gyro heading, or over all headings when it is not trusted.
  auto global = [&](double* yaw_out) {
    ++stats_.global_searches;
    rep.global = true;
    if (full && !config_.gyro_yaw_known) {
      PoseMatch pm = global_search_any_yaw(db_, field_, camera_, bearings, 2.0, match_options_);
      *yaw_out = pm.yaw_deg;
      pm.match.error = judged_error(pm.match);
      return pm.match;
    }
    MatchResult m = global_search(db_, scan, match_options_);
    refine(m, scan);
    m.error = judged_error(m);
    *yaw_out = yaw;
    return m;
  };

  if (state_ == State::kSearching || state_ == State::kLost) {
    double gyaw = yaw;
    const MatchResult g = global(&gyaw);
    rep.position_cm = g.position_cm;
    rep.yaw_deg = gyaw;
    rep.error = g.error;
    rep.search_range_cm = -1.0;
    last_error_ = g.error;
    last_range_cm_ = -1.0;
    if (g.error < config_.e_th && !(config_.refuse_ambiguous && g.ambiguous)) {
      relocalize(g.position_cm, gyaw, g.error);
    } else if (g.error < config_.e_th) {
      rep.outcome = FrameOutcome::kAmbiguous;
      ++stats_.ambiguous;
    } else {
      rep.outcome = FrameOutcome::kRejected;
      ++stats_.rejected;
    }
    return rep;
  }

  // Tracking: local search around the prediction in the fuzzy range.
  double range = fuzzy_search_range(config_.fuzzy, speed).snapped_cm;
  if (full) range = std::max(range, config_.min_range_cm);
  MatchResult m = local_search(db_, scan, xy(predicted), range, match_options_);
  refine(m, scan);
  m.error = judged_error(m);
  rep.position_cm = m.position_cm;
  rep.yaw_deg = yaw;
  rep.error = m.error;
  rep.search_range_cm = range;
  rep.predicted_offset_cm = distance_cm(m.position_cm, xy(predicted));
  last_error_ = m.error;
  last_range_cm_ = range;
  last_image_ms_ = t_ms;
  bool good = m.error < config_.e_th;

  if (full) {
    // Cross-check against a global search: after a kidnapping the local search can still find a
    // passable match near the wrong place, so a bad result alone is not the only symptom.
    if (!good || disagree_run_ > 0 || t_ms - last_check_ms_ >= config_.check_period_ms) {
      last_check_ms_ = t_ms;
      double gyaw = yaw;
      const MatchResult g = global(&gyaw);
      const double gate = std::max(config_.disagree_min_cm, config_.disagree_sigmas * predicted_sigma);
      const bool far = distance_cm(g.position_cm, xy(predicted)) > gate;
      const bool better = g.error < config_.disagree_error_ratio * m.error;
      if (g.error < config_.e_th && !g.ambiguous && far && better) {
        if (disagree_run_ > 0 && distance_cm(g.position_cm, disagree_position_cm_) > config_.disagree_min_cm)
          disagree_run_ = 0;  // a different place each time: not a consistent disagreement
        ++disagree_run_;
        disagree_position_cm_ = g.position_cm;
        if (disagree_run_ >= config_.disagree_frames) {
          ++stats_.lost_events;
          rep.position_cm = g.position_cm;
          rep.yaw_deg = gyaw;
          rep.error = g.error;
          rep.search_range_cm = -1.0;
          last_error_ = g.error;
          last_range_cm_ = -1.0;
          relocalize(g.position_cm, gyaw, g.error);
          return rep;
        }
        good = false;  // do not feed a result the global search contradicts into the odometry
      } else {
        disagree_run_ = 0;
      }
    }
  }

  if (good) {
    ++stats_.accepted;
    bad_run_ = 0;
    last_good_ = true;
    applied_this_window_ = true;
    rep.outcome = FrameOutcome::kAccepted;
    Pose2 pose{m.position_cm.x(), m.position_cm.y(), yaw};
    if (t_ms - last_reset_ms_ >= config_.reset_period_ms - 1e-6) {
      double sigma_yaw = odometry_.estimate().sigma_yaw_deg;
      if (full && config_.yaw_correction) {
        if (const std::optional<double> y = corrected_yaw(t_ms, bearings, m.position_cm, yaw)) {
          pose.yaw_deg = *y;
          sigma_yaw = std::min(sigma_yaw, config_.image_sigma_yaw_deg);
        }
      }
      reset_origin_at(t_ms, pose, config_.image_sigma_cm, sigma_yaw);
    }
    set_anchor(t_ms, pose, m.error);
  } else {
    ++stats_.rejected;
    rep.outcome = FrameOutcome::kRejected;
    last_good_ = false;
    // The paper: P_IL <- P_E, the odometry pose stands; kFull keeps the last good image carried
    // forward by odometry, which is the more recent fix.
    if (!full) anchor_.valid = false;
    ++bad_run_;
    if (full && bad_run_ >= config_.lost_after_bad_frames) {
      state_ = State::kLost;
      ++stats_.lost_events;
    }
  }
  return rep;
}

std::optional<double> Localizer::corrected_yaw(double t_ms, const BearingScan& bearings,
                                               const Eigen::Vector2d& position_cm, double gyro_yaw_deg) {
  // Alpha-beta filter on the heading error: predict with the learnt drift rate since the last
  // fix, then move by yaw_gain of the residual and learn the rate with yaw_rate_gain.
  const double dt_s = (t_ms - last_yaw_fix_ms_) / 1000.0;
  const bool recent = dt_s > 0.0 && dt_s <= 1.0;  // the rate is only learnt from close fixes
  const double predicted = gyro_yaw_deg + (recent ? yaw_rate_deg_per_s_ * dt_s : 0.0);
  const YawEstimate est = estimate_yaw(field_, camera_, bearings, position_cm, predicted, config_.yaw_search_deg);
  if (!(est.error < config_.e_th)) return std::nullopt;
  const double residual = angle_diff_deg(est.yaw_deg, predicted);
  if (recent) {
    yaw_rate_deg_per_s_ += config_.yaw_rate_gain * residual / dt_s;
    yaw_rate_deg_per_s_ = std::clamp(yaw_rate_deg_per_s_, -config_.yaw_rate_max_deg_per_s,
                                     config_.yaw_rate_max_deg_per_s);
  }
  last_yaw_fix_ms_ = t_ms;
  ++stats_.yaw_corrections;
  return wrap_deg(predicted + config_.yaw_gain * residual);
}

LocalizedPose Localizer::make_pose(const EncoderWindow& window) {
  const OdometryEstimate& e = odometry_.estimate();
  LocalizedPose p;
  p.t_ms = window.t_end_ms;
  p.seq = window.seq;
  p.slip = e.slip.detected;
  p.match_error = last_error_;
  p.search_range_cm = last_range_cm_;
  p.image_age_ms = anchor_.valid && anchor_.t_ms > 0.0 ? window.t_end_ms - anchor_.t_ms : kNoError;
  p.sigma_yaw_deg = e.sigma_yaw_deg;
  if (anchor_.valid) {
    p.pose = {anchor_.pose.x_cm + (e.pose.x_cm - anchor_.odometry_at_t.x_cm),
              anchor_.pose.y_cm + (e.pose.y_cm - anchor_.odometry_at_t.y_cm), e.pose.yaw_deg};
    const double moved = distance_cm(xy(e.pose), xy(anchor_.odometry_at_t));
    p.sigma_xy_cm = std::hypot(config_.image_sigma_cm, robot_.odometry_noise_fraction * moved);
  } else {
    p.pose = e.pose;
    p.sigma_xy_cm = e.sigma_xy_cm;
  }
  if (state_ == State::kSearching) p.source = PoseSource::kNone;
  else if (state_ == State::kLost) p.source = PoseSource::kLost;
  else if (applied_this_window_) p.source = PoseSource::kImage;
  else if (last_good_) p.source = PoseSource::kIntegrated;
  else p.source = PoseSource::kOdometry;
  if (state_ == State::kLost || state_ == State::kSearching) p.sigma_xy_cm = std::max(p.sigma_xy_cm, 100.0);
  return p;
}

}  // namespace omniloc
