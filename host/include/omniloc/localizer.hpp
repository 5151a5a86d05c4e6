// The integration localizer (paper section 2.5, Figs. 15-16) plus what a robot needs beyond it.
//
// Flow: a global search at start (or a given initial pose); once an image result's normalised
// match error is below E_TH its pose becomes the odometry origin. Afterwards each camera frame is
// matched by a local search around the odometry-predicted pose, in the range the fuzzy system
// picks from the robot's speed. A good result (error < E_TH) is kept as the output, carried
// forward by the odometry; a bad one leaves the odometry pose standing. Every reset period
// (125 ms) with a good result, the odometry origin is reset to it.
//
// Timing: encoder windows (100 Hz) and frames (60 Hz) carry their own timestamps (the board's
// time base); an image result is applied at the time the image was *taken*: the localizer keeps
// a short history of odometry states and re-integrates the windows after the image time.
// Frames may be given before the windows that cover their time (replay): they wait.
//
// Beyond the paper (LocalizerMode::kFull): sub-grid refinement, a minimum search range, refusal
// of ambiguous matches (unless the goal colours tell a pose from its twin), a cross-check by global
// search that detects being lost (a run of bad matches, or image and odometry disagreeing beyond
// their uncertainty as after a kidnapping) and recovers, and an uncertainty on every pose.
// LocalizerMode::kPaper does exactly what the paper describes (no refinement, no lost detection)
// for side-by-side figures.
//
// Every global search is locate_frame (locate.hpp), which `omniloc locate` runs on one frame.
// One class serves omnilocd (live), `omniloc replay` and the demo. Not thread-safe: call it from
// one thread (scan images elsewhere and pass the BearingScan to on_bearings() if needed). It runs
// the cross-check's global search on a thread of its own (cross_check_worker), on copies of the
// frame's scan and the const field, camera and database; nothing else is shared.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "omniloc/camera.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/feature_db.hpp"
#include "omniloc/field.hpp"
#include "omniloc/fuzzy.hpp"
#include "omniloc/goals.hpp"
#include "omniloc/heading_filter.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/matcher.hpp"
#include "omniloc/odometry.hpp"
#include "omniloc/robot_config.hpp"
#include "omniloc/vision.hpp"

namespace omniloc {

struct SingleFrameResult;  // locate.hpp

enum class LocalizerMode {
  kPaper,  ///< Fig. 15 as printed: grid-point results, no lost detection, no ambiguity check
  kFull,   ///< the paper plus refinement, lost detection/recovery, ambiguity refusal
};

/// The member initialisers are the shipped defaults: a test checks they equal every key of
/// common/localizer/default.json.
struct LocalizerConfig {
  LocalizerMode mode = LocalizerMode::kFull;
  FuzzyConfig fuzzy;
  /// The match error (docs/VISION.md "Match error"); kPaper uses kPaperSad with the paper's
  /// E_TH 20.
  MatchCost match_cost = MatchOptions{}.cost;
  int crossing_cap_px = MatchOptions{}.crossing_cap_px;  ///< kBounded: cap C of one crossing's cost
  /// match threshold on the normalised error (kBounded: px per crossing; paper: 20)
  double e_th = 8.0;
  /// ambiguous when 2nd error <= ratio * best
  double ambiguity_ratio = MatchOptions{}.ambiguity_ratio;
  double reset_period_ms = 125.0;  ///< odometry origin reset period (paper: 125 ms)
  double history_ms = 1000.0;  ///< odometry history kept for late frames; older frames are dropped
  int scan_rays_per_degree = 2;  ///< on_image(): robot-frame scan step (for re-rotating by yaw)
  // --- kFull only ---
  Refinement refinement = Refinement::kRayCast;  ///< kRayCast: E_TH judged at the refined position
  double min_range_cm = 10.0;  ///< local search at least this wide (0 would pin to one grid point)
  bool refuse_ambiguous = true;  ///< a global result flagged ambiguous is never accepted
  /// a fix's position uncertainty when its match gives none (MatchResult::sigma_cm)
  double image_sigma_cm = 2.0;
  double image_sigma_yaw_deg = 0.5;
  int lost_after_bad_frames = 30;  ///< this many bad results in a row -> lost (0.5 s at 60 Hz)
  /// cross-check by global search at least this often while tracking
  double check_period_ms = 100.0;
  double disagree_min_cm = 30.0;  ///< global vs tracked pose farther than max(this, k sigma) ...
  double disagree_sigmas = 4.0;   ///< ... (k) with the global result clearly better ...
  double disagree_error_ratio = 0.7;  ///< ... (global error < ratio * local error) ...
  int disagree_frames = 3;            ///< ... this many frames in a row -> relocalize there
  /// The cross-check's global search runs on a worker thread, off the frame's path to its pose: it
  /// is started with the frame it checks and judged when the next frame is processed (waiting for
  /// it there if it is not done, so the outcome never depends on timing). A disagreement it finds
  /// makes the next frames' local results untrusted, as the check on the frame itself would; a
  /// relocalization is applied at the checked frame's time, one frame later. false: the search runs
  /// inline on the frame that triggers it (the reference for the latency bench).
  bool cross_check_worker = true;
  bool gyro_yaw_known = true;  ///< false: recover with global_search_any_yaw (no trusted heading)
  // Heading from the image (kFull): a MEMS gyro's bias drifts (tenths of a degree a minute, more
  // after a bad start-up calibration) and over a match the scan would no longer line up with the
  // database. At each origin reset the yaw is also estimated from the scan (estimate_yaw within
  // +- yaw_search_deg of the gyro heading, at the matched position) and an alpha-beta filter
  // corrects the heading: yaw_gain of the difference now, and a drift rate learnt with
  // yaw_rate_gain and applied between fixes (bounded by yaw_rate_max_deg_per_s).
  bool yaw_correction = true;
  double yaw_search_deg = 3.0;
  double yaw_gain = 0.05;
  double yaw_rate_gain = 0.005;
  double yaw_rate_max_deg_per_s = 2.0;

