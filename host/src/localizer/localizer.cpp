// The integration localizer: Fig. 15's flow on Fig. 16's timeline (see localizer.hpp).
//
// One frame (process) goes through named steps:
//   frame_at      odometry pose and speed at the frame's time, the prediction (the last good
//                 image carried forward), and the scan rotated into the field frame once;
//   search        (searching or lost) a global search (locate_frame, shared with `omniloc
//                 locate`); relocalize on a good, unambiguous result (the goal colours may tell
//                 a result from its twin);
//   track         a local search around the prediction in the fuzzy range, then
//   cross_check   (policy) a global search that notices a kidnapping, then
//   accept/reject the result sets the anchor (and every reset period the odometry origin, with
//                 the image heading through the heading filter), or leaves the odometry standing.
// What LocalizerMode changes is in LocalizerPolicy, read by these steps.
#include "omniloc/localizer.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <utility>

#include "omniloc/locate.hpp"

namespace omniloc {

/// One thread that runs one global search at a time for the cross-check (cross_check_worker). The
/// job holds copies of the frame's scans; locate_frame reads the field, camera and database, which
/// nothing writes while the localizer lives. start() and wait() alternate (the localizer judges a
/// check before it starts the next).
class Localizer::CheckWorker {
 public:
  CheckWorker() : thread_([this] { loop(); }) {}
  ~CheckWorker() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  CheckWorker(const CheckWorker&) = delete;
  CheckWorker& operator=(const CheckWorker&) = delete;

  void start(std::function<SingleFrameResult()> job) {
    {
      std::lock_guard lock(mutex_);
      job_ = std::move(job);
      result_.reset();
      error_ = nullptr;
    }
    wake_.notify_all();
  }
  /// The result of the job started last (rethrowing what it threw).
  SingleFrameResult wait() {
    std::unique_lock lock(mutex_);
    done_.wait(lock, [&] { return result_.has_value() || error_ != nullptr; });
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    SingleFrameResult r = std::move(*result_);
    result_.reset();
    return r;
  }

 private:
  void loop() {
    std::unique_lock lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || job_ != nullptr; });
      if (stop_) return;
      std::function<SingleFrameResult()> job = std::move(job_);
      job_ = nullptr;
      lock.unlock();
      std::optional<SingleFrameResult> r;
      std::exception_ptr e;
      try {
        r = job();
      } catch (...) {
        e = std::current_exception();
      }
      lock.lock();
      result_ = std::move(r);
      error_ = e;
      done_.notify_all();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::function<SingleFrameResult()> job_;
  std::optional<SingleFrameResult> result_;
  std::exception_ptr error_;
  bool stop_ = false;
  std::thread thread_;  // last: started once the members above exist
};

namespace {

HeadingFilterConfig heading_filter_config(const LocalizerConfig& c) {
  HeadingFilterConfig h;
  h.gain = c.yaw_gain;
  h.rate_gain = c.yaw_rate_gain;
  h.rate_max_deg_per_s = c.yaw_rate_max_deg_per_s;
  h.max_rate_gap_s = 1.0;  // the rate is only learnt from close fixes
  return h;
}

/// `range_cm` as the local search will use it on `grid`; throws unless it is 0 or a whole,
/// non-zero multiple of the step (see validate_search_ranges).
void check_range_on_grid(double range_cm, const GridSpec& grid, const std::string& source,
                         const std::string& field) {
  const int reach = local_search_reach_cells(range_cm, grid.step_cm);
  const double searched_cm = reach * grid.step_cm;
  if (std::abs(searched_cm - range_cm) <= 1e-6) return;
  std::ostringstream os;
  os << source << ":" << field << ": search range " << range_cm
     << " cm is not 0 or a whole multiple of the feature database's grid step " << grid.step_cm
     << " cm: the local search would reach " << reach << " cell(s) each side, i.e. search "
     << searched_cm << " cm (" << 2 * reach + 1 << " x " << 2 * reach + 1 << " points)";
  throw ConfigError(os.str());
}

}  // namespace

