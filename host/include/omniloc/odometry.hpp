// Encoder + gyroscope odometry (paper section 2.4, equations (10)-(15)), in two variants:
//
//  * PaperOdometry: equations (10)-(15) exactly as printed, kept to show what they do. Equation
//  (13)
//    gives every wheel the same signs, so for any pure translation the four terms cancel
//    (sum of eq. (9)'s first two columns is zero) and only rotation is "seen"; equation (11) uses
//    R/2 where the arc of a wheel on radius R is R * angle. docs/ODOMETRY.md measures the result.
//  * Odometry: least squares through the pseudo-inverse of the robot's wheel Jacobian (eq. (9)
//    generalised to 3 or 4 wheels in any full-rank layout, robot_config.hpp), heading from the
//    gyroscope (wheel rotation kept as a cross-check), field-frame integration at the mid-window
//    heading, time from window timestamps, slip detection (SlipDetector: the wheels against the
//    gyro's rotation) and isolation with down-weighting, origin reset, and a per-pose uncertainty.
//    PaperOdometry accepts only the paper's symmetric four-wheel shorthand.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "omniloc/conventions.hpp"
#include "omniloc/robot_config.hpp"

namespace omniloc {

/// What the board's gyroscope measured over one window (regmap.json "frames": the window's gyro
/// fields), raw: the sum of the part's yaw-rate samples in LSB, how many, and the fault flags.
/// The scale (LSB per deg/s) and the output rate come from the part's configuration
/// (GyroScale in gyro_heading.hpp), not from here.
struct WindowGyro {
  bool present = false;       ///< false: the board has no gyro (or a board of before v0.2)
  std::int64_t sum_lsb = 0;   ///< sum of the accepted Z-rate samples (two's complement LSB)
  std::uint32_t samples = 0;  ///< samples summed
  std::uint8_t flags = 0;     ///< fault kinds seen in this window (0: none); see regmap.json
};

/// How far a window's gyro_yaw_deg can be trusted, as the heading source says (gyro_heading.hpp):
///  kAbsolute  aligned with the field from the start (the simulator's gyro; a replay of one);
///  kRelative  a working gyro, not aligned: once a fix (or the kick-off rule, or set_pose) has
///             given the field heading, the gyro keeps it and global searches may use it;
///  kNone      the wheels' own rotation (slip turns it): every global search tries every heading.
enum class HeadingTrust { kAbsolute, kRelative, kNone };
[[nodiscard]] const char* heading_trust_name(
    HeadingTrust trust);  ///< "absolute", "relative", "none"
/// The inverse of heading_trust_name; nullopt for any other text.
[[nodiscard]] std::optional<HeadingTrust> parse_heading_trust(const std::string& name);

/// One board window, as in a recording's encoders.csv row (t_ms,seq,c1,c2,c3,c4,gyro_yaw_deg).
struct EncoderWindow {
  std::uint32_t seq = 0;
  double t_end_ms = 0.0;                 ///< end of the window (board time)
  std::array<std::int32_t, 4> counts{};  ///< wheel 1..4 counts in this window (eq. (9) signs); a
                                         ///< three-wheel robot leaves counts[3] unused (ignored)
  double gyro_yaw_deg = 0.0;             ///< gyro's integrated yaw, field frame, at t_end_ms
  WindowGyro gyro;  ///< the board's raw gyro window (present only on a v0.2 board)
  HeadingTrust heading_trust = HeadingTrust::kAbsolute;  ///< how far gyro_yaw_deg can be trusted
};

/// Why check_gyro_yaw refused a window's gyro_yaw_deg.
enum class GyroYawFault {
  kNone,        ///< plausible
  kNotFinite,   ///< NaN or infinite
  kOutOfRange,  ///< beyond +-kGyroYawMaxAbsDeg: no heading source gives such an angle
  kJump,        ///< changed more than the robot can turn in the window (max_yaw_rate_deg_per_s)
};
[[nodiscard]] const char* gyro_yaw_fault_name(GyroYawFault fault);  ///< "jump", ...

/// Every heading source reports gyro_yaw_deg wrapped into (-180, 180] (gyro_heading.hpp, the
/// simulator's gyro); a value beyond +-360 cannot be one, whatever the previous window said.
inline constexpr double kGyroYawMaxAbsDeg = 360.0;

/// What check_gyro_yaw found for one window.
struct GyroYawCheck {
  GyroYawFault fault = GyroYawFault::kNone;
  double yaw_deg = 0.0;     ///< the value checked
  double change_deg = 0.0;  ///< its change from the previous good yaw (kJump), wrapped
  double bound_deg = 0.0;   ///< the largest change the window allowed (kJump)
  /// "gyro_yaw_deg 1e+06 is outside +-360 deg", "gyro_yaw_deg jumped 70.0 deg in 10.0 ms, more
  /// than the robot can turn (15.0 deg at max_yaw_rate_deg_per_s 1500)", ...
  [[nodiscard]] std::string describe() const;
};

/// The one check of a window's gyro yaw, shared by every path windows take into the odometry
/// (Localizer::on_window: replay, omnilocd, omnilocd-sim): not finite, outside
/// +-kGyroYawMaxAbsDeg, or a change from `previous_yaw_deg` (the last good one; none for the
/// first window) larger than max_yaw_rate_deg_per_s * dt_s is a fault.
[[nodiscard]] GyroYawCheck check_gyro_yaw(double yaw_deg, std::optional<double> previous_yaw_deg,
                                          double dt_s, double max_yaw_rate_deg_per_s);

/// Screens windows with check_gyro_yaw before the odometry sees them. A faulty gyro yaw is
/// dropped: the window keeps its wheel motion and takes its heading from the wheels (the last good
/// yaw plus the wheels' rotation over the window, as GyroHeading does for a flagged window), so
/// the odometry integrates it like any other. A gyro that jumps and then stays (the next window
/// agrees with the jumped value within the bound: a kidnapped simulated robot, a re-anchored
/// heading) is followed from that next window; a one-window spike never is.
class GyroYawGuard {
 public:
  explicit GyroYawGuard(const RobotConfig& robot);
  /// Checks `window` (its t_end_ms after the previous window's) and replaces a faulty
  /// gyro_yaw_deg as above; returns what the check found.
  GyroYawCheck screen(EncoderWindow& window);
  /// Windows whose gyro yaw was dropped so far.
  [[nodiscard]] std::uint64_t dropped() const { return dropped_; }