  /// kPaper: refinement kNone, min range 0, no ambiguity refusal, no lost detection.
  [[nodiscard]] static LocalizerConfig paper();

  /// Throws ConfigError "<at>.<field>: <why> (got <value>)" for the first bad field.
  void validate(const config::Origin& at) const;
  bool operator==(const LocalizerConfig&) const = default;
};

/// Reads the localizer config (common/localizer/default.json; docs/LOCALIZER.md) from a parsed
/// JSON node and validates it; errors (ConfigError) name the node's origin and the field. "mode"
/// is read first and chooses the values the other keys override (paper: LocalizerConfig::paper());
/// "fuzzy" is required.
[[nodiscard]] LocalizerConfig parse_localizer_config(const config::Node& node);
/// Loads a file by name ("default" -> common/localizer/default.json) or path.
[[nodiscard]] LocalizerConfig load_localizer_config(const std::string& name_or_path);
/// config.validate(source).
void validate_localizer_config(const LocalizerConfig& config, const std::string& source);
/// The key table (config_reader.hpp) of a localizer file.
[[nodiscard]] const std::vector<config::Key<LocalizerConfig>>& localizer_config_keys();

/// The ranges the local search can be asked for (the fuzzy snap ranges, and kFull's min_range_cm)
/// against the database's grid: the search reaches floor(range / step) cells each side
/// (local_search_reach_cells), so a range must be 0 or a whole, non-zero multiple of the step,
/// else it silently searches fewer cells than it says (at a 20 cm step a 10 cm range searches
/// the centre point only). Throws ConfigError naming `source`, the field, the range and the step.
/// The Localizer calls it at construction.
void validate_search_ranges(const LocalizerConfig& config, const GridSpec& grid,
                            const std::string& source);

/// What LocalizerMode changes, decided once from the config: kPaper is Fig. 15 as printed, kFull
/// adds the rest. The Localizer's steps consult this instead of the mode.
struct LocalizerPolicy {
  bool search_any_yaw = false;  ///< global searches try every heading (kFull, gyro_yaw_known false)
  double min_range_cm = 0.0;    ///< the local search is at least this wide (kFull: min_range_cm)
  bool cross_check = false;     ///< a global search checks the tracked pose (lost detection)
  bool correct_yaw = false;  ///< the image heading filter at origin resets (kFull, yaw_correction)
  /// a bad result keeps the last good image (paper: P_IL <- P_E)
  bool keep_anchor_on_reject = false;
  bool detect_lost = false;  ///< lost_after_bad_frames bad results in a row -> lost
  [[nodiscard]] static LocalizerPolicy of(const LocalizerConfig& config);
};

enum class PoseSource {
  kNone,        ///< no fix yet (waiting for a good global search); pose meaningless
  kImage,       ///< an image result was applied in this window
  kIntegrated,  ///< the last image result was good: its pose carried forward by odometry
  kOdometry,    ///< the last image result was bad: odometry pose stands
  kLost,        ///< lost (kFull): dead reckoning while global searches look for the robot
};
/// "none", "image", "integrated", "odometry", "lost" (the poses.csv `source` column).
[[nodiscard]] const char* pose_source_name(PoseSource source);
/// Inverse of pose_source_name; nullopt for anything else.
[[nodiscard]] std::optional<PoseSource> parse_pose_source(const std::string& name);

/// The localizer's answer for one encoder window.
struct LocalizedPose {
  double t_ms = 0.0;  ///< the window's end time
  std::uint32_t seq = 0;
  Pose2 pose;
  PoseSource source = PoseSource::kNone;
  /// The last image result's normalised error (none: no image matched yet).
  std::optional<double> match_error;
  /// The range of that result's local search (none: it came from a global search, or none yet).
  std::optional<double> search_range_cm;
  double sigma_xy_cm = 0.0;  ///< 1-sigma position uncertainty
  double sigma_yaw_deg = 0.0;
  bool slip = false;     ///< the odometry saw a wheel slip in this window
  double vx_cm_s = 0.0;  ///< robot-frame velocity from the odometry's last window
  double vy_cm_s = 0.0;
  double omega_deg_s = 0.0;  ///< yaw rate over the last window (the gyro's)
  /// Set when this window's gyro_yaw_deg was dropped as implausible (GyroYawGuard, odometry.hpp):
  /// what the check found. The window's heading came from the wheels.
  std::optional<GyroYawCheck> gyro_yaw_dropped;
};

/// What happened to one frame.
enum class FrameOutcome {
  kPending,      ///< waiting for the windows that cover its time
  kDropped,      ///< older than the history, or no window before it
  kAccepted,     ///< good result applied
  kRejected,     ///< error >= E_TH: odometry stands
  kAmbiguous,    ///< refused: ambiguous global result
  kRelocalized,  ///< a global search (start, lost or disagreement) set the pose
};
[[nodiscard]] const char* frame_outcome_name(FrameOutcome outcome);

struct FrameReport {
  double t_ms = 0.0;
  FrameOutcome outcome = FrameOutcome::kPending;
  bool global = false;  ///< a global search decided this frame
  Eigen::Vector2d position_cm{0.0, 0.0};
  double yaw_deg = 0.0;
  double error = kNoError;
  double search_range_cm = 0.0;
  double speed_cm_per_s = 0.0;
  double predicted_offset_cm = 0.0;  ///< |image - odometry prediction|
  /// Non-empty: the frame showed nothing usable (no carpet, too few rays or crossings), so it was
  /// not matched (outcome kRejected; odometry stands); says why.
  std::string no_measurement;
};

struct LocalizerStats {
  int frames = 0;
  int accepted = 0;
  int rejected = 0;
  int ambiguous = 0;
  int dropped = 0;
  int global_searches = 0;
  int relocalizations = 0;
  int origin_resets = 0;
  int lost_events = 0;
  int yaw_corrections = 0;
  int decided_by_side = 0;  ///< ambiguous global results decided by the kick-off rule (set_side)
  /// a relative gyro's alignment forgotten after failed searches
  int heading_alignments_dropped = 0;
  /// windows whose gyro yaw was dropped as implausible (LocalizedPose::gyro_yaw_dropped)
  int gyro_yaw_dropped = 0;
};

class Localizer {
 public:
  /// The references must outlive the localizer (the database is large and shared).
  Localizer(const LocalizerConfig& config, const RobotConfig& robot, const FieldGeometry& field,
            const CameraModel& camera, const FeatureDb& db,
            std::optional<Pose2> initial_pose = std::nullopt);
  ~Localizer();  // joins the cross-check worker (cross_check_worker)
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  /// Integrates one encoder window (times must increase), applies any waiting frames whose time
  /// it covers, and returns the pose at the window's end. The window's gyro yaw passes
  /// GyroYawGuard first: an implausible one is dropped (the wheels give this window's heading),
  /// counted in stats().gyro_yaw_dropped and reported in the pose's gyro_yaw_dropped.
  LocalizedPose on_window(const EncoderWindow& window);