void validate_search_ranges(const LocalizerConfig& config, const GridSpec& grid,
                            const std::string& source) {
  for (std::size_t i = 0; i < config.fuzzy.snap_ranges_cm.size(); ++i)
    check_range_on_grid(config.fuzzy.snap_ranges_cm[i], grid, source,
                        "fuzzy.snap_ranges_cm[" + std::to_string(i) + "]");
  if (LocalizerPolicy::of(config).min_range_cm > 0.0)
    check_range_on_grid(config.min_range_cm, grid, source, "min_range_cm");
}

LocalizerPolicy LocalizerPolicy::of(const LocalizerConfig& c) {
  LocalizerPolicy p;
  if (c.mode == LocalizerMode::kPaper) return p;
  p.search_any_yaw = !c.gyro_yaw_known;
  p.min_range_cm = c.min_range_cm;
  p.cross_check = true;
  p.correct_yaw = c.yaw_correction;
  p.keep_anchor_on_reject = true;
  p.detect_lost = true;
  return p;
}

Pose2 Localizer::Anchor::carried_to(const Pose2& odometry_now) const {
  return pose.shifted(odometry_now.position_cm() - odometry_at_t.position_cm())
      .with_yaw(odometry_now.yaw_deg);
}

Localizer::Localizer(const LocalizerConfig& config, const RobotConfig& robot,
                     const FieldGeometry& field, const CameraModel& camera, const FeatureDb& db,
                     std::optional<Pose2> initial_pose)
    : config_(config),
      policy_(LocalizerPolicy::of(config)),
      robot_(robot),
      field_(field),
      camera_(camera),
      db_(db),
      goal_colours_(goal_colour_models(camera.vision)),
      odometry_(robot),
      gyro_guard_(robot),
      extractor_(camera),
      heading_filter_(heading_filter_config(config)) {
  validate_localizer_config(config_, "localizer config");
  if (db.field_fingerprint != field.fingerprint() || db.camera_fingerprint != camera.fingerprint())
    throw std::invalid_argument(
        "Localizer: the feature database was built for another field or camera");
  validate_search_ranges(config_, db.grid, "localizer config");
  match_options_ = match_options_of(config_);
  if (!config_.gyro_yaw_known) trust_ = HeadingTrust::kNone;
  if (initial_pose) {
    heading_aligned_ = true;  // a known start pose is a known heading
    odometry_.reset(*initial_pose, 0.0, 0.0);
    state_ = State::kTracking;
    anchor_ = {true, 0.0, *initial_pose, *initial_pose, kNoError};
    last_good_ = true;
  }
  last_pose_.pose = initial_pose.value_or(Pose2{});
  last_pose_.source = initial_pose ? PoseSource::kIntegrated : PoseSource::kNone;
}

Localizer::~Localizer() = default;

bool Localizer::covered(double t_ms) const {
  return !history_.empty() && history_.back().window.t_end_ms >= t_ms;
}

