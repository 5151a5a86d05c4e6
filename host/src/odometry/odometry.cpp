// The correct odometry variant. Derivation and the numbers behind the defaults: docs/ODOMETRY.md.
#include "omniloc/odometry.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "omniloc/regmap.hpp"

namespace omniloc {
namespace {

using Matrix43 = Eigen::Matrix<double, 4, 3>;
using Matrix42 = Eigen::Matrix<double, 4, 2>;

Eigen::Vector3d weighted_motion(const Matrix43& j, const Eigen::Vector4d& travel_cm,
                                const Eigen::Vector4d& w) {
  const Eigen::Matrix3d m = j.transpose() * w.asDiagonal() * j;
  return m.ldlt().solve(j.transpose() * w.asDiagonal() * travel_cm);
}

struct Isolation {
  int wheel = 0;  // index 0..wheels-1
  double magnitude_cm = 0.0;
};

// Which wheel? Leaving out wheel k, the others determine the translation (the rotation is the
// gyro's): with four wheels one equation is still redundant and the wheel whose removal leaves the
// smallest residual explains the disagreement; with three, two wheels fit exactly and only the
// motion prior (`predicted` body translation from the last velocity, good to about a_max dt^2)
// decides. Diagonal wheels (1,4) and (2,3) of the symmetric four leave the same residual signature,
// so there too the prior decides.
Isolation isolate_wheel(const Matrix43& j, int wheels, const Eigen::Vector4d& travel,
                        double rotation_rad, const Eigen::Vector2d& predicted, double sigma_meas,
                        double sigma_prior) {
  Isolation best;
  double best_score = std::numeric_limits<double>::infinity();
  for (int k = 0; k < wheels; ++k) {
    Eigen::Vector4d w = Eigen::Vector4d::Ones();
    w[k] = 0.0;
    const std::optional<Eigen::Vector2d> t = translation_with_rotation(j, travel, rotation_rad, w);
    if (!t) continue;  // the other wheels alone cannot see some translation: not a hypothesis
    const Eigen::Vector4d r = travel - j * Eigen::Vector3d(t->x(), t->y(), rotation_rad);
    const double others = r.squaredNorm() - r[k] * r[k];
    const double score = others / (sigma_meas * sigma_meas) +
                         (*t - predicted).squaredNorm() / (sigma_prior * sigma_prior);
    if (score < best_score) {
      best_score = score;
      best = {k, r[k]};
    }
  }
  return best;
}

void check_window(const EncoderWindow& w, const char* who) {
  if (!std::isfinite(w.t_end_ms) || !std::isfinite(w.gyro_yaw_deg)) {
    std::ostringstream os;
    os << who << ": window seq " << w.seq << " has a non-finite t_end_ms or gyro_yaw_deg";
    throw std::invalid_argument(os.str());
  }
}

// sin(x)/x: a window turning by dtheta at a steady rate moves along a chord that much shorter
// than the path the wheels measured.
double sinc(double x) {
  return std::abs(x) < 1e-6 ? 1.0 - x * x / 6.0 : std::sin(x) / x;
}

double mean_distance_cm(const RobotConfig& c) {
  if (c.wheels.empty()) return c.center_to_wheel_cm;
  double sum = 0.0;
  for (const WheelConfig& w : c.wheels) sum += w.distance_cm;
  return sum / static_cast<double>(c.wheels.size());
}

}  // namespace

std::optional<Eigen::Vector2d> translation_with_rotation(const Matrix43& j,
                                                         const Eigen::Vector4d& travel_cm,
                                                         double rotation_rad,
                                                         const Eigen::Vector4d& w) {
  const Matrix42 a = j.leftCols<2>();
  const Eigen::Vector4d y = travel_cm - j.col(2) * rotation_rad;
  const Eigen::Matrix2d m = a.transpose() * w.asDiagonal() * a;
  // The translation columns are unit drive directions, so m's entries are O(sum of weights):
  // a determinant this small means the weighted wheels all drive along one line.
  if (!(std::abs(m.determinant()) > 1e-9 * m.trace() * m.trace())) return std::nullopt;
  return Eigen::Vector2d(m.ldlt().solve(a.transpose() * w.asDiagonal() * y));
}

Matrix43 padded_wheel_jacobian(const RobotConfig& config) {
  const Eigen::Matrix<double, Eigen::Dynamic, 3> j = wheel_jacobian(config);
  if (j.rows() > 4)
    throw std::invalid_argument("padded_wheel_jacobian: " + std::to_string(j.rows()) +
                                " wheels, at most 4");
  Matrix43 out = Matrix43::Zero();
  out.topRows(j.rows()) = j;
  return out;
}

Eigen::Matrix<double, 3, 4> wheel_pseudo_inverse(const RobotConfig& config) {
  const Matrix43 j = padded_wheel_jacobian(config);
  return (j.transpose() * j).inverse() * j.transpose();
}

Eigen::Vector3d least_squares_motion(const Eigen::Matrix<double, 3, 4>& pinv,
                                     const Eigen::Vector4d& wheel_travel) {
  return pinv * wheel_travel;
}

Eigen::Vector4d wheel_travel_cm(const RobotConfig& config,
                                const std::array<std::int32_t, 4>& counts) {
  Eigen::Vector4d out = Eigen::Vector4d::Zero();
  const int n = wheel_count(config);
  for (int i = 0; i < n; ++i)
    out[i] = counts[static_cast<std::size_t>(i)] * cm_per_count(config, i);
  return out;
}

SlipDetector::SlipDetector(const RobotConfig& config)
    : config_(config),
      wheels_(wheel_count(config)),
      jacobian_(padded_wheel_jacobian(config)),
      pinv_(wheel_pseudo_inverse(config)),
      min_cm_per_count_(std::numeric_limits<double>::infinity()) {
  for (int i = 0; i < wheels_; ++i)
    min_cm_per_count_ = std::min(min_cm_per_count_, cm_per_count(config, i));
}

SlipCheck SlipDetector::check(const Eigen::Vector4d& travel, double gyro_yaw_rate_deg_per_s,
                              double dt_s, const Eigen::Vector2d& predicted_cm) const {
  SlipCheck out;
  const double rotation_rad = deg_to_rad(gyro_yaw_rate_deg_per_s) * dt_s;
  // Full column rank (validated) makes the translation columns independent: this always exists.
  const Eigen::Vector2d t =
      translation_with_rotation(jacobian_, travel, rotation_rad, Eigen::Vector4d::Ones())
          .value_or(Eigen::Vector2d::Zero());
  const Eigen::Vector4d residual = travel - jacobian_ * Eigen::Vector3d(t.x(), t.y(), rotation_rad);
  out.report.wheel_minus_gyro_deg_per_s =
      rad_to_deg((pinv_ * travel).z()) / dt_s - gyro_yaw_rate_deg_per_s;

  // The threshold: the configured rate, raised to 6 sigma of the expected random wheel noise when
  // the wheels travel fast (the residual's norm is Rayleigh-like: P(> 6 sigma) ~ 1e-8 per window).
  const double noise_cm =
      config_.wheel_noise_cm_per_sqrt_cm * std::sqrt(travel.head(wheels_).cwiseAbs().mean());
  const double thr_cm = std::max(config_.slip_threshold_cm_per_s * dt_s, 6.0 * noise_cm);
  out.report.residual_cm_per_s = residual.norm() / dt_s;
  out.report.threshold_cm_per_s = thr_cm / dt_s;
  if (!(residual.norm() > thr_cm)) return out;

  const double sigma_meas = std::max(0.25 * thr_cm, 2.0 * min_cm_per_count_);
  const double sigma_prior =
      std::max(config_.max_accel_cm_per_s2 * dt_s * dt_s, 2.0 * min_cm_per_count_);
  const Isolation iso = isolate_wheel(jacobian_, wheels_, travel, rotation_rad, predicted_cm,
                                      sigma_meas, sigma_prior);
  out.report.detected = true;
  out.report.wheel = iso.wheel + 1;
  out.report.magnitude_cm = iso.magnitude_cm;
  out.report.magnitude_cm_per_s = iso.magnitude_cm / dt_s;
  // Down-weight rather than drop: a weight that shrinks with the square of the disagreement.
  const double ratio = 0.1 * thr_cm / std::abs(iso.magnitude_cm);
  out.weights[iso.wheel] = std::min(1.0, ratio * ratio);
  return out;
}

Odometry::Odometry(const RobotConfig& config)
    : config_((validate_robot_config(config, "Odometry config"), config)),
      jacobian_(padded_wheel_jacobian(config)),
      pinv_(wheel_pseudo_inverse(config)),
      slip_(config),
      mean_distance_cm_(mean_distance_cm(config)) {}

void Odometry::reset(const Pose2& pose, double sigma_xy_cm, double sigma_yaw_deg) {
  if (!have_window_) last_gyro_deg_ = pose.yaw_deg;  // gyro aligned with the field at start-up
  yaw_offset_deg_ = angle_diff_deg(pose.yaw_deg, last_gyro_deg_);
  start_pose_pending_ = !have_window_;
  // The motion prior's velocity turns with the heading correction.
  last_velocity_field_ = robot_to_field(last_velocity_field_, yaw_difference_deg(pose, est_.pose));
  est_.pose = {pose.x_cm, pose.y_cm, wrap_deg(pose.yaw_deg)};
  est_.sigma_xy_cm = sigma_xy_cm;
  est_.sigma_yaw_deg = sigma_yaw_deg;
  est_.distance_cm = 0.0;
  est_.wheel_yaw_deg = est_.pose.yaw_deg;
}

namespace {

// The window's span: from the previous window's end (the very first window has no start time: it
// is taken to last the board's window period). A window not after the previous one is refused.
double window_span_s(const EncoderWindow& window, bool have_window, double last_t_ms,
                     double period_ms) {
  double dt_s = period_ms / 1000.0;
  if (have_window) {
    dt_s = (window.t_end_ms - last_t_ms) / 1000.0;
    if (!(dt_s > 0.0)) {
      std::ostringstream os;
      os << "Odometry: window seq " << window.seq << " ends at " << window.t_end_ms
         << " ms, not after the previous window (" << last_t_ms << " ms)";
      throw std::invalid_argument(os.str());
    }
  }
  return dt_s;
}

// Uncertainty: a fraction of the wheel travel, the heading uncertainty acting on it, and the
// whole slip magnitude (the isolation may have picked the wrong wheel of a diagonal pair).
// `turn_cm` is the wheels' rotational travel R * |dtheta|: wheel errors also displace the centre
// while turning on the spot.
void grow_uncertainty(OdometryEstimate& est, const RobotConfig& config, double dt_s, double step_cm,
                      double turn_cm, const SlipReport& slip) {
  est.sigma_yaw_deg =
      std::sqrt(est.sigma_yaw_deg * est.sigma_yaw_deg +
                config.gyro_arw_deg_per_sqrt_s * config.gyro_arw_deg_per_sqrt_s * dt_s);
  est.sigma_xy_cm += config.odometry_noise_fraction * (step_cm + turn_cm) +
                     deg_to_rad(est.sigma_yaw_deg) * step_cm +
                     (slip.detected ? std::abs(slip.magnitude_cm) : 0.0);
  est.slip = slip;
}

}  // namespace

const OdometryEstimate& Odometry::update(const EncoderWindow& window) {
  check_window(window, "Odometry");
  const double dt_s = window_span_s(window, have_window_, last_t_ms_, regmap::kWindowPeriodMs);
  if (!have_window_ && start_pose_pending_ && window.heading_trust != HeadingTrust::kAbsolute) {
    // A start pose given before the first window, and a heading that is not the field's: the
    // board's gyro (or the wheels) starts at 0 (gyro_heading.hpp), so the start yaw is the offset,
    // not the gyro's first reading.
    last_gyro_deg_ = 0.0;
    yaw_offset_deg_ = angle_diff_deg(est_.pose.yaw_deg, 0.0);
  }
  start_pose_pending_ = false;
  const Eigen::Vector4d travel = wheel_travel_cm(config_, window.counts);
  const double dyaw_deg = angle_diff_deg(window.gyro_yaw_deg, last_gyro_deg_);
  const double dyaw_rad = deg_to_rad(dyaw_deg);
  const double yaw_start_deg = last_gyro_deg_ + yaw_offset_deg_;
  const double yaw_mid_deg = yaw_start_deg + 0.5 * dyaw_deg;

  // Plain LS through the precomputed pseudo-inverse (the main path: eq. (9) generalised).
  const Eigen::Vector3d ls = least_squares_motion(pinv_, travel);
  Eigen::Vector2d body = ls.head<2>();
  double wheel_dyaw_rad = ls.z();

  // Slip: the wheels against the gyro's yaw rate over this window.
  const Eigen::Vector2d predicted = field_to_robot(last_velocity_field_ * dt_s, yaw_mid_deg);
  const SlipCheck check = slip_.check(travel, dyaw_deg / dt_s, dt_s, predicted);
  const SlipReport& slip = check.report;
  if (slip.detected) {
    body = translation_with_rotation(jacobian_, travel, dyaw_rad, check.weights).value_or(body);
    wheel_dyaw_rad = weighted_motion(jacobian_, travel, check.weights).z();
  }

  const Eigen::Vector2d delta_field = robot_to_field(body, yaw_mid_deg) * sinc(0.5 * dyaw_rad);
  const double step_cm = delta_field.norm();

  est_.t_ms = window.t_end_ms;
  est_.pose = est_.pose.shifted(delta_field).with_yaw(window.gyro_yaw_deg + yaw_offset_deg_);
  est_.speed_cm_per_s = step_cm / dt_s;
  est_.yaw_rate_deg_per_s = dyaw_deg / dt_s;
  est_.vx_cm_per_s = body.x() / dt_s;
  est_.vy_cm_per_s = body.y() / dt_s;
  est_.distance_cm += step_cm;
  est_.wheel_yaw_deg = wrap_deg(est_.wheel_yaw_deg + rad_to_deg(wheel_dyaw_rad));
  grow_uncertainty(est_, config_, dt_s, step_cm, mean_distance_cm_ * std::abs(dyaw_rad), slip);

  last_velocity_field_ = delta_field / dt_s;
  last_t_ms_ = window.t_end_ms;
  last_gyro_deg_ = window.gyro_yaw_deg;
  have_window_ = true;
  return est_;
}

}  // namespace omniloc