  /// A camera frame taken at t_ms (same time base as the windows). Its lines are extracted now
  /// (LineExtractor); a frame with no measurement is reported kRejected at once, not matched.
  /// Processed now if a window at or after t_ms has been seen, else kept until one arrives (the
  /// report then says kPending).
  FrameReport on_image(double t_ms, const cv::Mat& bgr);
  /// Same with a robot-frame scan already made (scan_image_bearings); `goals` is the frame's goal
  /// observation (observe_goals), if any, for telling a global result from its twin.
  FrameReport on_bearings(double t_ms, BearingScan bearings,
                          std::optional<GoalObservation> goals = std::nullopt);

  /// The goal colour models on_image() observes the goals with (interim: until the camera carries
  /// them, camera.vision.goals; see goals.hpp). Without them a twin stays ambiguous.
  void set_goal_colours(const GoalColourModels& models) { goal_colours_ = models; }

  /// Forgets the window history and waiting frames, for when the board's time base restarts
  /// (reconnect): the current pose becomes the odometry origin and the next window may have any
  /// time. The gyro is assumed to have kept its alignment with the field.
  void resync();

  /// An operator's pose (the control channel's set_pose, ROS 2's /initialpose): from the last
  /// window on, the robot is at `pose` with the given uncertainty, tracking; the next frames refine
  /// it by local search as after an image fix. The gyro keeps its own alignment (the odometry's
  /// yaw offset absorbs the new heading).
  void set_pose(const Pose2& pose, double sigma_xy_cm, double sigma_yaw_deg);
  /// Forgets the fix (the control channel's relocalize): lost, so the next usable frame makes a
  /// global search; the odometry goes on meanwhile.
  void force_global_search();
  /// The team's side (the control channel's set_side, the daemon's `side` key): the colour of the
  /// goal it defends. Until the next fix, a global result the lines cannot tell from its twin (the
  /// point-symmetric field without a heading) is decided by the kick-off rule: the robot stands in
  /// its own half, facing the opponent's goal (docs/LOCALIZER.md, "Side"). Throws
  /// std::invalid_argument when neither the field nor the camera's vision block says which goal is
  /// which colour (goal_colour_at_x_max), or for GoalColour::kUnknown.
  void set_side(GoalColour defended);
  /// How far the windows' heading is trusted now (the last window's heading_trust,
  /// docs/LOCALIZER.md "Heading"); gyro_yaw_known false in the config: always kNone.
  [[nodiscard]] HeadingTrust heading_trust() const { return trust_; }
  /// True when a global search now takes the window heading as known.
  [[nodiscard]] bool heading_known() const;
  /// The side given, if any.
  [[nodiscard]] std::optional<GoalColour> side() const { return side_; }