Pose2 Localizer::odometry_pose_at(double t_ms, double* speed_cm_per_s, double* sigma_xy_cm) const {
  if (history_.empty()) {
    if (speed_cm_per_s) *speed_cm_per_s = 0.0;
    if (sigma_xy_cm) *sigma_xy_cm = odometry_.estimate().sigma_xy_cm;
    return odometry_.estimate().pose;
  }
  // Last entry at or before t (history is sorted by time); before the first window the odometry
  // stands at its origin, which the first window's start shares.
  auto after =
      std::upper_bound(history_.begin(), history_.end(), t_ms,
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
  return interpolate(lo->pose, hi->pose, f);
}

void Localizer::reset_origin_at(double t_ms, const Pose2& pose, double sigma_xy_cm,
                                double sigma_yaw_deg) {
  ++stats_.origin_resets;
  last_reset_ms_ = t_ms;
  if (history_.empty()) {
    odometry_.reset(pose, sigma_xy_cm, sigma_yaw_deg);
    return;
  }
  // Reset at the last window k ending at or before t, shifted back by the odometry's own motion
  // from t_k to t, then re-integrate the windows after k: the result is applied at the image time.
  auto after =
      std::upper_bound(history_.begin(), history_.end(), t_ms,
                       [](double t, const HistoryEntry& e) { return t < e.window.t_end_ms; });
  auto k = after == history_.begin() ? history_.begin() : std::prev(after);
  const Pose2 at_t = odometry_pose_at(t_ms, nullptr, nullptr);
  const Pose2 at_k = k->odometry.estimate().pose;
  // The origin at window k that the odometry carries to `pose` at t_ms: `pose` shifted back by
  // the field-frame displacement (and turned back by the heading change) from k to t.
  const Pose2 origin = pose.shifted(at_k.position_cm() - at_t.position_cm())
                           .with_yaw(pose.yaw_deg - yaw_difference_deg(at_t, at_k));
  Odometry o = k->odometry;
  o.reset(origin, sigma_xy_cm, sigma_yaw_deg);
  k->odometry = o;
  for (auto it = std::next(k); it != history_.end(); ++it) {
    o.update(it->window);
    it->odometry = o;
  }
  odometry_ = o;
}

void Localizer::set_anchor(double t_ms, const Pose2& pose, double error, double sigma_cm) {
  anchor_.valid = true;
  anchor_.sigma_cm = sigma_cm;
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

LocalizedPose Localizer::on_window(const EncoderWindow& received) {
  if (!history_.empty() && !(received.t_end_ms > history_.back().window.t_end_ms)) {
    std::ostringstream os;
    os << "Localizer: encoder window seq " << received.seq << " at t=" << received.t_end_ms
       << " ms does not come after the previous one (seq " << history_.back().window.seq
       << " at t=" << history_.back().window.t_end_ms << " ms)";
    throw std::invalid_argument(os.str());
  }
  // The one gyro yaw check of every path (replay, omnilocd, omnilocd-sim): an implausible yaw is
  // replaced by the wheels' heading for this window, counted and reported with the pose.
  EncoderWindow window = received;
  const GyroYawCheck gyro = gyro_guard_.screen(window);
  if (gyro.fault != GyroYawFault::kNone) ++stats_.gyro_yaw_dropped;
  set_heading_trust(window.heading_trust);
  odometry_.update(window);
  history_.push_back({window, odometry_});
  applied_this_window_ = false;
  while (!pending_.empty() && covered(pending_.front().t_ms)) {
    PendingFrame f = std::move(pending_.front());
    pending_.pop_front();
    reports_.push_back(process(f.t_ms, f.bearings, f.goals ? &*f.goals : nullptr));
  }
  trim_history();
  last_pose_ = make_pose(window);
  if (gyro.fault != GyroYawFault::kNone) last_pose_.gyro_yaw_dropped = gyro;
  return last_pose_;
}

FrameReport Localizer::on_image(double t_ms, const cv::Mat& bgr) {
  ExtractionReport er;
  BearingScan bearings = extractor_.extract(bgr, config_.scan_rays_per_degree, &er);
  if (!er.usable) {
    FrameReport r;
    r.t_ms = t_ms;
    r.outcome = FrameOutcome::kRejected;
    r.no_measurement = er.reason;
    ++stats_.frames;
    ++stats_.rejected;
    reports_.push_back(r);
    return r;
  }
  return on_bearings(t_ms, std::move(bearings), observe_goals(bgr, camera_, field_, goal_colours_));
}

FrameReport Localizer::on_bearings(double t_ms, BearingScan bearings,
                                   std::optional<GoalObservation> goals) {
  if (!std::isfinite(t_ms)) throw std::invalid_argument("Localizer: frame time is not finite");
  if (!covered(t_ms)) {
    // Keep frames in time order; a frame older than a waiting one is still fine to queue.
    auto pos = std::upper_bound(pending_.begin(), pending_.end(), t_ms,
                                [](double t, const PendingFrame& f) { return t < f.t_ms; });
    pending_.insert(pos, PendingFrame{t_ms, std::move(bearings), std::move(goals)});
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
  FrameReport r = process(t_ms, bearings, goals ? &*goals : nullptr);
  reports_.push_back(r);
  return r;
}

void Localizer::resync() {
  discard_started_check();
  const Pose2 pose = last_pose_.pose;
  const double sigma = last_pose_.sigma_xy_cm;
  odometry_ = Odometry(robot_);
  odometry_.reset(pose, sigma, last_pose_.sigma_yaw_deg);
  history_.clear();
  pending_.clear();
  trimmed_ = false;
  anchor_.valid = false;
  last_reset_ms_.reset();
  last_check_ms_.reset();
  disagree_run_ = 0;
}

void Localizer::set_pose(const Pose2& pose, double sigma_xy_cm, double sigma_yaw_deg) {
  discard_started_check();
  const double t_ms = history_.empty() ? 0.0 : history_.back().window.t_end_ms;
  reset_origin_at(t_ms, pose, sigma_xy_cm, sigma_yaw_deg);
  set_anchor(t_ms, pose, kNoError, sigma_xy_cm);
  kickoff_pending_ = false;
  heading_aligned_ = true;  // the operator's heading: the gyro holds it from here
  bad_aligned_searches_ = 0;
  state_ = State::kTracking;
  bad_run_ = 0;
  disagree_run_ = 0;
  last_good_ = true;
  last_pose_.pose = odometry_.estimate().pose;
  last_pose_.sigma_xy_cm = sigma_xy_cm;
  last_pose_.sigma_yaw_deg = sigma_yaw_deg;
}

void Localizer::set_heading_trust(HeadingTrust trust) {
  if (!config_.gyro_yaw_known) trust = HeadingTrust::kNone;
  if (trust == trust_) return;
  // A heading that was not trusted for a while (a gyro fault: the wheels stood in) has lost the
  // alignment the last fix gave it.
  if (trust != HeadingTrust::kRelative) heading_aligned_ = false;
  trust_ = trust;
}

bool Localizer::heading_known() const {
  return trust_ == HeadingTrust::kAbsolute ||
         (trust_ == HeadingTrust::kRelative && heading_aligned_);
}

void Localizer::set_side(GoalColour defended) {
  if (defended == GoalColour::kUnknown) throw std::invalid_argument("side: must be blue or yellow");
  if (goal_colour_at_x_max(field_, goal_colours_) == GoalColour::kUnknown)
    throw std::invalid_argument(
        "side: field '" + field_.name +
        "' does not say which goal is which colour (goal.colour_at_x_max in the field file, or "
        "goal_colour_at_x_max in the camera's vision block from omniloc calibrate)");
  side_ = defended;
  kickoff_pending_ = true;
}

std::optional<SingleFrameResult> Localizer::choose_by_side(const SingleFrameResult& g) const {
  if (!side_ || !kickoff_pending_ || !(g.match.error < config_.e_th)) return std::nullopt;
  // The defended goal at the x = max end: the own half is x > centre and the opponent's goal,
  // which the robot faces at kick-off, lies towards -x.
  const bool own_half_x_max = goal_colour_at_x_max(field_, goal_colours_) == *side_;
  const double centre_x = field_.centre_cm().x();
  const auto in_own_half = [&](const Pose2& p) {
    return own_half_x_max ? p.x_cm > centre_x : p.x_cm < centre_x;
  };
  const auto facing_opponent = [&](const Pose2& p) {
    return std::cos(deg_to_rad(p.yaw_deg)) * (own_half_x_max ? -1.0 : 1.0) > 0.0;
  };
  SingleFrameResult chosen = g;
  chosen.accepted = true;
  chosen.ambiguous = chosen.heading_ambiguous = chosen.lines_ambiguous = false;
  chosen.twin.reset();
  if (g.heading_ambiguous) {  // near the centre spot: the position is known, the heading up to 180
                              // deg
    if (!facing_opponent(g.pose)) chosen.pose.yaw_deg = wrap_deg(g.pose.yaw_deg + 180.0);
    return chosen;
  }
  if (!g.ambiguous || !g.twin || !(g.twin_error < config_.e_th)) return std::nullopt;
  const bool first = in_own_half(g.pose), second = in_own_half(*g.twin);
  if (first == second)
    return std::nullopt;  // both on one side of the centre line: the rule cannot tell
  if (second) {
    chosen.pose = *g.twin;
    chosen.match.position_cm = g.twin->position_cm();
    chosen.match.error = g.twin_error;
    chosen.match.sigma_cm = kNoError;  // the refinement's uncertainty was the other candidate's
  }
  return chosen;
}

void Localizer::force_global_search() {
  discard_started_check();
  if (state_ == State::kTracking) {
    state_ = State::kLost;
    ++stats_.lost_events;
  }
  anchor_.valid = false;
  bad_run_ = 0;
  disagree_run_ = 0;
}

std::vector<FrameReport> Localizer::take_frame_reports() {
  std::vector<FrameReport> out;
  out.swap(reports_);
  return out;
}

FrameReport Localizer::process(double t_ms, const BearingScan& bearings,
                               const GoalObservation* goals) {
  FrameReport rep;
  rep.t_ms = t_ms;
  ++stats_.frames;
  // The worker's check of the previous checked frame first: a relocalization it decides moves the
  // prediction this frame is matched around (and this frame then only reports it).
  if (started_check_ && judge_started_check(rep) == CrossCheck::kRelocalized) return rep;
  if (trimmed_ && t_ms < history_.front().window.t_end_ms) {
    rep.outcome = FrameOutcome::kDropped;
    ++stats_.dropped;
    return rep;
  }
  const Frame frame = frame_at(t_ms, bearings, goals);
  rep.speed_cm_per_s = frame.speed_cm_per_s;
  if (state_ == State::kTracking) {
    track(frame, rep);
  } else {
    search(frame, rep);
  }
  return rep;
}

Localizer::Frame Localizer::frame_at(double t_ms, const BearingScan& bearings,
                                     const GoalObservation* goals) const {
  Frame f;
  f.t_ms = t_ms;
  f.bearings = &bearings;
  f.goals = goals;
  double odo_sigma = 0.0;
  f.odometry = odometry_pose_at(t_ms, &f.speed_cm_per_s, &odo_sigma);
  // Prediction: the last good image carried forward by odometry (the output), else odometry.
  f.predicted = anchor_.valid ? anchor_.carried_to(f.odometry) : f.odometry;
  f.predicted_sigma_cm = anchor_.valid ? anchor_sigma_cm(f.odometry) : odo_sigma;
  f.scan = make_field_scan(bearings, f.odometry.yaw_deg);  // the odometry's yaw follows the gyro
  return f;
}

void Localizer::search(const Frame& frame, FrameReport& rep) {
  const SingleFrameResult g = global_match(frame, rep);
  note_global(rep, g);
  const bool good = g.match.error < config_.e_th;
  // Without a heading, one known only up to 180 deg would turn every wheel displacement around.
  if (g.accepted && !(g.heading_ambiguous && config_.refuse_ambiguous)) {
    relocalize(frame.t_ms, g, rep);
  } else if (const std::optional<SingleFrameResult> by_side = choose_by_side(g)) {
    ++stats_.decided_by_side;
    note_global(rep, *by_side);
    relocalize(frame.t_ms, *by_side, rep);
  } else if (good) {
    rep.outcome = FrameOutcome::kAmbiguous;
    ++stats_.ambiguous;
  } else {
    rep.outcome = FrameOutcome::kRejected;
    ++stats_.rejected;
    // The gyro's alignment may be what is wrong (a wrong twin at the first fix): after this many
    // failures at its heading, try every heading again.
    if (trust_ == HeadingTrust::kRelative && heading_aligned_ &&
        ++bad_aligned_searches_ >= config_.lost_after_bad_frames) {
      heading_aligned_ = false;
      bad_aligned_searches_ = 0;
      ++stats_.heading_alignments_dropped;
    }
  }
}

void Localizer::track(const Frame& frame, FrameReport& rep) {
  const double range = search_range_cm(frame.speed_cm_per_s);
  const MatchResult m = local_match(frame, range);
  rep.position_cm = m.position_cm;
  rep.yaw_deg = frame.scan.yaw_deg;
  rep.error = m.error;
  rep.search_range_cm = range;
  rep.predicted_offset_cm = (m.position_cm - frame.predicted.position_cm()).norm();
  note_image_result(m.error, range);
  bool good = m.error < config_.e_th;
  // A disagreement found by the worker's check of an earlier frame runs on: the local result is
  // not trusted until a check agrees again (the inline check refuses the frame it contradicts).
  if (policy_.cross_check && config_.cross_check_worker && disagree_run_ > 0) good = false;
  if (policy_.cross_check) {
    const CrossCheck check = cross_check(frame, m, rep);
    if (check == CrossCheck::kRelocalized) return;
    if (check == CrossCheck::kContradicts) good = false;  // do not feed it into the odometry
  }
  if (good) {
    accept(frame, m, rep);
  } else {
    reject(rep);
  }
}

Localizer::CrossCheck Localizer::cross_check(const Frame& frame, const MatchResult& local,
                                             FrameReport& rep) {
  // After a kidnapping the local search can still find a passable match near the wrong place, so
  // a bad result alone is not the only symptom. Checked on a bad result, while a disagreement
  // runs, and at least every check_period_ms.
  const bool good = local.error < config_.e_th;
  if (good && disagree_run_ == 0 && last_check_ms_ &&
      frame.t_ms - *last_check_ms_ < config_.check_period_ms)
    return CrossCheck::kNotRun;
  last_check_ms_ = frame.t_ms;
  const CheckContext checked{frame.t_ms, frame.predicted.position_cm(), frame.predicted_sigma_cm,
                             local.error};
  if (config_.cross_check_worker) {
    if (started_check_) return CrossCheck::kNotRun;  // judged at the start of process(): never here
    if (!worker_) worker_ = std::make_unique<CheckWorker>();
    const std::optional<double> yaw = begin_global_search(frame, rep);
    // Copies: the frame's scans go away with it. The members read are the const configuration,
    // field, camera and database, which outlive the worker.
    worker_->start(
        [this, yaw, bearings = *frame.bearings, scan = frame.scan,
         goals = frame.goals ? std::optional<GoalObservation>(*frame.goals) : std::nullopt]() {
          return locate_frame(config_, field_, camera_, db_, bearings, yaw,
                              goals ? &*goals : nullptr, &scan);
        });
    started_check_ = checked;
    return CrossCheck::kStarted;
  }
  return judge_check(checked, global_match(frame, rep), rep);
}

Localizer::CrossCheck Localizer::judge_check(const CheckContext& checked,
                                             const SingleFrameResult& g, FrameReport& rep) {
  const double gate =
      std::max(config_.disagree_min_cm, config_.disagree_sigmas * checked.predicted_sigma_cm);
  const bool far = (g.match.position_cm - checked.predicted_cm).norm() > gate;
  const bool better = g.match.error < config_.disagree_error_ratio * checked.local_error;
  if (!(g.match.error < config_.e_th && !g.ambiguous && far && better)) {
    disagree_run_ = 0;
    return CrossCheck::kAgrees;
  }
  if (disagree_run_ > 0 &&
      (g.match.position_cm - disagree_position_cm_).norm() > config_.disagree_min_cm)
    disagree_run_ = 0;  // a different place each time: not a consistent disagreement
  ++disagree_run_;
  disagree_position_cm_ = g.match.position_cm;
  if (disagree_run_ < config_.disagree_frames) return CrossCheck::kContradicts;
  ++stats_.lost_events;
  note_global(rep, g);
  relocalize(checked.t_ms, g, rep);
  return CrossCheck::kRelocalized;
}

Localizer::CrossCheck Localizer::judge_started_check(FrameReport& rep) {
  const CheckContext checked = *started_check_;
  started_check_.reset();
  const SingleFrameResult g = worker_->wait();
  // Only while still tracking, and only within the history (its relocalization is applied at the
  // checked frame's time); otherwise the pose has moved on without it.
  if (state_ != State::kTracking || history_.empty() ||
      (trimmed_ && checked.t_ms < history_.front().window.t_end_ms))
    return CrossCheck::kNotRun;
  const CrossCheck c = judge_check(checked, g, rep);
  if (c == CrossCheck::kRelocalized) rep.global = true;
  return c;
}

void Localizer::discard_started_check() {
  if (!started_check_) return;
  started_check_.reset();
  try {
    (void)
        worker_->wait();  // the worker is free for the next check; its answer is about the old pose
  } catch (const std::exception&) {
    // About the old pose too: a search that failed is as irrelevant now as one that succeeded.
  }
}

void Localizer::accept(const Frame& frame, const MatchResult& local, FrameReport& rep) {
  ++stats_.accepted;
  bad_run_ = 0;
  last_good_ = true;
  applied_this_window_ = true;
  rep.outcome = FrameOutcome::kAccepted;
  Pose2 pose{local.position_cm.x(), local.position_cm.y(), frame.odometry.yaw_deg};
  if (!last_reset_ms_ || frame.t_ms - *last_reset_ms_ >= config_.reset_period_ms - 1e-6) {
    double sigma_yaw = odometry_.estimate().sigma_yaw_deg;
    if (policy_.correct_yaw) {
      if (const std::optional<double> y =
              corrected_yaw(frame.t_ms, *frame.bearings, local.position_cm, pose.yaw_deg)) {
        pose.yaw_deg = *y;
        sigma_yaw = std::min(sigma_yaw, config_.image_sigma_yaw_deg);
      }
    }
    reset_origin_at(frame.t_ms, pose, image_sigma_cm(local), sigma_yaw);
  }
  set_anchor(frame.t_ms, pose, local.error, image_sigma_cm(local));
}

void Localizer::reject(FrameReport& rep) {
  ++stats_.rejected;
  rep.outcome = FrameOutcome::kRejected;
  last_good_ = false;
  // The paper: P_IL <- P_E, the odometry pose stands; kFull keeps the last good image carried
  // forward by odometry, which is the more recent fix.
  if (!policy_.keep_anchor_on_reject) anchor_.valid = false;
  ++bad_run_;
  if (policy_.detect_lost && bad_run_ >= config_.lost_after_bad_frames) {
    state_ = State::kLost;
    ++stats_.lost_events;
  }
}

void Localizer::relocalize(double t_ms, const SingleFrameResult& global, FrameReport& rep) {
  const Pose2 pose = global.pose;
  reset_origin_at(t_ms, pose, image_sigma_cm(global.match), config_.image_sigma_yaw_deg);
  set_anchor(t_ms, pose, global.match.error, image_sigma_cm(global.match));
  state_ = State::kTracking;
  bad_run_ = 0;
  disagree_run_ = 0;
  last_good_ = true;
  applied_this_window_ = true;
  ++stats_.relocalizations;
  kickoff_pending_ = false;  // the kick-off rule has served (or was not needed)
  heading_aligned_ = true;   // a relative gyro holds the fix's heading from here
  bad_aligned_searches_ = 0;
  rep.outcome = FrameOutcome::kRelocalized;
}

std::optional<double> Localizer::begin_global_search(const Frame& frame, FrameReport& rep) {
  ++stats_.global_searches;
  rep.global = true;
  const bool any_yaw = policy_.search_any_yaw || !heading_known();
  return any_yaw ? std::nullopt : std::optional<double>(frame.scan.yaw_deg);
}

SingleFrameResult Localizer::global_match(const Frame& frame, FrameReport& rep) {
  const std::optional<double> yaw = begin_global_search(frame, rep);
  return locate_frame(config_, field_, camera_, db_, *frame.bearings, yaw, frame.goals,
                      &frame.scan);
}

MatchResult Localizer::local_match(const Frame& frame, double range_cm) const {
  MatchResult m =
      local_search(db_, frame.scan, frame.predicted.position_cm(), range_cm, match_options_);
  apply_refinement(db_, field_, camera_, frame.scan, m, match_options_);
  m.error = judged_error(config_, m);
  return m;
}

double Localizer::search_range_cm(double speed_cm_per_s) const {
  return std::max(fuzzy_search_range(config_.fuzzy, speed_cm_per_s).snapped_cm,
                  policy_.min_range_cm);
}

void Localizer::note_global(FrameReport& rep, const SingleFrameResult& global) {
  rep.position_cm = global.match.position_cm;
  rep.yaw_deg = global.pose.yaw_deg;
  rep.error = global.match.error;
  rep.search_range_cm = -1.0;
  note_image_result(global.match.error, std::nullopt);
}

void Localizer::note_image_result(double error, std::optional<double> range_cm) {
  // An error of kNoError compared nothing: no result to report.
  last_error_ = std::isfinite(error) ? std::optional(error) : std::nullopt;
  last_range_cm_ = last_error_ ? range_cm : std::nullopt;
}

std::optional<double> Localizer::corrected_yaw(double t_ms, const BearingScan& bearings,
                                               const Eigen::Vector2d& position_cm,
                                               double gyro_yaw_deg) {
  const double predicted = heading_filter_.predict(t_ms, gyro_yaw_deg);
  const YawEstimate est = estimate_yaw(field_, camera_, bearings, position_cm, predicted,
                                       config_.yaw_search_deg, match_options_);
  if (!(est.error < config_.e_th)) return std::nullopt;
  ++stats_.yaw_corrections;
  return heading_filter_.correct(t_ms, predicted, est.yaw_deg);
}

double Localizer::anchor_sigma_cm(const Pose2& odometry_now) const {
  const double moved = distance_cm(odometry_now, anchor_.odometry_at_t);
  return std::hypot(anchor_.sigma_cm, robot_.odometry_noise_fraction * moved);
}

double Localizer::image_sigma_cm(const MatchResult& match) const {
  return std::isfinite(match.sigma_cm) ? match.sigma_cm : config_.image_sigma_cm;
}

LocalizedPose Localizer::make_pose(const EncoderWindow& window) {
  const OdometryEstimate& e = odometry_.estimate();
  LocalizedPose p;
  p.t_ms = window.t_end_ms;
  p.seq = window.seq;
  p.slip = e.slip.detected;
  p.vx_cm_s = e.vx_cm_per_s;
  p.vy_cm_s = e.vy_cm_per_s;
  p.omega_deg_s = e.yaw_rate_deg_per_s;
  p.match_error = last_error_;
  p.search_range_cm = last_range_cm_;
  p.sigma_yaw_deg = e.sigma_yaw_deg;
  p.pose = anchor_.valid ? anchor_.carried_to(e.pose) : e.pose;
  p.sigma_xy_cm = anchor_.valid ? anchor_sigma_cm(e.pose) : e.sigma_xy_cm;
  if (state_ == State::kSearching)
    p.source = PoseSource::kNone;
  else if (state_ == State::kLost)
    p.source = PoseSource::kLost;
  else if (applied_this_window_)
    p.source = PoseSource::kImage;
  else if (last_good_)
    p.source = PoseSource::kIntegrated;
  else
    p.source = PoseSource::kOdometry;
  if (state_ == State::kLost || state_ == State::kSearching)
    p.sigma_xy_cm = std::max(p.sigma_xy_cm, 100.0);
  return p;
}

}  // namespace omniloc