// --- the gyro yaw check --------------------------------------------------------------------------

namespace omniloc {

const char* gyro_yaw_fault_name(GyroYawFault fault) {
  switch (fault) {
    case GyroYawFault::kNone:
      return "none";
    case GyroYawFault::kNotFinite:
      return "not finite";
    case GyroYawFault::kOutOfRange:
      return "out of range";
    case GyroYawFault::kJump:
      return "jump";
  }
  return "?";
}

std::string GyroYawCheck::describe() const {
  std::ostringstream os;
  os.precision(6);
  os << "gyro_yaw_deg " << yaw_deg;
  switch (fault) {
    case GyroYawFault::kNone:
      os << " is plausible";
      break;
    case GyroYawFault::kNotFinite:
      os << " is not a finite number";
      break;
    case GyroYawFault::kOutOfRange:
      os << " is outside +-" << kGyroYawMaxAbsDeg << " deg (headings are wrapped into (-180, 180])";
      break;
    case GyroYawFault::kJump:
      os.precision(3);
      os << " jumped " << std::fixed << change_deg << " deg since the last window, more than the "
         << bound_deg << " deg the robot can turn in it (max_yaw_rate_deg_per_s)";
      break;
  }
  return os.str();
}

GyroYawCheck check_gyro_yaw(double yaw_deg, std::optional<double> previous_yaw_deg, double dt_s,
                            double max_yaw_rate_deg_per_s) {
  GyroYawCheck c;
  c.yaw_deg = yaw_deg;
  if (!std::isfinite(yaw_deg)) {
    c.fault = GyroYawFault::kNotFinite;
  } else if (std::abs(yaw_deg) > kGyroYawMaxAbsDeg) {
    c.fault = GyroYawFault::kOutOfRange;
  } else if (previous_yaw_deg) {
    c.change_deg = angle_diff_deg(yaw_deg, *previous_yaw_deg);
    c.bound_deg = max_yaw_rate_deg_per_s * dt_s;
    if (std::abs(c.change_deg) > c.bound_deg) c.fault = GyroYawFault::kJump;
  }
  return c;
}

GyroYawGuard::GyroYawGuard(const RobotConfig& robot)
    : max_rate_deg_per_s_(robot.max_yaw_rate_deg_per_s),
      pinv_(wheel_pseudo_inverse(robot)),
      robot_(robot) {}

GyroYawCheck GyroYawGuard::screen(EncoderWindow& window) {
  const bool first = !last_good_deg_.has_value();
  const double dt_s = first || !(window.t_end_ms > last_t_ms_)
                          ? regmap::kWindowPeriodMs / 1000.0
                          : (window.t_end_ms - last_t_ms_) / 1000.0;
  GyroYawCheck c = check_gyro_yaw(window.gyro_yaw_deg, last_good_deg_, dt_s, max_rate_deg_per_s_);
  const std::optional<double> raw_before = last_raw_deg_;
  last_raw_deg_ = c.fault == GyroYawFault::kNone || c.fault == GyroYawFault::kJump
                      ? std::optional(window.gyro_yaw_deg)
                      : std::nullopt;
  last_t_ms_ = window.t_end_ms;
  // A jump the previous window already made, and this one keeps: the gyro moved and stayed.
  if (c.fault == GyroYawFault::kJump && raw_before &&
      check_gyro_yaw(window.gyro_yaw_deg, raw_before, dt_s, max_rate_deg_per_s_).fault ==
          GyroYawFault::kNone)
    c.fault = GyroYawFault::kNone;
  if (c.fault == GyroYawFault::kNone) {
    last_good_deg_ = window.gyro_yaw_deg;
    return c;
  }
  // Dropped: the wheels' rotation over the window carries the last good heading on.
  const double wheels_deg =
      rad_to_deg(least_squares_motion(pinv_, wheel_travel_cm(robot_, window.counts)).z());
  window.gyro_yaw_deg = wrap_deg(last_good_deg_.value_or(0.0) + wheels_deg);
  last_good_deg_ = window.gyro_yaw_deg;
  ++dropped_;
  return c;
}

}  // namespace omniloc