 private:
  double max_rate_deg_per_s_;
  Eigen::Matrix<double, 3, 4> pinv_;
  RobotConfig robot_;
  std::optional<double> last_good_deg_;  // the yaw passed on for the previous window
  std::optional<double> last_raw_deg_;   // the previous window's own value, if finite, in range
  double last_t_ms_ = 0.0;
  std::uint64_t dropped_ = 0;
};

/// Per-wheel slip finding for one window.
struct SlipReport {
  bool detected = false;
  int wheel = 0;              ///< 1..wheel count when detected, else 0
  double magnitude_cm = 0.0;  ///< wheel travel not explained by the robot's motion (signed)
  double magnitude_cm_per_s = 0.0;
  /// norm of the wheels' LS residual with the gyro's rotation, per second
  double residual_cm_per_s = 0.0;
  double threshold_cm_per_s = 0.0;  ///< what the residual was compared with in this window
  /// Wheel-only rotation rate (LS, no gyro) minus the gyro's yaw rate. With three wheels this is
  /// all the check has: the residual is |n . J_theta| times it (n: the normal of the translation
  /// columns).
  double wheel_minus_gyro_deg_per_s = 0.0;
};

struct OdometryEstimate {
  double t_ms = 0.0;
  Pose2 pose;
  double sigma_xy_cm = 0.0;  ///< 1-sigma position uncertainty (isotropic)
  double sigma_yaw_deg = 0.0;
  double speed_cm_per_s = 0.0;  ///< over the last window
  double yaw_rate_deg_per_s = 0.0;
  double vx_cm_per_s = 0.0;    ///< robot-frame velocity over the last window (+x forward)
  double vy_cm_per_s = 0.0;    ///< (+y to the left)
  double distance_cm = 0.0;    ///< path length since the last origin reset
  double wheel_yaw_deg = 0.0;  ///< heading integrated from the wheels alone (cross-check)
  SlipReport slip;
};

/// Least-squares estimate of one window's motion from the wheel travels (cm, slot i = wheel i+1):
/// body-frame displacement dx, dy (cm) and rotation (rad), all from the pseudo-inverse.
[[nodiscard]] Eigen::Vector3d least_squares_motion(const Eigen::Matrix<double, 3, 4>& pinv,
                                                   const Eigen::Vector4d& wheel_travel_cm);

/// The wheel Jacobian (robot_config.hpp) in the four slots of EncoderWindow::counts: a three-wheel
/// robot's fourth row is zero (that slot moves nothing and is never read).
[[nodiscard]] Eigen::Matrix<double, 4, 3> padded_wheel_jacobian(const RobotConfig& config);

/// The pseudo-inverse (J^T J)^-1 J^T of the robot's wheel Jacobian, in the four slots (a
/// three-wheel robot's fourth column is zero, so counts[3] is ignored).
[[nodiscard]] Eigen::Matrix<double, 3, 4> wheel_pseudo_inverse(const RobotConfig& config);

/// Wheel travel in cm for a window's counts (each wheel its own cm per count; 0 in unused slots).
[[nodiscard]] Eigen::Vector4d wheel_travel_cm(const RobotConfig& config,
                                              const std::array<std::int32_t, 4>& counts);

/// What the slip detector decided for one window: the report and the weight of each wheel slot
/// for the translation (1, or less for the wheel found slipping).
struct SlipCheck {
  SlipReport report;
  Eigen::Vector4d weights = Eigen::Vector4d::Ones();
};

/// The slip detector. Its inputs are the wheel travels of a window and the gyro's yaw rate: the
/// gyro fixes the rotation, the wheels' translation is fitted by least squares, and what the fit
/// cannot explain is the residual. With four wheels two equations are redundant (a 2-D residual);
/// with three wheels there is no redundancy among the wheels themselves, and the one redundant
/// equation is the gyro: the residual is the wheels' rotation against the gyro's. A window is
/// flagged when the residual exceeds max(slip_threshold_cm_per_s dt, 6 sigma of the wheel noise);
/// the wheel is then named by leaving each out in turn, with a motion prior (the last velocity,
/// good to max_accel dt^2) deciding between hypotheses the kinematics cannot tell apart (diagonal
/// wheels of the symmetric four; every wheel of a three-wheel robot). docs/ODOMETRY.md.
class SlipDetector {
 public:
  explicit SlipDetector(const RobotConfig& config);
  /// `predicted_cm`: the body-frame translation the last velocity predicts for this window.
  [[nodiscard]] SlipCheck check(const Eigen::Vector4d& travel_cm, double gyro_yaw_rate_deg_per_s,
                                double dt_s, const Eigen::Vector2d& predicted_cm) const;
  [[nodiscard]] int wheels() const { return wheels_; }