  /// The pose at the last window (source kNone before any).
  [[nodiscard]] const LocalizedPose& pose() const { return last_pose_; }
  [[nodiscard]] bool has_fix() const { return state_ != State::kSearching; }
  [[nodiscard]] bool lost() const { return state_ == State::kLost; }
  [[nodiscard]] const LocalizerStats& stats() const { return stats_; }
  /// Reports of frames processed since the last call (pending ones appear once processed).
  [[nodiscard]] std::vector<FrameReport> take_frame_reports();
  [[nodiscard]] const LocalizerConfig& config() const { return config_; }
  /// The gyro drift learnt from the images (deg/s added to the gyro heading; 0 until learnt).
  [[nodiscard]] double yaw_drift_deg_per_s() const { return heading_filter_.rate_deg_per_s(); }

 private:
  /// Each window's heading_trust (the daemon's heading source, a replay's recording): kAbsolute:
  /// global searches use the window heading. kRelative (a working gyro, not aligned with the
  /// field): every heading is tried until a fix (an unambiguous global result, the kick-off rule of
  /// set_side, set_pose, a known start pose) aligns it, then the gyro's heading is used as known;
  /// lost_after_bad_frames failed global searches in a row at that heading forget the alignment.
  /// kNone (the wheels): every heading is always tried. A drop to kNone forgets the alignment.
  void set_heading_trust(HeadingTrust trust);
  enum class State { kSearching, kTracking, kLost };
  struct HistoryEntry {
    EncoderWindow window;
    Odometry odometry;  // state after the window
  };
  struct PendingFrame {
    double t_ms;
    BearingScan bearings;
    std::optional<GoalObservation> goals;
  };
  struct Anchor {  // last good image result, carried forward by odometry
    bool valid = false;
    double t_ms = 0.0;
    Pose2 pose;
    Pose2 odometry_at_t;  // odometry's pose at t_ms, to carry the anchor forward
    double error = kNoError;
    double sigma_cm = 0.0;  // the fix's position uncertainty (radial RMS)
    /// The anchor moved by the odometry's field-frame displacement since t_ms; the heading is the
    /// odometry's (both follow the same gyro, so the displacement needs no rotation).
    [[nodiscard]] Pose2 carried_to(const Pose2& odometry_now) const;
  };
  /// What is known of a frame before matching it.
  struct Frame {
    double t_ms = 0.0;
    const BearingScan* bearings = nullptr;
    const GoalObservation* goals = nullptr;  // null: none observed
    Pose2 odometry;                          // odometry pose at t_ms; its yaw is the gyro heading
    double speed_cm_per_s = 0.0;
    Pose2 predicted;  // the anchor carried to t_ms, else the odometry pose
    double predicted_sigma_cm = 0.0;
    FieldScan scan;  // the bearings in the field frame at the gyro heading (rotated once)
  };
  enum class CrossCheck { kNotRun, kStarted, kAgrees, kContradicts, kRelocalized };
  /// What judging a cross-check needs of the frame it checked.
  struct CheckContext {
    double t_ms = 0.0;
    Eigen::Vector2d predicted_cm{0.0, 0.0};
    double predicted_sigma_cm = 0.0;
    double local_error = kNoError;
  };
  class CheckWorker;  // localizer.cpp: one thread, one job at a time