 private:
  RobotConfig config_;
  int wheels_;
  Eigen::Matrix<double, 4, 3> jacobian_;
  Eigen::Matrix<double, 3, 4> pinv_;
  double min_cm_per_count_;
};

/// Translation (cm) of one window with the rotation fixed, each wheel slot weighted by w (a zero
/// weight drops the wheel); nullopt when the weighted wheels cannot determine it.
[[nodiscard]] std::optional<Eigen::Vector2d> translation_with_rotation(
    const Eigen::Matrix<double, 4, 3>& jacobian, const Eigen::Vector4d& travel_cm,
    double rotation_rad, const Eigen::Vector4d& w);

class Odometry {
 public:
  explicit Odometry(const RobotConfig& config);

  /// Origin reset: the pose at the end of the last window processed is `pose` (the integration
  /// algorithm does this every 125 ms). The gyro heading is re-anchored so yaw follows `pose`.
  /// Before the first window the gyro is taken as aligned with the field (issue 7 contract).
  void reset(const Pose2& pose, double sigma_xy_cm = 0.0, double sigma_yaw_deg = 0.0);

  /// Integrates one window. Throws std::invalid_argument (naming seq and times) if the window's
  /// time does not advance or a value is not finite.
  const OdometryEstimate& update(const EncoderWindow& window);

  [[nodiscard]] const OdometryEstimate& estimate() const { return est_; }
  [[nodiscard]] const RobotConfig& config() const { return config_; }

 private:
  RobotConfig config_;
  Eigen::Matrix<double, 4, 3> jacobian_;
  Eigen::Matrix<double, 3, 4> pinv_;
  SlipDetector slip_;
  double mean_distance_cm_;  // mean centre-to-wheel distance, for the uncertainty
  OdometryEstimate est_;
  bool have_window_ = false;
  bool start_pose_pending_ = false;  // reset() before the first window: its yaw waits for the trust
  double last_t_ms_ = 0.0;
  double last_gyro_deg_ = 0.0;
  double yaw_offset_deg_ = 0.0;                    // pose yaw = gyro yaw + offset
  Eigen::Vector2d last_velocity_field_{0.0, 0.0};  // cm/s, for the motion prior
};

/// How eq. (14)'s theta_g is read: the printed text defines theta_g as the yaw *difference*
/// (eq. (11)), which cannot give a field-frame direction; the only workable reading uses the
/// gyro's yaw. Both are offered so the difference can be measured.
enum class PaperHeading { kGyroYaw, kGyroDifference };

class PaperOdometry {
 public:
  /// Throws std::invalid_argument for a robot that lists its wheels: equations (10)-(15) are
  /// written for the paper's symmetric four-wheel layout only.
  explicit PaperOdometry(const RobotConfig& config, PaperHeading heading = PaperHeading::kGyroYaw);
  void reset(const Pose2& pose);
  const OdometryEstimate& update(const EncoderWindow& window);
  [[nodiscard]] const OdometryEstimate& estimate() const { return est_; }

 private:
  RobotConfig config_;
  PaperHeading heading_;
  OdometryEstimate est_;
  bool have_window_ = false;
  double last_gyro_deg_ = 0.0;
  double yaw_offset_deg_ = 0.0;
};

}  // namespace omniloc