  // --- the steps of one frame (process) ---
  FrameReport process(double t_ms, const BearingScan& bearings, const GoalObservation* goals);
  [[nodiscard]] Frame frame_at(double t_ms, const BearingScan& bearings,
                               const GoalObservation* goals) const;
  /// Searching or lost: a global search; relocalizes on a good, unambiguous result.
  void search(const Frame& frame, FrameReport& rep);
  /// Tracking: a local search around the prediction in the fuzzy range, the cross-check, then
  /// accept or reject.
  void track(const Frame& frame, FrameReport& rep);
  /// A global search compared with the tracked result: a consistent, clearly better match far
  /// from the prediction (a kidnapping) relocalizes there after disagree_frames frames. With the
  /// worker the search is only started here (kStarted) and judged by judge_started_check.
  CrossCheck cross_check(const Frame& frame, const MatchResult& local, FrameReport& rep);
  CrossCheck judge_check(const CheckContext& checked, const SingleFrameResult& global,
                         FrameReport& rep);
  /// The worker's check of an earlier frame, judged now (before the frame `rep` reports is
  /// matched).
  CrossCheck judge_started_check(FrameReport& rep);
  /// Forgets a check still running (the pose was set or the time base restarted).
  void discard_started_check();
  void accept(const Frame& frame, const MatchResult& local, FrameReport& rep);
  void reject(FrameReport& rep);
  void relocalize(double t_ms, const SingleFrameResult& global, FrameReport& rep);

  // --- matching ---
  /// locate_frame (locate.hpp) at the gyro heading (or over all headings, by policy).
  [[nodiscard]] SingleFrameResult global_match(const Frame& frame, FrameReport& rep);
  /// The heading a global search of `frame` holds fixed: none (all headings) by policy or while the
  /// heading is not known. Counts the search in the stats and in `rep` (inline or on the worker).
  [[nodiscard]] std::optional<double> begin_global_search(const Frame& frame, FrameReport& rep);
  [[nodiscard]] MatchResult local_match(const Frame& frame, double range_cm) const;
  [[nodiscard]] double search_range_cm(double speed_cm_per_s) const;
  void note_global(FrameReport& rep, const SingleFrameResult& global);
  /// Keeps an image result's error and its local search range (none: a global search) for the
  /// poses that follow.
  void note_image_result(double error, std::optional<double> range_cm);

  // --- odometry history ---
  [[nodiscard]] bool covered(double t_ms) const;
  [[nodiscard]] Pose2 odometry_pose_at(double t_ms, double* speed_cm_per_s,
                                       double* sigma_xy_cm) const;
  void reset_origin_at(double t_ms, const Pose2& pose, double sigma_xy_cm, double sigma_yaw_deg);
  void set_anchor(double t_ms, const Pose2& pose, double error, double sigma_cm);
  /// A fix's position uncertainty: the match's own (MatchResult::sigma_cm, from its error
  /// surface), else the configured image_sigma_cm.
  [[nodiscard]] double image_sigma_cm(const MatchResult& match) const;
  [[nodiscard]] double anchor_sigma_cm(const Pose2& odometry_now) const;
  [[nodiscard]] LocalizedPose make_pose(const EncoderWindow& window);
  void trim_history();
  /// The heading to reset the odometry with, from the image through the heading filter; nullopt
  /// when the scan gives no usable estimate.
  std::optional<double> corrected_yaw(double t_ms, const BearingScan& bearings,
                                      const Eigen::Vector2d& position_cm, double gyro_yaw_deg);

  LocalizerConfig config_;
  LocalizerPolicy policy_;
  RobotConfig robot_;
  const FieldGeometry& field_;
  const CameraModel& camera_;
  const FeatureDb& db_;
  MatchOptions match_options_;
  GoalColourModels goal_colours_;
  std::optional<GoalColour> side_;  ///< the defended goal's colour (set_side)
  /// set_heading_trust (gyro_yaw_known false: kNone)
  HeadingTrust trust_ = HeadingTrust::kAbsolute;
  bool heading_aligned_ = false;  ///< kRelative: a fix has aligned the gyro with the field since
  int bad_aligned_searches_ = 0;  ///< failed global searches in a row at the aligned heading
  bool kickoff_pending_ = false;  ///< set_side given and no fix since: the kick-off rule applies
  /// The candidate of an ambiguous global result that the kick-off rule picks, as an accepted
  /// result; nullopt when the rule does not apply or cannot decide.
  [[nodiscard]] std::optional<SingleFrameResult> choose_by_side(
      const SingleFrameResult& global) const;
  Odometry odometry_;
  GyroYawGuard gyro_guard_;  // every window passes it before odometry_
  LineExtractor extractor_;  ///< on_image(): this camera's line extraction (adapts frame to frame)
  std::deque<HistoryEntry> history_;
  std::deque<PendingFrame> pending_;
  std::vector<FrameReport> reports_;
  State state_ = State::kSearching;
  Anchor anchor_;
  std::optional<double> last_reset_ms_;  ///< the odometry origin's last reset (none yet)
  std::optional<double> last_check_ms_;  ///< the last cross-check (none yet)
  std::optional<double> last_error_;     ///< LocalizedPose::match_error
  std::optional<double> last_range_cm_;  ///< LocalizedPose::search_range_cm
  bool last_good_ = false;
  bool applied_this_window_ = false;
  bool trimmed_ = false;  // history has lost its first windows: older frames are dropped
  static constexpr std::size_t kMaxPending = 120;  // 2 s at 60 Hz: windows have stopped coming
  int bad_run_ = 0;
  int disagree_run_ = 0;
  Eigen::Vector2d disagree_position_cm_{0.0, 0.0};
  HeadingFilter heading_filter_;
  std::unique_ptr<CheckWorker> worker_;        ///< cross_check_worker: started on the first check
  std::optional<CheckContext> started_check_;  ///< a check running on the worker, to be judged
  LocalizedPose last_pose_;
  LocalizerStats stats_;
};

}  // namespace omniloc
